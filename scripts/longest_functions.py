#!/usr/bin/env python3
"""Prints the longest C++ functions of the source modules and the include cycles.

A report, not a gate: it always exits 0 (CI prints it). Usage:
  scripts/longest_functions.py [--root DIR] [--top N] [--limit LINES] [MODULE ...]
MODULEs default to acquisition station estimator sim app base. A function's length is counted
from the first line of its signature to its closing brace, inclusive. Two kinds of cycle are
listed: between headers (x.h includes y.h includes x.h), and between units, where a unit is a
header with its .cc (x.cc includes y.h while y.cc includes x.h: each half of the code needs the
other, even when no header includes a header back).
"""
import argparse
import os
import re
import sys

MODULES = ["acquisition", "station", "estimator", "sim", "app", "base"]
NOT_FUNCTIONS = re.compile(
    r"^\s*(namespace|class|struct|union|enum|extern\s+\"C\"\s*$|if|else|for|while|switch|do|try|"
    r"catch)\b")
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')


def strip_code(text):
    """The text with comments, string and char literals blanked (newlines kept)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == 'R' and text.startswith('R"', i):
            m = re.match(r'R"([^(]*)\(', text[i:])
            end = text.find(")" + m.group(1) + '"', i) if m else -1
            j = n if end < 0 else end + len(m.group(1)) + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            out.append(c + " " * (min(j, n) - i - 1) + (c if j < n else ""))
            i = j + 1
        elif c == "#" and (i == 0 or text[i - 1] == "\n"):  # preprocessor line
            j = text.find("\n", i)
            while j > 0 and text[j - 1] == "\\":
                j = text.find("\n", j + 1)
            j = n if j < 0 else j
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


def function_name(header):
    depth = 0
    for k, c in enumerate(header):
        if c == "(" and depth == 0:
            m = re.search(r"([~A-Za-z_][\w:~<>,\s]*?)\s*$", header[:k])
            if m:
                name = m.group(1).split()[-1] if m.group(1).split() else "?"
                return name
            return "?"
        depth += c == "<"
        depth -= c == ">"
    return None


def functions(path):
    """(name, first_line, length) of every function body defined in the file."""
    code = strip_code(open(path, encoding="utf-8", errors="replace").read())
    found = []
    stack = []  # per open brace: "function" or "other"
    header_start = 0
    inside = 0  # depth of the outermost function, 0 when outside
    line = 1
    start_line = 0
    for i, c in enumerate(code):
        if c == "\n":
            line += 1
        elif c == "{":
            header = code[header_start:i]
            is_function = (not inside and ")" in header and not NOT_FUNCTIONS.match(header)
                           and not header.rstrip().endswith("=") and function_name(header))
            if is_function:
                inside = len(stack) + 1
                first = header_start + len(header) - len(header.lstrip())
                start_line = code.count("\n", 0, first) + 1
                name = function_name(header)
            stack.append("function" if is_function else "other")
            header_start = i + 1
        elif c == "}":
            if stack:
                stack.pop()
            if inside and len(stack) < inside:
                found.append((name, start_line, line - start_line + 1))
                inside = 0
            header_start = i + 1
        elif c == ";" and not inside:
            header_start = i + 1
    return found


def source_files(dirs):
    for d in dirs:
        for root, _, files in os.walk(d):
            for f in sorted(files):
                if f.endswith((".cc", ".h", ".cpp", ".hpp")):
                    yield os.path.join(root, f)


def include_graph(dirs, unit):
    """Edges from each header (or, with unit, each x.h + x.cc) to the project headers it includes."""
    graph = {}
    for path in source_files(dirs):
        if not unit and not path.endswith(".h"):
            continue
        key = os.path.splitext(os.path.normpath(path))[0] if unit else os.path.normpath(path)
        edges = graph.setdefault(key, [])
        for text in open(path, encoding="utf-8", errors="replace"):
            m = INCLUDE.match(text)
            if not m or not m.group(1).endswith(".h") or not os.path.exists(m.group(1)):
                continue
            target = os.path.normpath(m.group(1))
            target = os.path.splitext(target)[0] if unit else target
            if target != key and target not in edges:
                edges.append(target)
    return graph


def cycles(graph):
    """Strongly connected components with more than one node (Tarjan)."""
    index, low, on_stack, stack, sccs = {}, {}, set(), [], []
    counter = [0]

    def visit(v):  # recursive: the graphs are small
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, []):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            scc = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                scc.append(w)
                if w == v:
                    break
            if len(scc) > 1:
                sccs.append(sorted(scc))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sccs


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dirs", nargs="*", default=None)
    parser.add_argument("--root", help="the source tree (default: this script's repository)")
    parser.add_argument("--top", type=int, default=20)
    parser.add_argument("--limit", type=int, default=80, help="the house's hard limit (lines)")
    args = parser.parse_args()
    os.chdir(args.root or os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    dirs = args.dirs or [m for m in MODULES if os.path.isdir(m)]
    all_functions = []
    for path in source_files(dirs):
        all_functions += [(length, path, first, name) for name, first, length in functions(path)]
    all_functions.sort(key=lambda f: (-f[0], f[1], f[2]))
    over = [f for f in all_functions if f[0] > args.limit]
    over60 = [f for f in all_functions if f[0] > 60]
    print(f"Longest functions in {' '.join(dirs)} ({len(all_functions)} functions; "
          f"{len(over)} over {args.limit} lines, {len(over60)} over 60):")
    for length, path, first, name in all_functions[:args.top]:
        mark = "  OVER" if length > args.limit else ""
        print(f"  {length:4d}  {path}:{first}  {name}{mark}")
    for unit, what in ((False, "headers"), (True, "units (x.h + x.cc)")):
        found = cycles(include_graph(dirs, unit))
        print(f"Include cycles between {what}: {len(found) if found else 'none'}")
        for scc in found:
            print("  " + " <-> ".join(scc))
    return 0


if __name__ == "__main__":
    sys.exit(main())
