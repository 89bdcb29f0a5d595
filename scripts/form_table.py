#!/usr/bin/env python3
"""Dual vs primal on captured systems: every global method in both forms, one table.

usage: python3 scripts/form_table.py [--bench build/xpbd-bench] [--dir results/forms] [--tol 1e-8]
                                     [--solvers cholmod,jacobi-pcg,mgpbd,hypre,muelu] [--only LABEL,...]
                                     [--quick] [--data FILE.json]

For each system below it runs `xpbd-bench capture` once (cached in DIR; the cholmod-driven state
of the scene), then `xpbd-bench solve --form dual,primal` with every solver, and prints one
Markdown table: rows, setup and solve time, iterations, operator complexity, status, per method
and form, plus the ratio the primal-form claims are judged by (primal mgpbd's iterations over dual
jacobi-pcg's; primal mgpbd's time over the best dual method's). Times are one run on this
machine (setup + solve as the harness measured them; for the primal form the assembly of K is
inside setup and the recovery of Δλ inside solve). `--quick` keeps only the smaller systems.
`--data`: the table as stamped data (plots/pages.py: the machine, its triad and load taken at the
start), which `python3 plots/pages.py publish FILE.json` makes the results page `forms`
(docs/results/).
"""
import argparse
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(ROOT, "plots"))
import pages  # noqa: E402
import xbruns  # noqa: E402

# label: (scene, sets, frame, iteration). bar_hang 5% prestretched is the hard, nearly
# volume-preserving tet-ARAP state; resolution 4/8/16 is the scalability series. squash_bunny12k_i6
# is the squash six outer iterations on: the states a simulation solves after the first.
SYSTEMS = {
    "cloth_r128": ("cloth_hang", ["resolution=128"], 0, 0),
    "cloth_r160": ("cloth_hang", ["resolution=160"], 0, 0),
    "bar_r4": ("bar_hang", ["resolution=4", "prestretch=1.05"], 0, 0),
    "bar_r8": ("bar_hang", ["resolution=8", "prestretch=1.05"], 0, 0),
    "bar_r16": ("bar_hang", ["resolution=16", "prestretch=1.05"], 0, 0),
    "squash_bunny12k": ("squash", ["mesh=bunny:12k"], 0, 0),
    "squash_bunny12k_i6": ("squash", ["mesh=bunny:12k"], 0, 6),
    "squash_bunny50k": ("squash", ["mesh=bunny:50k"], 0, 0),
}
QUICK = ["cloth_r128", "bar_r4", "bar_r8", "squash_bunny12k", "squash_bunny12k_i6"]


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"form_table: {' '.join(cmd)} failed:\n{r.stderr.strip()}")
    return r


def capture(bench, out_dir, label):
    prefix = os.path.join(out_dir, label)
    if not os.path.exists(prefix + ".h5"):
        scene, sets, frame, iteration = SYSTEMS[label]
        cmd = [bench, "capture", "--scene", scene, "--frame", str(frame), "--iteration", str(iteration), "--out", prefix]
        for s in sets:
            cmd += ["--set", s]
        run(cmd)
    return prefix + ".h5"


def fmt(v, spec):
    try:
        return format(float(v), spec)
    except (TypeError, ValueError):
        return "-"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bench", default=os.path.join(ROOT, "build", "xpbd-bench"))
    ap.add_argument("--dir", default=os.path.join(ROOT, "results", "forms"))
    ap.add_argument("--tol", default="1e-8")
    ap.add_argument("--solvers", default="cholmod,jacobi-pcg,mgpbd,hypre,muelu")
    ap.add_argument("--only", default="")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--data", default="", help="write the table as stamped data for plots/pages.py")
    a = ap.parse_args()
    labels = a.only.split(",") if a.only else (QUICK if a.quick else list(SYSTEMS))
    for l in labels:
        if l not in SYSTEMS:
            sys.exit(f"form_table: unknown system '{l}' (valid: {', '.join(SYSTEMS)})")
    os.makedirs(a.dir, exist_ok=True)
    stamp = pages.stamp("python3 scripts/form_table.py " + " ".join(sys.argv[1:]),
                        microbench=os.path.join(os.path.dirname(a.bench), "xb_microbench")) if a.data else None
    t = pages.Table(["system", "dual rows", "method", "form", "rows", "setup s", "solve s", "total s", "iterations",
                     "op. complexity", "status"])
    verdicts = []
    for label in labels:
        system = capture(a.bench, a.dir, label)
        out = os.path.join(a.dir, label + "_solve.h5")
        run([a.bench, "solve", "--system", system, "--solver", a.solvers, "--form", "dual,primal", "--tol", a.tol,
             "--out", out])
        by = {}
        for r in xbruns.load(out, datasets=(), level="linear"):
            at = r["attrs"]
            total = float(at.get("setup_time", "nan")) + float(at.get("solve_time", "nan"))
            by[(at["solver"], at["form_used"])] = (at, total)
            rows = at.get("primal_rows", at["rows"]) if at["form_used"] == "primal" else at["rows"]
            t.row([label, at["rows"], at["solver"], at["form_used"], int(float(rows)), fmt(at.get("setup_time"), ".3f"),
                   fmt(at.get("solve_time"), ".3f"), f"{total:.3f}", at.get("iterations"),
                   fmt(at.get("operator_complexity"), ".2f"), at["status"]])
        if ("mgpbd", "primal") in by and ("jacobi-pcg", "dual") in by:
            p, tp = by[("mgpbd", "primal")]
            j, _ = by[("jacobi-pcg", "dual")]
            duals = [t for (s, f), (at, t) in by.items() if f == "dual" and at["status"] == "ok"]
            best = min(duals) if duals else float("nan")
            verdicts.append(f"{label}: primal mgpbd {p['iterations']} iterations vs dual jacobi-pcg {j['iterations']} "
                            f"({int(p['iterations']) / max(1, int(j['iterations'])):.3f}); time {tp:.3f} s vs best dual "
                            f"{best:.3f} s ({tp / best:.2f})")
    print()
    for v in verdicts:
        print("- " + v)
    if a.data:
        text = (f"Each captured system (the cholmod-driven state of its scene; SYSTEMS in the command's script) solved "
                f"from zero to a dual relative residual of {a.tol} by every method in both forms, one process; the "
                "primal form's setup includes the assembly of K. Per system: primal mgpbd's iterations over dual "
                "jacobi-pcg's, and its time over the best dual method's that converged:\n\n"
                + "\n".join("- " + v for v in verdicts))
        pages.write_data(a.data, "forms", "Dual against primal form on captured systems",
                         f"Every global method, both forms, to {a.tol}", stamp, [t.data()], text)


if __name__ == "__main__":
    main()
