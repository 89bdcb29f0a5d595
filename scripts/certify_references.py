#!/usr/bin/env python3
"""Every stock scene's reference, certified (docs/newton.md, "The certificate of a reference").

usage: python3 scripts/certify_references.py [--bench build/xpbd-bench] [--out DIR] [--scenes a,b]
           [--solver cholmod] [--mu12-frames 30]

For each scene of `xpbd-bench list`: `run --profile newton --reference` (two frames; ball_drop
twelve, through its contact), one process each. Per scene: the run's status, the substeps, how
many references are a solution (reference/success) and certified (the exact Hessian on the free set
positive definite, reference/certified), the worst error estimate and its substep's contraction q,
and the finest position error the references can judge (100 × the worst estimate). Then the
μ = 1e12 cases (heavy_rope and pendulum, variant mu1e12, --mu12-frames frames; docs/newton.md's
Tournier table): the same columns, and per threshold 1e-2 and 1e-4 in how many substeps the
reference can judge it, and what the race's rules (plots/race_rules.py) say of the run's first. Then `xpbd-bench report` of every file (its
`certificate` column). Every command is printed with the 1-min load before it.
"""
import argparse
import math
import os
import subprocess
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "plots"))
import race_rules  # noqa: E402
import xbruns  # noqa: E402

DATA = ("frame", "substep", "iteration", "wall_time", "position_error", "reference/contraction") + \
    xbruns.REFERENCE_DATASETS


def run(args, name, scene, sets):
    out = os.path.join(args.out, name + ".h5")
    if os.path.exists(out):
        os.remove(out)
    cmd = [args.bench, "run", "--scene", scene, "--solver", args.solver, "--profile", "newton", "--reference",
           "--out", out, "--quiet"]
    for s in sets:
        cmd += ["--set", s]
    load = open("/proc/loadavg").read().split()[0]
    print(f"# load {load}: {' '.join(cmd)}", flush=True)
    subprocess.run(cmd, check=False, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return out


def row(label, path, thresholds=()):
    r = xbruns.load(path, datasets=DATA)[-1]
    a, d = r["attrs"], r["data"]
    est = np.asarray(d["reference/error_estimate"], float)
    q = np.asarray(d["reference/contraction"], float)
    worst = int(np.argmax(est))
    notes = sorted({str(n) for n in d["reference/certificate_note"] if str(n)})
    cells = [label, a.get("status"), len(est), int(np.sum(d["reference/success"])), int(np.sum(d["reference/certified"])),
             f"{est[worst]:.2g}", "—" if math.isnan(q[worst]) else f"{q[worst]:.2g}",
             f"{float(a.get('reference_certified_threshold', math.inf)):.2g}"]
    th = np.asarray(d["reference/certified_threshold"], float)
    for t in thresholds:
        secs, why = race_rules.verdict(r, t)
        cells.append(f"judged in {int(np.sum(th <= t))} of {len(th)} substeps; the race's (the first): "
                     + (f"{secs:.3g} s" if secs is not None else why))
    cells.append("; ".join(notes) or "—")
    return "| " + " | ".join(str(c) for c in cells) + " |"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bench", default=os.path.join(ROOT, "build", "xpbd-bench"))
    ap.add_argument("--out", default="/tmp/xb_certify")
    ap.add_argument("--scenes", default=None, help="comma-separated (default: every scene of `list`)")
    ap.add_argument("--solver", default="cholmod")
    ap.add_argument("--mu12-frames", type=int, default=30)
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    if args.scenes:
        scenes = args.scenes.split(",")
    else:
        listed = subprocess.run([args.bench, "list"], capture_output=True, text=True, check=True).stdout
        block = listed.split("scenes:")[1].split("solvers:")[0]
        scenes = [s.strip() for s in block.splitlines() if s.strip()]
    head = ("| scene | status | substeps | references a solution | certified | worst error estimate | its q | "
            "finest error judged |")
    print(head + " notes |")
    print("|" + "---|" * (head.count("|")))
    files = []
    for scene in scenes:
        files.append(run(args, f"cert_{scene}", scene, [f"frames={12 if scene == 'ball_drop' else 2}"]))
        print(row(scene, files[-1]), flush=True)
    print()
    print(head + " 1e-2 | 1e-4 | notes |")
    print("|" + "---|" * (head.count("|") + 2))
    for scene in ("heavy_rope", "pendulum"):
        files.append(run(args, f"cert_{scene}_mu1e12", scene, ["variant=mu1e12", f"frames={args.mu12_frames}"]))
        print(row(f"{scene} mu1e12", files[-1], (1e-2, 1e-4)), flush=True)
    for f in files:
        print(f"\n# {args.bench} report {f}", flush=True)
        subprocess.run([args.bench, "report", f], check=False)


if __name__ == "__main__":
    sys.exit(main())
