#!/usr/bin/env python3
"""scripts/doc_blocks.py on made-up docs: a marked block runs, an unmarked one never does, a
failing one is reported with its file and line, a marked block of another language is refused."""

import os
import subprocess
import sys
import tempfile

SCRIPT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts",
                      "doc_blocks.py")


def run(root, *files):
    done = subprocess.run([sys.executable, SCRIPT, "--root", root] + list(files),
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    return done.returncode, done.stdout


def main():
    failures = []
    with tempfile.TemporaryDirectory() as root:
        os.mkdir(os.path.join(root, "docs"))
        good = os.path.join(root, "docs", "good.md")
        with open(good, "w") as f:
            f.write("# Good\n\n<!-- runnable -->\n```sh\ntouch ran-sh\n```\n\n"
                    "```sh\ntouch never\n```\n\n<!-- runnable -->\n```python\n"
                    "open('ran-py', 'w').close()\n```\n")
        status, out = run(root, good)
        if status != 0 or "2 run, 0 failed" not in out:
            failures.append("good.md: %s %s" % (status, out))
        for name, expected in (("ran-sh", True), ("ran-py", True), ("never", False)):
            if os.path.exists(os.path.join(root, name)) != expected:
                failures.append("%s exists: %s" % (name, not expected))
        bad = os.path.join(root, "docs", "bad.md")
        with open(bad, "w") as f:
            f.write("text\n<!-- runnable -->\n```bash\necho before\nfalse\necho after\n```\n")
        status, out = run(root, bad)
        if status != 1 or "docs/bad.md:3: the bash block failed (1)" not in out or \
                "after" in out:
            failures.append("bad.md: %s %s" % (status, out))
        other = os.path.join(root, "docs", "other.md")
        with open(other, "w") as f:
            f.write("<!-- runnable -->\n```console\n$ ls\n```\n")
        status, out = run(root, other)
        if status != 1 or "must be sh, bash or python" not in out:
            failures.append("other.md: %s %s" % (status, out))
    for failure in failures:
        print("FAIL:", failure)
    print("doc_blocks_test: %d failure(s)" % len(failures))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
