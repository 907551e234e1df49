#!/usr/bin/env python3
"""The house rules the build cannot see, checked from the source tree (Python standard library).

  layers   no file includes upward: base/ only itself; acquisition/, station/, estimator/ and sim/
           only base/ and themselves; an app/ folder only the modules and the app/ folders below it,
           as app/CMakeLists.txt's irdist_app_folder(... BELOW ...) declares them (the same lists
           the build links); every app/ source in its folder's library.
  docs     every file and function docs/architecture.md names exists.
  tests    (a report, never fails) the product .cc files with no test file of their own.

Exit status 1 when a checked rule is broken (each finding printed as file:line: what and the fix),
0 otherwise. `house_check.py` runs layers and docs and prints the tests report; CTest runs each
check (house/layers, house/docs), CI's house stage the whole.
"""

import argparse
import os
import re
import sys

MODULES = ("base", "acquisition", "station", "estimator", "sim")
# What each module below app/ may include besides itself.
MODULE_MAY_INCLUDE = {"base": set(), "acquisition": {"base"}, "station": {"base"},
                      "estimator": {"base"}, "sim": {"base"}}
SOURCE_EXTENSIONS = (".h", ".cc")
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')
FOLDER_CALL = re.compile(r"irdist_app_folder\(\s*(\w+)(.*?)\)", re.S)


def source_files(root, top):
    """Every .h and .cc file under root/top, as paths relative to root, sorted."""
    found = []
    for folder, _, files in os.walk(os.path.join(root, top)):
        for name in files:
            if name.endswith(SOURCE_EXTENSIONS):
                found.append(os.path.relpath(os.path.join(folder, name), root))
    return sorted(found)


def parse_app_folders(root):
    """app/CMakeLists.txt's folders: {folder: {"below": [...], "sources": [...], "line": n}}."""
    path = os.path.join(root, "app", "CMakeLists.txt")
    with open(path, encoding="utf-8") as f:
        text = f.read()
    text = re.sub(r"#[^\n]*", lambda m: " " * len(m.group(0)), text)
    folders = {}
    for match in FOLDER_CALL.finditer(text):
        lists, key = {"SOURCES": [], "BELOW": []}, None
        for word in match.group(2).split():
            if word in ("SOURCES", "BELOW", "PUBLIC_DEPS", "PRIVATE_DEPS"):
                key = word
            elif key in lists:
                lists[key].append(word)
        line = text.count("\n", 0, match.start()) + 1
        folders[match.group(1)] = {"below": lists["BELOW"], "sources": lists["SOURCES"],
                                   "line": line}
    return folders


def below_closure(folders):
    """Each folder's floors below it, following BELOW transitively; a cycle is an error."""
    closure, findings = {}, []

    def visit(name, trail):
        if name in closure:
            return closure[name]
        if name in trail:
            findings.append("app/CMakeLists.txt:%d: the folders' BELOW lists form a cycle (%s): "
                            "a folder links only floors below it" %
                            (folders[name]["line"], " -> ".join(trail + [name])))
            return set()
        result = set()
        for lower in folders[name]["below"]:
            if lower not in folders:
                findings.append("app/CMakeLists.txt:%d: %s lists BELOW %s, which is no app/ "
                                "folder library" % (folders[name]["line"], name, lower))
                continue
            result |= {lower} | visit(lower, trail + [name])
        closure[name] = result
        return result

    for name in folders:
        visit(name, [])
    return closure, findings


def allowed_includes(path, closure):
    """The top folders (and app/ folders) a file may include, or None when any is allowed."""
    parts = path.split(os.sep)
    if parts[0] in MODULES:
        return {parts[0]} | MODULE_MAY_INCLUDE[parts[0]], set()
    if parts[0] == "app" and len(parts) > 2:
        return set(MODULES), {parts[1]} | closure.get(parts[1], set())
    return None


