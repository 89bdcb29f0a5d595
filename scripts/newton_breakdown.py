#!/usr/bin/env python3
"""Where Newton's frame goes, per iteration and per part: the squash (enlarged start) under
`--profile newton` with each linear method, each in its own process, against one stored reference.

usage: python3 scripts/newton_breakdown.py [--bench build/xpbd-bench] [--mesh bunny:270k]
           [--solver mgpbd,cholmod] [--set KEY=VALUE]... [--variant NAME:KEY=VALUE,...]...
           [--out DIR] [--perf] [--threshold 1e-3]

Per run: the position error and wall time of every Newton iteration; each step's element Hessians
(`hessian_time`), K's fill (`fill_time`), the linear setup (`linear_setup_time`: factorisation, AMG
setup or refresh), the solve (`linear_solve_time`, PCG iterations), the line search (its trials;
its time is the step's less the rest) and the time outside the steps; the time to --threshold and,
for each run, its ratio to the first solver's (the baseline); the process's CPU seconds (user +
sys) and the 1-min load before it. A variant is extra --set keys under a name (e.g.
`keep:amg.refresh=keep`). --perf: each mgpbd run also under `perf record` (cpu-clock, call graphs),
and the 25 hottest symbols printed (perf report --no-children).

The reference is computed once into OUT/reference_<mesh>.h5 (`run --reference-file`) and read by
every run. Under load the wall times move; the counts (iterations, trials) do not.
"""
import argparse
import os
import resource
import subprocess
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "plots"))
import xbruns  # noqa: E402

DATASETS = ("iteration", "wall_time", "position_error", "step_time", "hessian_time", "fill_time", "linear_setup_time",
            "linear_solve_time", "linear_iterations", "line_search_trials", "linear_setup_action")


def cpu_children():
    u = resource.getrusage(resource.RUSAGE_CHILDREN)
    return u.ru_utime + u.ru_stime


def reference_pass(args, ref):
    """The stored reference, computed once before the timed runs (one sweep of xpbd-jacobi)."""
    if os.path.exists(ref):
        return
    cmd = [args.bench, "run", "--scene", "squash", "--solver", "xpbd-jacobi", "--set", f"mesh={args.mesh}", "--set",
           "init=enlarge", "--set", "max_iterations=1", "--reference-file", ref, "--quiet", "--out",
           os.path.join(args.out, "reference_pass.h5")]
    for kv in args.set:  # the problem's keys are part of the reference's
        cmd += ["--set", kv]
    print(f"# {' '.join(cmd)}   (the reference; 1-min load {os.getloadavg()[0]:.2f})", flush=True)
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)


def run(args, name, solver, sets, perf):
    out = os.path.join(args.out, f"{name}.h5")
    ref = os.path.join(args.out, f"reference_{args.mesh.replace(':', '_')}.h5")
    cmd = [args.bench, "run", "--scene", "squash", "--profile", "newton", "--solver", solver, "--set", f"mesh={args.mesh}",
           "--set", "init=enlarge", "--reference-file", ref, "--quiet", "--out", out]
    for kv in sets:
        cmd += ["--set", kv]
    reference_pass(args, ref)
    if perf:
        cmd = ["perf", "record", "-q", "-e", "cpu-clock", "-g", "-o", out + ".perf", "--"] + cmd
    load = os.getloadavg()[0]
    print(f"# {' '.join(cmd)}   (1-min load {load:.2f})", flush=True)
    c0, t0 = cpu_children(), time.time()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    cpu, wall = cpu_children() - c0, time.time() - t0
    r = xbruns.load(out, datasets=DATASETS)[-1]
    return dict(name=name, run=r, cpu=cpu, wall=wall, load=load, perf=out + ".perf" if perf else None)


def time_to(r, e):
    d = r["data"]
    hit = np.flatnonzero(np.asarray(d["position_error"]) <= e)
    return float(d["wall_time"][hit[0]]) if len(hit) else float("nan")


