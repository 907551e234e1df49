#!/usr/bin/env python3
"""The docs' runnable examples, extracted and run (Python standard library).

A fenced code block is runnable when the line right before its opening fence is exactly
`<!-- runnable -->` (invisible on the rendered page) and its language is sh, bash or python. Such
a block needs no camera and no hardware: it runs from the repository root with the build's
irdist first on PATH (build/app) and its Python module on PYTHONPATH (build/python), sh/bash
blocks by `bash -e -u -o pipefail -c TEXT`, python blocks by `python3 -c TEXT` (argument vectors,
no shell between), each within TIMEOUT seconds. Unmarked blocks are never run.

  doc_blocks.py [--root DIR] [--build DIR] [--list] [FILE.md ...]   (default: docs/*.md, README.md)

Exit status 1 when a block fails (its file:line, status and output printed), 0 otherwise.
"""

import argparse
import glob
import os
import subprocess
import sys

MARKER = "<!-- runnable -->"
RUNNERS = {"sh": ["bash", "-e", "-u", "-o", "pipefail", "-c"],
           "bash": ["bash", "-e", "-u", "-o", "pipefail", "-c"],
           "python": [sys.executable, "-c"]}
TIMEOUT_S = 120


def runnable_blocks(path):
    """(line of the opening fence, language, text) of each marked block of a Markdown file."""
    with open(path, encoding="utf-8") as f:
        lines = f.read().split("\n")
    blocks = []
    i = 0
    while i < len(lines):
        if lines[i].strip() == MARKER and i + 1 < len(lines) and lines[i + 1].startswith("```"):
            language = lines[i + 1][3:].strip()
            if language not in RUNNERS:
                raise ValueError("%s:%d: a runnable block must be sh, bash or python, not %r" %
                                 (path, i + 2, language))
            end = i + 2
            while end < len(lines) and not lines[end].startswith("```"):
                end += 1
            if end == len(lines):
                raise ValueError("%s:%d: the runnable block has no closing fence" % (path, i + 2))
            blocks.append((i + 2, language, "\n".join(lines[i + 2:end]) + "\n"))
            i = end
        i += 1
    return blocks


def run_block(root, build, language, text):
    env = dict(os.environ)
    env["PATH"] = os.path.join(build, "app") + os.pathsep + env.get("PATH", "")
    python_path = os.path.join(build, "python")
    env["PYTHONPATH"] = python_path + (os.pathsep + env["PYTHONPATH"]
                                       if env.get("PYTHONPATH") else "")
    try:
        done = subprocess.run(RUNNERS[language] + [text], cwd=root, env=env, timeout=TIMEOUT_S,
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        return done.returncode, done.stdout
    except subprocess.TimeoutExpired as e:
        return "timeout after %d s" % TIMEOUT_S, e.stdout or ""


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--root", default=os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    parser.add_argument("--build", help="the build folder (default: ROOT/build)")
    parser.add_argument("--list", action="store_true", help="list the runnable blocks, run none")
    parser.add_argument("files", nargs="*")
    args = parser.parse_args(argv)
    build = os.path.abspath(args.build or os.path.join(args.root, "build"))
    files = args.files or sorted(glob.glob(os.path.join(args.root, "docs", "*.md"))) + \
        [os.path.join(args.root, "README.md")]
    failed = ran = 0
    for path in files:
        if not os.path.isfile(path):
            continue
        try:
            blocks = runnable_blocks(path)
        except ValueError as error:
            print(error)
            failed += 1
            continue
        for line, language, text in blocks:
            where = "%s:%d" % (os.path.relpath(path, args.root), line)
            if args.list:
                print("%s: %s" % (where, language))
                continue
            status, output = run_block(args.root, build, language, text)
            ran += 1
            if status != 0:
                failed += 1
                print("%s: the %s block failed (%s); fix the example or the code:\n%s" %
                      (where, language, status, output))
    if not args.list:
        print("doc blocks: %d run, %d failed" % (ran, failed))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
