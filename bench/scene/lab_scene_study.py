#!/usr/bin/env python3
"""A lab's scene, end to end on the virtual rig (docs/estimator.md, "A lab's scene, measured").

One clean calibration (a model.yaml, e.g. from `irdist calibrate recipes/table3-calibration.yaml`),
then the validation recipe once per fault of docs/virtual-rig.md ("A lab's scene"), each on a copy
of recipes/rigs/virtual.yaml with the fault's keys added. Prints, per fault, the default method's
(`i0_free` joint rows) median and max distance error, the trusted rows' max, the brackets flagged
by each cause, and the silently wrong ones (trusted, off by more than max(0.3%, 4 d_se_mm)).

  bench/scene/lab_scene_study.py --model RUN/model.yaml [--recipe recipes/validation-fig10.yaml]
      [--irdist build/app/irdist] [--out /tmp/lab-scene] [--time-scale 50] [--only NAME ...]

Run it inside a private network namespace (the virtual camera is found by GigE discovery):
  unshare -n bash -c 'ip link set lo up && bench/scene/lab_scene_study.py --model ...'
Standard library only; the rig copies are written as text (no YAML module needed).
"""
import argparse
import csv
import os
import statistics
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

# name, lines added under `virtual.sensor:`, lines added as `virtual.scene:` (docs/virtual-rig.md).
CASES = [
    ("control", [], []),
    ("defects_30", ["hot_pixels: 20", "hot_rate_e_per_s: [180000, 300000]", "stuck_pixels: 10",
                    "stuck_level_dn: [1000, 4095]", "defect_seed: 3", "defects_near_blob: 3"], []),
    ("ambient_1_3pct", [], ["ambient: {center_e_per_s: 6000, gradient_x_percent: 100}"]),
    ("reflection_25px", [], ["reflection: {plane_below_mm: 8.3, reflectance: 0.2}"]),
    ("reflection_8px", [], ["reflection: {plane_below_mm: 2.65, reflectance: 0.2}"]),
    ("cable_15pct", [], ["occluder: {covered_fraction: 0.15, edge_angle_deg: 90}"]),
    ("second_led", [], ["second_source: {position_mm: [20, 0, 2000], diameter_mm: 5, "
                        "intensity_mw_sr: 27}"]),
]


def rig_text(sensor_lines, scene_lines):
    with open(os.path.join(ROOT, "recipes", "rigs", "virtual.yaml")) as f:
        text = f.read()
    if sensor_lines:
        anchor = "\n  sensor:\n"
        assert anchor in text, "recipes/rigs/virtual.yaml has no virtual.sensor section"
        text = text.replace(anchor, anchor + "".join("    %s\n" % l for l in sensor_lines), 1)
    if scene_lines:  # virtual: is the file's last section: a new key at its indentation
        text = text.rstrip("\n") + "\n  scene:\n" + "".join("    %s\n" % l for l in scene_lines)
    return text


def recipe_text(recipe, rig_path):
    lines = []
    with open(recipe) as f:
        for line in f:
            lines.append("rig: %s\n" % rig_path if line.startswith("rig:") else line)
    return "".join(lines)


def flags_of(row):
    return {w.split("=")[0] for w in row["flags"].split()}


def figures(rows):
    err = [100.0 * abs(float(r["d_mm"]) - float(r["true_d_mm"])) / float(r["true_d_mm"])
           for r in rows if r["ok"] == "1"]
    suspect_names = {"no_blob", "saturated", "touches_border", "clipped", "second_source",
                     "occluded", "moving", "blur_larger", "blur_smaller", "outside", "disagrees",
                     "no_estimate"}
    trusted = [r for r in rows if r["ok"] == "1" and not (flags_of(r) & suspect_names)]
    trusted_err = [100.0 * abs(float(r["d_mm"]) - float(r["true_d_mm"])) / float(r["true_d_mm"])
                   for r in trusted]
    silent = 0
    for r in trusted:
        d, t = float(r["d_mm"]), float(r["true_d_mm"])
        se = float(r["d_se_mm"]) if r["d_se_mm"] else 0.0
        silent += abs(d - t) > max(0.003 * t, 4.0 * se)
    count = {}
    for r in rows:
        for name in flags_of(r):
            count[name] = count.get(name, 0) + 1
    return {
        "brackets": len(rows),
        "median": statistics.median(err) if err else float("nan"),
        "max": max(err) if err else float("nan"),
        "trusted": len(trusted),
        "trusted_max": max(trusted_err) if trusted_err else float("nan"),
        "silent": silent,
        "flags": count,
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--model", required=True)
    ap.add_argument("--recipe", default=os.path.join(ROOT, "recipes", "validation-fig10.yaml"))
    ap.add_argument("--irdist", default=os.path.join(ROOT, "build", "app", "irdist"))
    ap.add_argument("--out", default="/tmp/lab-scene")
    ap.add_argument("--time-scale", default="50")
    ap.add_argument("--only", nargs="*")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    print("| case | brackets | median | max | trusted | trusted max | silently wrong | flags |")
    print("|---|---|---|---|---|---|---|---|")
    for name, sensor, scene in CASES:
        if args.only and name not in args.only:
            continue
        rig = os.path.join(args.out, name + "-rig.yaml")
        with open(rig, "w") as f:
            f.write(rig_text(sensor, scene))
        recipe = os.path.join(args.out, name + ".yaml")
        with open(recipe, "w") as f:
            f.write(recipe_text(args.recipe, rig))
        run = os.path.join(args.out, name)
        argv = [args.irdist, "validate", recipe, "--model", args.model, "--out", run,
                "--time-scale", args.time_scale, "--quiet"]
        with open(run + ".log", "w") as log:
            code = subprocess.call(argv, stdout=log, stderr=subprocess.STDOUT)
        if code != 0:
            print("| %s | validate exited %d: see %s.log | | | | | | |" % (name, code, run))
            continue
        with open(os.path.join(run, "estimates.csv")) as f:
            rows = [r for r in csv.DictReader(f)
                    if r["method"] == "i0_free" and float(r["dt_ms"]) == 0.0]
        g = figures(rows)
        flags = ", ".join("%s %d" % kv for kv in sorted(g["flags"].items()))
        print("| %s | %d | %.3f%% | %.3f%% | %d | %.3f%% | %d | %s |" % (
            name, g["brackets"], g["median"], g["max"], g["trusted"], g["trusted_max"],
            g["silent"], flags))
        sys.stdout.flush()


if __name__ == "__main__":
    main()