def check_includes(root, path, closure):
    allowed = allowed_includes(path, closure)
    if allowed is None:
        return []
    modules, app_folders = allowed
    findings = []
    with open(os.path.join(root, path), encoding="utf-8", errors="replace") as f:
        for number, line in enumerate(f, 1):
            match = INCLUDE.match(line)
            if not match:
                continue
            target = match.group(1).split("/")
            if target[0] == "app" and len(target) > 2:
                if target[1] not in app_folders:
                    findings.append(
                        "%s:%d: includes %s, but app/%s is not below app/%s (app/CMakeLists.txt "
                        "BELOW): move the piece it needs down, or the including code up" %
                        (path, number, match.group(1), target[1], path.split(os.sep)[1]))
            elif target[0] in MODULES + ("app", "python", "tests", "bench", "fuzz"):
                if target[0] not in modules:
                    findings.append(
                        "%s:%d: includes %s: %s/ may include only %s (docs/architecture.md, "
                        "Folders)" % (path, number, match.group(1), path.split(os.sep)[0],
                                      ", ".join(sorted(m + "/" for m in modules))))
    return findings


def check_layers(root):
    """Findings of the layers check (empty when the house holds)."""
    folders = parse_app_folders(root)
    if not folders:
        return ["app/CMakeLists.txt: no irdist_app_folder(...) found: one library per app/ folder"]
    closure, findings = below_closure(folders)
    app_dir = os.path.join(root, "app")
    for name in sorted(os.listdir(app_dir)):
        if os.path.isdir(os.path.join(app_dir, name)) and name not in folders:
            findings.append("app/%s/: no library of its own: add irdist_app_folder(%s ...) to "
                            "app/CMakeLists.txt" % (name, name))
    for name, folder in folders.items():
        for source in folder["sources"]:
            if not os.path.isfile(os.path.join(app_dir, name, source)):
                findings.append("app/CMakeLists.txt:%d: %s lists %s, which app/%s/ does not have"
                                % (folder["line"], name, source, name))
    for path in [p for top in MODULES + ("app",) for p in source_files(root, top)]:
        findings += check_includes(root, path, closure)
        parts = path.split(os.sep)
        if (parts[0] == "app" and len(parts) == 3 and path.endswith(".cc") and
                parts[1] in folders and parts[2] not in folders[parts[1]]["sources"] and
                parts[2] != "main.cc"):
            findings.append("%s: in no library: add it to irdist_app_folder(%s SOURCES ...) in "
                            "app/CMakeLists.txt" % (path, parts[1]))
    return findings


SPAN = re.compile(r"`([^`\n]+)`")
CALL = re.compile(r"^([A-Za-z_][\w:]*)\(.*\)$")
NAME = re.compile(r"^[A-Za-z_]\w*(::\w+)*$")
PATH_LIKE = re.compile(r"(/|\.(h|cc|py|md|cmake|in|json)$|\.\{)")
SKIP_TREES = {".git", "build", "build-asan", "build-fuzz"}
# Convention words the architecture names as examples, not as code.
NOT_CODE = {"PascalCase"}


def expand_braces(token):
    """cli.{h,cc} -> [cli.h, cli.cc]."""
    match = re.search(r"\{([^}]*)\}", token)
    if not match:
        return [token]
    return [token[:match.start()] + part + token[match.end():]
            for part in match.group(1).split(",")]


def repository_index(root):
    """(every file's relative path, every folder's relative path, the words of the code)."""
    files, folders, words = set(), set(), set()
    for folder, subfolders, names in os.walk(root):
        subfolders[:] = [d for d in subfolders
                         if not (folder == root and (d in SKIP_TREES or d.startswith("build")))]
        relative = os.path.relpath(folder, root)
        folders.add(relative)
        for name in names:
            path = os.path.normpath(os.path.join(relative, name))
            files.add(path)
            if name.endswith(SOURCE_EXTENSIONS + (".py",)) and path.split(os.sep)[0] != "tests":
                with open(os.path.join(root, path), encoding="utf-8", errors="replace") as f:
                    code = re.sub(r"//[^\n]*", "", f.read())
                words.update(re.findall(r"\w+", code))
    return files, folders, words


def path_exists(token, files, folders):
    """A path from docs/architecture.md: rooted at the repository or docs/; a bare file name
    anywhere in the tree; a folder name at the root, in docs/ or one level down."""
    if token.endswith("/"):
        name = token.rstrip("/")
        return (name in folders or os.path.join("docs", name) in folders or
                any(f.endswith(os.sep + name) and f.count(os.sep) == 1 for f in folders))
    if "/" in token:
        return os.path.normpath(token) in files or os.path.join("docs", token) in files
    return any(os.path.basename(f) == token for f in files)


