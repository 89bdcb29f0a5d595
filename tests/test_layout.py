#!/usr/bin/env python3
"""The layout rules of docs/architecture.md, checked on the source tree (a ctest):

- layers: nothing under core/ includes another project folder; nothing under problems/ includes
  solvers/ or harness/; nothing under solvers/ includes harness/ or a scene header; nothing below
  python/ (the bindings) includes it;
- harness sub-layers: perf/ → cli/ → sim/ → io/ → the parameters (harness/*.hpp): each includes
  only the sub-layers after it;
- size: no C++ source or header over 400 lines, no function body over 80 lines.

usage: python3 tests/test_layout.py [--root DIR] [--report]   (--report lists, never fails)
"""
import argparse
import os
import re
import sys

MAX_FILE_LINES = 400
MAX_FUNCTION_LINES = 80
SOURCE_DIRS = ["core", "problems", "solvers", "harness", "python", "bench", "tests"]
# folder → project folders it must not include
FORBIDDEN = {
    "core": ["problems/", "solvers/", "harness/", "python/"],
    "problems": ["solvers/", "harness/", "python/"],
    "solvers": ["harness/", "python/", "problems/scenes/", "problems/scene"],
    "harness": ["python/"],
    # harness sub-layers (perf → cli → sim → io → harness/*): none includes one before it
    "harness/io": ["harness/sim/", "harness/cli/", "harness/perf/"],
    "harness/sim": ["harness/cli/", "harness/perf/"],
    "harness/cli": ["harness/perf/"],
    "harness/": ["harness/io/", "harness/sim/", "harness/cli/", "harness/perf/"],
}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')


def sources(root):
    for top in SOURCE_DIRS:
        for d, _, files in os.walk(os.path.join(root, top)):
            for f in sorted(files):
                if f.endswith((".cpp", ".hpp")):
                    yield os.path.join(d, f)


def layer_violations(root, path):
    rel = os.path.relpath(path, root)
    parts = rel.split(os.sep)
    # a layer is a top folder, or for the harness its sub-folder ("harness/" = its own files)
    layers = [parts[0]] + (["harness/" + (parts[1] if len(parts) > 2 else "")] if parts[0] == "harness" else [])
    out = []
    with open(path, encoding="utf-8") as fh:
        for n, line in enumerate(fh, 1):
            m = INCLUDE.match(line)
            if not m:
                continue
            target = os.path.relpath(os.path.normpath(os.path.join(os.path.dirname(path), m.group(1))), root)
            if not os.path.exists(os.path.join(root, target)):
                target = m.group(1)  # included relative to the project root
            for layer in layers:
                for bad in FORBIDDEN.get(layer, []):
                    if target.replace(os.sep, "/").startswith(bad):
                        out.append(f"{rel}:{n}: includes {m.group(1)} ({layer.rstrip('/')}/ must not include {bad})")
    return out


def strip_code(text):
    """Comments, strings and character literals blanked (lines kept), so braces can be counted."""
    text = re.sub(r"//[^\n]*", "", text)
    text = re.sub(r"/\*.*?\*/", lambda m: "\n" * m.group(0).count("\n"), text, flags=re.S)
    text = re.sub(r'R"\((.*?)\)"', lambda m: "\n" * m.group(0).count("\n"), text, flags=re.S)
    text = re.sub(r'"(\\.|[^"\\\n])*"', '""', text)
    return re.sub(r"'(\\.|[^'\\\n])'", "''", text)


def long_functions(root, path):
    """Bodies of functions (a brace block opened after a ')' or a const/override/noexcept
    qualifier, outside of another function) longer than MAX_FUNCTION_LINES."""
    rel = os.path.relpath(path, root)
    with open(path, encoding="utf-8") as fh:
        lines = strip_code(fh.read()).split("\n")
    out, depth, start, fn_depth = [], 0, None, None
    for n, line in enumerate(lines, 1):
        for i, ch in enumerate(line):
            if ch == "{":
                head = (line[:i] if line[:i].strip() else (lines[n - 2] if n >= 2 else "")).rstrip()
                if fn_depth is None and re.search(r"(\)|\bconst|\boverride|\bnoexcept|\bfinal|->\s*[\w:<>]+)\s*$", head) \
                        and not re.search(r"\b(if|for|while|switch|catch)\s*\(.*\)\s*$", head):
                    fn_depth, start = depth, n
                depth += 1
            elif ch == "}":
                depth -= 1
                if fn_depth is not None and depth == fn_depth:
                    if n - start + 1 > MAX_FUNCTION_LINES:
                        out.append(f"{rel}:{start}: function of {n - start + 1} lines (limit {MAX_FUNCTION_LINES})")
                    fn_depth = None
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--root", default=os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    ap.add_argument("--report", action="store_true")
    a = ap.parse_args()
    problems = []
    for path in sources(a.root):
        with open(path, encoding="utf-8") as fh:
            n = sum(1 for _ in fh)
        if n > MAX_FILE_LINES:
            problems.append(f"{os.path.relpath(path, a.root)}: {n} lines (limit {MAX_FILE_LINES})")
        problems += layer_violations(a.root, path)
        problems += long_functions(a.root, path)
    for p in problems:
        print(p)
    print(f"layout: {len(problems)} problem(s)")
    return 0 if a.report or not problems else 1


if __name__ == "__main__":
    sys.exit(main())
