#!/usr/bin/env python3
"""Every repository path named in a comment or a doc exists (a ctest).

Reads the comments of C++ and Python files and every Markdown file the repository tracks (`git
ls-files`; every such file under ROOT where git is not there), generated pages committed as
snapshots included; a token that looks like a path under one of the project's folders (core/,
problems/, solvers/, harness/, ..., or a path relative to the file's own folder) must name a file
or folder that exists. Placeholders (an upper-case word such as NAME or X, `...`), generated
outputs (GENERATED) are not checked. A path into the shared folder beside the working tree
(shared/..., ../shared/...) is refused: a clone does not have it, so a reader cannot follow it.

usage: python3 tests/test_paths.py [--root DIR]
"""
import argparse
import os
import re
import subprocess
import sys

CHECKED = (".cpp", ".hpp", ".py", ".md", ".toml", ".sh", "CMakeLists.txt", "Makefile")

PATH = re.compile(r"(?<![\w./-])((?:\.\./|\./)?(?:[\w.-]+/)+[\w.-]+\.(?:hpp|cpp|py|md|toml|json|sh|txt|tsv))\b")
TOPS = {"core", "problems", "solvers", "harness", "bench", "tests", "plots", "scripts", "figures", "docs", "results",
        "fuzz", ".ci"}
# written by a command, not tracked
GENERATED = ("plots/figures/", "plots/race/", "results/perf/", "results/forms/")


def comment_lines(path, text):
    """(line number, text) of the lines a reader takes as prose: all of a Markdown file, the
    comments of C++ and Python (not #include lines), of TOML, shell, CMake and the Makefile."""
    for n, line in enumerate(text.split("\n"), 1):
        if path.endswith(".md"):
            yield n, line
        elif path.endswith((".toml", ".sh", "CMakeLists.txt", "Makefile")):
            if "#" in line:
                yield n, line[line.index("#"):]
        elif path.endswith(".py"):
            if "#" in line or '"""' in line or not line.startswith((" ", "\t")) or line.strip().startswith(("-", "usage")):
                yield n, line
        elif "//" in line:
            yield n, line[line.index("//"):]


def broken(root, path):
    rel = os.path.relpath(path, root)
    with open(path, encoding="utf-8", errors="replace") as fh:
        text = fh.read()
    out = []
    for n, line in comment_lines(path, text):
        for m in PATH.finditer(line):
            p = m.group(1)
            if p.startswith(("shared/", "../shared/")):
                out.append(f"{rel}:{n}: names {p}, outside the repository (a clone has no shared/)")
                continue
            if re.search(r"\b[A-Z]{1,}\b(?=[./])|\.\.\.|[*{<$]", p):
                continue
            if p.startswith(GENERATED):
                continue
            here = os.path.normpath(os.path.join(os.path.dirname(path), p))
            if p.split("/")[0] in TOPS:
                ok = os.path.exists(os.path.join(root, p)) or os.path.exists(here)
            elif p.startswith("."):
                ok = os.path.exists(here)
            else:
                # relative to a folder above the file (e.g. "sim/capture.cpp" inside harness/): checked
                # only where the first folder exists there, so prose like "a/b.py" is not read as a path
                parts = rel.split(os.sep)
                bases = [os.path.join(root, *parts[:k]) for k in range(len(parts))]
                first = p.split("/")[0]
                placed = [b for b in bases if os.path.isdir(os.path.join(b, first))]
                if not placed:
                    continue
                ok = any(os.path.exists(os.path.join(b, p)) for b in placed)
            if not ok:
                out.append(f"{rel}:{n}: names {p}, which does not exist")
    return out


def files(root):
    """The checked files: those git tracks (and untracked ones not ignored), else all under root."""
    try:
        out = subprocess.run(["git", "-C", root, "ls-files", "--cached", "--others", "--exclude-standard"],
                             capture_output=True, text=True, check=True).stdout.split("\n")
        listed = [os.path.join(root, f) for f in out if f.endswith(CHECKED) and not f.startswith("shared/")]
        return sorted(f for f in listed if os.path.isfile(f))
    except (OSError, subprocess.CalledProcessError):
        pass
    found = []
    for d, dirs, names in os.walk(root):
        dirs[:] = sorted(x for x in dirs if not x.startswith(".") and not x.startswith("build") and x != "shared")
        found += [os.path.join(d, f) for f in sorted(names) if f.endswith(CHECKED)]
    return found


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--root", default=os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    a = ap.parse_args()
    problems = []
    for path in files(a.root):
        problems += broken(a.root, path)
    for p in problems:
        print(p)
    print(f"paths: {len(problems)} problem(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
