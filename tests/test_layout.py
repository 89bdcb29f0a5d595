#!/usr/bin/env python3
"""The layout rules of docs/architecture.md, checked on the source tree (a ctest):

- layers: nothing under core/ includes another project folder; nothing under problems/ includes
  solvers/ or harness/; nothing under solvers/ includes harness/ or a scene header; nothing below
  python/ (the bindings) includes it;
- harness sub-layers: perf/ → cli/ → sim/ → io/ → the parameters (harness/*.hpp): each includes
  only the sub-layers after it;
- size: no C++ source or header and no Python file over 400 lines, no C++ function body over 80 lines;
- no include loops: a unit (NAME.hpp with NAME.cpp) never reaches itself through the includes;
- tests mirror the source: every .cpp under a folder of MIRRORED has tests/<folder>/test_<name>.cpp;
- determinism: no OpenMP reduction(+ : …) (or − or *) over a double or a float outside tests/: its
  rounding depends on the thread count (sums go through core/reduce.hpp, docs/determinism.md);
- no tracker numbers in code (an issue's or a pull request's number, "#" and digits): a reader of the code has no tracker, so
  a comment says why, not which ticket. Markdown is not checked (docs may cite the history).

usage: python3 tests/test_layout.py [--root DIR] [--report]   (--report lists, never fails)
"""
import argparse
import os
import re
import subprocess
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
# folders (with their sub-folders) whose every source has a test of its name at the mirror path
MIRRORED = ["solvers/amg"]
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')


def sources(root):
    for top in SOURCE_DIRS:
        for d, _, files in os.walk(os.path.join(root, top)):
            for f in sorted(files):
                if f.endswith((".cpp", ".hpp")):
                    yield os.path.join(d, f)


def python_files(root):
    for d, dirs, files in os.walk(root):
        dirs[:] = [x for x in dirs if not x.startswith(".") and x != "build" and not x.startswith("build-")]
        for f in sorted(files):
            if f.endswith(".py"):
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


def include_loops(root, paths):
    """Units (a path without .hpp/.cpp) whose includes lead back to themselves, one line per loop."""
    graph = {}
    for path in paths:
        unit = os.path.splitext(os.path.relpath(path, root))[0]
        with open(path, encoding="utf-8") as fh:
            for line in fh:
                m = INCLUDE.match(line)
                if not m:
                    continue
                target = os.path.normpath(os.path.join(os.path.dirname(path), m.group(1)))
                if not os.path.exists(target):
                    target = os.path.join(root, m.group(1))
                other = os.path.splitext(os.path.relpath(target, root))[0]
                if other != unit:
                    graph.setdefault(unit, set()).add(other)
    # strongly connected components (Tarjan, iterative)
    index, low, on_stack, stack, loops, counter = {}, {}, set(), [], [], [0]
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted(graph.get(start, ()))))]
        index[start] = low[start] = counter[0]
        counter[0] += 1
        stack.append(start)
        on_stack.add(start)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = counter[0]
                    counter[0] += 1
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(graph.get(w, ())))))
                elif w in on_stack:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    on_stack.discard(w)
                    comp.append(w)
                    if w == v:
                        break
                if len(comp) > 1:
                    loops.append("include loop: " + " <-> ".join(sorted(comp)))
    return loops


def missing_tests(root):
    out = []
    for folder in MIRRORED:
        for d, _, files in os.walk(os.path.join(root, folder)):
            for f in sorted(files):
                if f.endswith(".cpp"):
                    rel = os.path.relpath(os.path.join(d, f), root)
                    test = os.path.join("tests", os.path.dirname(rel), "test_" + f)
                    if not os.path.exists(os.path.join(root, test)):
                        out.append(f"{rel}: no test of its name ({test})")
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


FP_REDUCTION = re.compile(r"#\s*pragma\s+omp\s+(?!simd)[^\n]*\breduction\s*\(\s*[-+*]\s*:\s*([\w\s,]+)\)")


def float_reductions(root, path):
    """OpenMP +, − or * reductions whose variable is declared double or float in the 20 lines above."""
    with open(path, encoding="utf-8") as fh:
        lines = fh.read().split("\n")
    found = []
    for i, line in enumerate(lines):
        m = FP_REDUCTION.search(line)
        if not m:
            continue
        for var in (v.strip() for v in m.group(1).split(",")):
            decl = re.compile(rf"\b(?:double|float)\b[^;()]*\b{re.escape(var)}\b")
            if any(decl.search(x) for x in lines[max(0, i - 20):i]):
                found.append(f"{os.path.relpath(path, root)}:{i + 1}: reduction over the floating-point '{var}': "
                             "its rounding depends on the thread count (use core/reduce.hpp)")
    return found


CODE_FILES = (".cpp", ".hpp", ".py", ".toml", ".sh", ".cmake", "CMakeLists.txt", "Makefile")
TRACKER = re.compile(r"\b(?:[Ii]ssues?|PR|[Pp]ull request)[ -]?#?\d+|(?<![&\w#])#\d{1,4}\b")


def code_files(root):
    """The tracked code files (and untracked ones git does not ignore), else every one under root."""
    try:
        out = subprocess.run(["git", "-C", root, "ls-files", "--cached", "--others", "--exclude-standard"],
                             capture_output=True, text=True, check=True).stdout.split("\n")
        return [os.path.join(root, f) for f in out if f.endswith(CODE_FILES) and os.path.isfile(os.path.join(root, f))]
    except (OSError, subprocess.CalledProcessError):
        pass
    found = []
    for d, dirs, names in os.walk(root):
        dirs[:] = [x for x in dirs if not x.startswith(".") and not x.startswith("build") and x != "shared"]
        found += [os.path.join(d, f) for f in sorted(names) if f.endswith(CODE_FILES)]
    return found


def tracker_numbers(root, paths):
    """Lines of code files that cite a tracker number (preprocessor lines aside)."""
    out = []
    for path in paths:
        with open(path, encoding="utf-8", errors="replace") as fh:
            for n, line in enumerate(fh, 1):
                if re.match(r"\s*#\s*(include|pragma|define|if|ifdef|ifndef|endif|else|elif|undef|error)\b", line):
                    continue
                m = TRACKER.search(line)
                if m:
                    out.append(f"{os.path.relpath(path, root)}:{n}: cites a tracker number ('{m.group(0)}'): say why instead")
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--root", default=os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    ap.add_argument("--report", action="store_true")
    a = ap.parse_args()
    problems = []
    paths = list(sources(a.root))
    problems += include_loops(a.root, [p for p in paths if not os.path.relpath(p, a.root).startswith("tests")])
    problems += missing_tests(a.root)
    for path in paths + list(python_files(a.root)):
        with open(path, encoding="utf-8") as fh:
            n = sum(1 for _ in fh)
        if n > MAX_FILE_LINES:
            problems.append(f"{os.path.relpath(path, a.root)}: {n} lines (limit {MAX_FILE_LINES})")
        if path.endswith(".py"):
            continue
        problems += layer_violations(a.root, path)
        problems += long_functions(a.root, path)
        if not os.path.relpath(path, a.root).startswith("tests"):
            problems += float_reductions(a.root, path)
    problems += tracker_numbers(a.root, code_files(a.root))
    for p in problems:
        print(p)
    print(f"layout: {len(problems)} problem(s)")
    return 0 if a.report or not problems else 1


if __name__ == "__main__":
    sys.exit(main())