def table(res, threshold):
    d, a = res["run"]["data"], res["run"]["attrs"]
    print(f"\n## {res['name']}: status {a['status']}, {a['outer_iterations']} Newton iterations, wall {float(a['wall_time']):.2f} s "
          f"(process {res['wall']:.1f} s, CPU {res['cpu']:.1f} s, load {res['load']:.2f}), time to {threshold:g}: "
          f"{time_to(res['run'], threshold):.2f} s")
    print("| it | position error | at s | step s | Hessians s | K fill s | setup s | solve s | PCG its | search trials | search+rest s | setup action |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for k in range(len(d["iteration"])):
        parts = [float(d[x][k]) for x in ("step_time", "hessian_time", "fill_time", "linear_setup_time", "linear_solve_time")]
        # fill_time is inside linear_setup_time (K is assembled by the setup): not subtracted twice.
        rest = parts[0] - parts[1] - parts[3] - parts[4]
        print(f"| {int(d['iteration'][k])} | {float(d['position_error'][k]):.3g} | {float(d['wall_time'][k]):.2f} | "
              + " | ".join(f"{v:.3f}" for v in parts) + f" | {int(d['linear_iterations'][k])} | "
              f"{int(d['line_search_trials'][k])} | {rest:.3f} | {d['linear_setup_action'][k]} |")
    sums = {x: float(np.sum(d[x])) for x in ("step_time", "hessian_time", "fill_time", "linear_setup_time", "linear_solve_time")}
    outside = float(d["wall_time"][-1]) - sums["step_time"]
    print(f"totals: steps {sums['step_time']:.2f} s = Hessians {sums['hessian_time']:.2f} + setup {sums['linear_setup_time']:.2f} "
          f"(K fill {sums['fill_time']:.2f} of it) + solve {sums['linear_solve_time']:.2f} + search/rest "
          f"{sums['step_time'] - sums['hessian_time'] - sums['linear_setup_time'] - sums['linear_solve_time']:.2f}; "
          f"outside the steps {outside:.2f} s; PCG its {int(np.sum(d['linear_iterations']))}")


def hottest(perf_file, n=25):
    rep = subprocess.run(["perf", "report", "-i", perf_file, "--no-children", "--stdio", "-F", "overhead,sym", "-g", "none",
                          "--percent-limit", "0.5"], capture_output=True, text=True)
    lines = [line for line in rep.stdout.splitlines() if line.strip() and not line.startswith("#")]
    print(f"\nhottest symbols of {perf_file}:")
    print("\n".join(lines[:n]))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bench", default=os.path.join(ROOT, "build", "xpbd-bench"))
    ap.add_argument("--mesh", default="bunny:270k")
    ap.add_argument("--solver", default="mgpbd,cholmod")
    ap.add_argument("--set", action="append", default=[], help="KEY=VALUE for every run")
    ap.add_argument("--variant", action="append", default=[], help="NAME:KEY=VALUE,... an mgpbd run with these keys")
    ap.add_argument("--out", default=os.path.join(ROOT, "plots", "newton_breakdown"))
    ap.add_argument("--perf", action="store_true")
    ap.add_argument("--threshold", type=float, default=1e-3)
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    results = [run(args, s, s, args.set, args.perf and s == "mgpbd") for s in args.solver.split(",")]
    for v in args.variant:
        name, _, keys = v.partition(":")
        results.append(run(args, name, "mgpbd", args.set + keys.split(","), args.perf))
    for r in results:
        table(r, args.threshold)
    base = time_to(results[0]["run"], args.threshold)
    print(f"\ntime to {args.threshold:g}, over {results[0]['name']}'s ({base:.2f} s):")
    for r in results:
        t = time_to(r["run"], args.threshold)
        print(f"  {r['name']}: {t:.2f} s ({t / base:.2f}x)")
    for r in results:
        if r["perf"]:
            hottest(r["perf"])


if __name__ == "__main__":
    main()