def check_app_table(text, root):
    """The app/ section's table: each folder row names the files its folder has, and only those."""
    findings = []
    for number, line in enumerate(text.split("\n"), 1):
        row = re.match(r"^\|\s*`(\w+)/`\s*\|([^|]*)\|", line)
        folder = row and os.path.join(root, "app", row.group(1))
        if not row or not os.path.isdir(folder):
            continue
        named = set()
        for span in SPAN.findall(row.group(2)):
            for name in expand_braces(span):
                named.add(name.split(".")[0])
                candidates = [name] if "." in name else [name + ".h", name + ".cc"]
                if not any(os.path.isfile(os.path.join(folder, c)) for c in candidates):
                    findings.append("docs/architecture.md:%d: app/%s/ has no %s: name the "
                                    "folder's files as they are" % (number, row.group(1), name))
        for stem in sorted({n.split(".")[0] for n in os.listdir(folder)
                            if n.endswith(SOURCE_EXTENSIONS)} - named):
            findings.append("docs/architecture.md:%d: app/%s/%s is not in the table: add it with "
                            "its role" % (number, row.group(1), stem))
    return findings


def check_span(span, files, folders, words):
    """None when the span names nothing to check or names what exists, else what is missing."""
    call = CALL.match(span)
    if call:
        span = call.group(1)
    if re.search(r"[\s<*|]", span) or span.startswith(("-", ".", "_")):
        return None
    if PATH_LIKE.search(span):
        if any(re.fullmatch(r"[A-Z]+", part) for part in span.split("/")):
            return None  # a placeholder (fuzz/corpus/TARGET)
        missing = [p for p in expand_braces(span) if not path_exists(p, files, folders)]
        return "no file or folder %s" % ", ".join(missing) if missing else None
    if not NAME.match(span) or span in NOT_CODE:
        return None
    parts = span.split("::")
    if "::" not in span and not (re.match(r"[A-Z][a-z]", span) or span.startswith("IRDIST_")):
        return None
    missing = [p for p in parts if p not in words]
    return "no %s in the code" % span if missing else None


def check_docs(root):
    """Findings of the docs check: what docs/architecture.md names and the code does not have."""
    path = os.path.join(root, "docs", "architecture.md")
    with open(path, encoding="utf-8") as f:
        text = f.read()
    files, folders, words = repository_index(root)
    findings = check_app_table(text, root)
    for number, line in enumerate(text.split("\n"), 1):
        for span in SPAN.findall(line):
            problem = check_span(span, files, folders, words)
            if problem:
                findings.append("docs/architecture.md:%d: `%s` names %s: say what the code has" %
                                (number, span, problem))
    return findings


def check_tests(root):
    """The product .cc files with no tests/<module>/<file>_test.cc (app/: tests/app/<folder>/)."""
    findings = []
    for path in [p for top in MODULES + ("app",) for p in source_files(root, top)]:
        if not path.endswith(".cc") or os.path.basename(path) == "main.cc":
            continue
        test = os.path.join("tests", path[:-len(".cc")] + "_test.cc")
        if not os.path.isfile(os.path.join(root, test)):
            findings.append("%s: no test file of its own (%s)" % (path, test))
    return findings


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("checks", nargs="*", metavar="CHECK",
                        help="layers, docs or tests (default: all three)")
    parser.add_argument("--root", default=os.path.join(os.path.dirname(__file__), ".."),
                        help="the repository (default: this script's parent folder)")
    args = parser.parse_args(argv)
    root = os.path.abspath(args.root)
    checks = args.checks or ["layers", "docs", "tests"]
    unknown = [c for c in checks if c not in CHECKS]
    if unknown:
        parser.error("unknown check %s: choose from %s" % (", ".join(unknown), ", ".join(CHECKS)))
    failed = False
    for check in checks:
        findings = CHECKS[check](root)
        for finding in findings:
            print(finding)
        if check == "tests":
            print("house tests: %d product source files without a test file of their own "
                  "(a report)" % len(findings))
            continue
        print("house %s: %s" % (check, "%d findings" % len(findings) if findings else "ok"))
        failed = failed or bool(findings)
    return 1 if failed else 0


CHECKS = {"layers": check_layers, "docs": check_docs, "tests": check_tests}

if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
