#!/usr/bin/env python3
"""Soak bench: `irdist measure` for many brackets beside an `irdist sim`, sampling both processes.

Starts `irdist sim` (the virtual rig, time scale 10 by default), places the IRED with
`irdist station` (home, move 2000 10 0, current 500), then runs
`irdist measure --json --count N --out DIR` on the sim's camera and reads its JSON lines. At the
first bracket and every --every brackets it samples, for measure and for the sim: RSS (VmRSS of
/proc/PID/status), threads (Threads:) and open files (entries of /proc/PID/fd). At the end it
prints the table and, for each process, the least-squares slope of RSS per 1,000 brackets over the
samples from the first --every on, RSS at the end minus RSS after the first --every brackets
(goal: within 2 MB), and whether threads and files stayed constant. The figures also go to
WORK/soak.json.

Run it inside a private network namespace (the virtual rig's camera is on 127.0.0.1):

    unshare -n bash -c 'ip link set lo up && bench/soak/soak.py --irdist build/app/irdist'

    --irdist BIN      the irdist binary under test (e.g. an older build, for a before/after)
    --brackets N      brackets to measure (10000: about 20 minutes at time scale 10)
    --every K         sample every K brackets (1000)
    --model FILE      a model.yaml; without it recipes/smoke-calibration.yaml (3 distances x
                      4 angles x 2 currents, at time scale 50) makes one first
    --work DIR        scratch folder (default /tmp/irdist-soak-<pid>); the sim's state file goes
                      to DIR/run (XDG_RUNTIME_DIR), so soaks in other namespaces do not meet

Not run by CTest: a long run is the unit.
"""

import argparse
import json
import os
import pathlib
import signal
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
RIG = ROOT / "recipes" / "rigs" / "virtual.yaml"

CALIBRATION = ROOT / "recipes" / "smoke-calibration.yaml"  # 24 poses, about a minute at x50


def sample(pid):
    """RSS (kB), threads and open files of a live process."""
    status = pathlib.Path(f"/proc/{pid}/status").read_text()
    fields = dict(line.split(":", 1) for line in status.splitlines() if ":" in line)
    rss_kb = int(fields["VmRSS"].split()[0])
    threads = int(fields["Threads"])
    files = len(os.listdir(f"/proc/{pid}/fd"))
    return {"rss_kb": rss_kb, "threads": threads, "files": files}


def run(binary, args, env, log):
    """Runs irdist (in the source tree, where rig names resolve) to completion, or fails."""
    with open(log, "w") as out:
        code = subprocess.call([binary] + args, stdout=out, stderr=subprocess.STDOUT, env=env,
                               cwd=ROOT)
    if code != 0:
        raise SystemExit(f"irdist {' '.join(args)} exited {code}:\n{pathlib.Path(log).read_text()}")


def start_sim(binary, time_scale, env, work):
    log = open(work / "sim.log", "w")
    sim = subprocess.Popen([binary, "sim", "--rig", str(RIG), "--time-scale", str(time_scale)],
                           stdout=log, stderr=subprocess.STDOUT, env=env)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        if "Running until" in (work / "sim.log").read_text():
            return sim
        if sim.poll() is not None:
            break
        time.sleep(0.1)
    sim.kill()
    raise SystemExit("irdist sim did not start:\n" + (work / "sim.log").read_text())


def slope_per_1000(points):
    """Least-squares slope of (bracket, value) points, per 1,000 brackets."""
    n = len(points)
    if n < 2:
        return float("nan")
    mx = sum(p[0] for p in points) / n
    my = sum(p[1] for p in points) / n
    sxx = sum((p[0] - mx) ** 2 for p in points)
    sxy = sum((p[0] - mx) * (p[1] - my) for p in points)
    return 1000.0 * sxy / sxx


def figures(samples, key, every):
    after = [(s["bracket"], s[key]["rss_kb"]) for s in samples if s["bracket"] >= every]
    first_after = after[0][1] if after else float("nan")
    return {
        "rss_slope_kb_per_1000": slope_per_1000(after),
        "rss_end_minus_after_first_kb": after[-1][1] - first_after if after else float("nan"),
        "threads": sorted({s[key]["threads"] for s in samples}),
        "files": sorted({s[key]["files"] for s in samples}),
    }


def measure(args, env, work, model, sim):
    command = [args.irdist, "measure", "--model", model, "--rig", str(RIG), "--json",
               "--count", str(args.brackets), "--out", str(work / "measure-out")]
    err = open(work / "measure.log", "w")
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=err, env=env, text=True)
    samples, count, t0 = [], 0, time.monotonic()
    for line in proc.stdout:
        if not line.startswith("{"):
            continue
        count += 1
        if count == 1 or count % args.every == 0:
            s = {"bracket": count, "wall_s": round(time.monotonic() - t0, 1),
                 "measure": sample(proc.pid), "sim": sample(sim.pid)}
            samples.append(s)
            print(json.dumps(s), flush=True)
    code = proc.wait()
    if code != 0:
        raise SystemExit(f"measure exited {code}:\n" + (work / "measure.log").read_text())
    return samples


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--irdist", default=str(ROOT / "build" / "app" / "irdist"))
    parser.add_argument("--brackets", type=int, default=10000)
    parser.add_argument("--every", type=int, default=1000)
    parser.add_argument("--time-scale", type=float, default=10.0)
    parser.add_argument("--model")
    parser.add_argument("--work", default=f"/tmp/irdist-soak-{os.getpid()}")
    args = parser.parse_args()
    work = pathlib.Path(args.work)
    (work / "run").mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, XDG_RUNTIME_DIR=str(work / "run"))
    model = args.model
    if not model:
        run(args.irdist, ["calibrate", str(CALIBRATION), "--out", str(work / "cal"),
                          "--time-scale", "50", "--quiet"], env, work / "calibrate.log")
        model = str(work / "cal" / "model.yaml")
    sim = start_sim(args.irdist, args.time_scale, env, work)
    try:
        for step in (["home"], ["move", "2000", "10", "0"], ["current", "500"]):
            run(args.irdist, ["station", "--rig", str(RIG)] + step, env, work / "station.log")
        samples = measure(args, env, work, model, sim)
    finally:
        sim.send_signal(signal.SIGINT)
        sim.wait(timeout=60)
    result = {"irdist": args.irdist, "brackets": args.brackets, "time_scale": args.time_scale,
              "samples": samples, "measure": figures(samples, "measure", args.every),
              "sim": figures(samples, "sim", args.every)}
    (work / "soak.json").write_text(json.dumps(result, indent=1))
    for key in ("measure", "sim"):
        print(f"{key}: {json.dumps(result[key])}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
