#!/usr/bin/env python3
"""The block-descent methods (docs/vbd.md) on the truth: every stock scene and the near-rigid
variants, VBD (plain and Chebyshev) and AVBD with `--reference`, each substep's iterations to a
position error of 1e-2 and 1e-3, the smallest error reached, how the substep ended; a table per claim.

usage: python3 scripts/vbd_claims.py scenes | rigid | tune [--bench build/xpbd-bench] [--out DIR]
                                     [--iterations N] [--frames N] [--set KEY=VALUE ...] [--only SCENE,...]
                                     [--data docs/results/data/vbd_CLAIM.json]

scenes  every stock scene (problems/scenes/, their own frames but at most --frames), rtol = atol = 0
        and --iterations sweeps per substep (the fixed-iteration frame), vbd, vbd with Chebyshev, avbd
rigid   heavy_rope, pendulum, mass_chain and their mu1e12 variants (and the rigid variants for avbd)
tune    avbd on the near-rigid set over avbd.beta x avbd.stiffness_start (how the defaults were chosen)

Each (scene, variant) is one `xpbd-bench run` into OUT/<claim>/<scene>_<variant>.h5 (an existing
file is reused; --fresh starts over); the table goes to stdout with the 1-min load at the start.
Counts, not times, are the result: the machine's load changes times, not iterations. --data: the
table as stamped data (plots/pages.py), which `python3 plots/pages.py publish FILE.json` makes a
section of docs/results/vbd.md.
"""
import argparse
import os
import subprocess
import sys

import h5py
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "plots"))
import pages  # noqa: E402
STOCK = ["cloth_hang", "bar_hang", "cantilever", "squash", "twist_bar", "ball_drop", "mass_chain", "heavy_rope",
         "pendulum"]
NEAR_RIGID = ["heavy_rope", "pendulum", "mass_chain"]
FRAMES = {"ball_drop": 12}  # the ball lands in frame 9: its contact frames
METHODS = {"vbd": ["--solver", "vbd"], "vbd-chebyshev": ["--solver", "vbd", "--set", "vbd.acceleration=chebyshev"],
           "avbd": ["--solver", "avbd"]}


def run(args, path, scene, method, sets):
    if args.fresh and os.path.exists(path):
        os.remove(path)
    if not os.path.exists(path):
        cmd = [args.bench, "run", "--scene", scene, *METHODS[method], "--reference", "--quiet", "--out", path]
        for s in sets + args.set:
            cmd += ["--set", s]
        os.makedirs(os.path.dirname(path), exist_ok=True)
        done = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        if done.returncode != 0 or not os.path.exists(path):
            return None, done.stderr.strip()[-300:]
    with h5py.File(path, "r") as f:
        g = next(iter(f["runs"].values()))
        return {k: g[k][()] for k in ("frame", "substep", "iteration", "position_error", "substep_status",
                                       "wall_time") if k in g} | {"@" + k: v for k, v in g.attrs.items()}, ""


def substeps(r):
    """Per substep: (iterations, its to 1e-2, its to 1e-3, smallest error, last error, how it ended)."""
    fr, sb, it, pe = (np.asarray(r[k]) for k in ("frame", "substep", "iteration", "position_error"))
    status = [s.decode() if isinstance(s, bytes) else str(s) for s in r.get("substep_status", [])]
    out = []
    for k, key in enumerate(sorted(set(zip(fr.tolist(), sb.tolist())))):
        m = (fr == key[0]) & (sb == key[1])
        e = pe[m]

        def first(t):
            hit = np.flatnonzero(e <= t)
            return int(it[m][hit[0]]) if len(hit) else None
        out.append((int(it[m][-1]), first(1e-2), first(1e-3), float(e.min()), float(e[-1]),
                    status[k] if k < len(status) else "-"))
    return out


def fmt(v):
    return "—" if v is None else (f"{v:.2e}" if isinstance(v, float) else str(v))


def summarise(label, r, why):
    """One table row's cells: the run's status, and over its substeps."""
    if r is None:
        return [label, f"failed: {why}", "", "", "", "", ""]
    ss = substeps(r)
    reached2 = [s[1] for s in ss if s[1] is not None]
    reached3 = [s[2] for s in ss if s[2] is not None]
    worst_end = max(s[4] for s in ss) if ss else float("nan")
    ends = sorted({s[5] for s in ss})
    return [label, f"{r['@status']} ({', '.join(ends)})", len(ss), f"{len(reached3)} of {len(ss)}",
            f"{fmt(max(reached2) if reached2 else None)} / {fmt(max(reached3) if reached3 else None)}",
            f"{worst_end:.2e}", f"{float(r['@wall_time']):.2f}"]


COLUMNS = ["scene, method", "status (substeps' ends)", "substeps", "substeps reaching 1e-3",
           "worst its to 1e-2 / 1e-3", "worst final error", "wall s"]


def scenes(args):
    t = pages.Table(COLUMNS)
    for scene in [s for s in STOCK if not args.only or s in args.only.split(",")]:
        for method in METHODS:
            sets = ["rtol=0", "atol=0", f"max_iterations={args.iterations}", f"frames={FRAMES.get(scene, args.frames)}"]
            r, why = run(args, os.path.join(args.out, "scenes", f"{scene}.{method}.h5"), scene, method, sets)
            t.row(summarise(f"{scene}, {method}", r, why))
    return t, (f"Every stock scene with its own settings, --reference, rtol = atol = 0 and {args.iterations} sweeps per "
               f"substep (the fixed-iteration frame), the first {args.frames} frames (ball_drop: {FRAMES['ball_drop']}, "
               "its contact frames); per substep the sweeps to a position error of 1e-2 and 1e-3 (the worst substep's), "
               "the worst error at the end. A substep ends early only at ‖∇E‖'s rounding floor.")


def rigid(args):
    t = pages.Table(COLUMNS)
    for scene in NEAR_RIGID:
        for variant in ("none", "mu1e12", "rigid"):
            for method in METHODS:
                if variant == "rigid" and method != "avbd":
                    continue  # E has no term for a rigid constraint
                sets = ["rtol=1e-10", "atol=0", f"max_iterations={args.iterations}", f"frames={args.frames}",
                        f"variant={variant}"]
                r, why = run(args, os.path.join(args.out, "rigid", f"{scene}_{variant}.{method}.h5"), scene, method, sets)
                t.row(summarise(f"{scene} {variant}, {method}", r, why))
    return t, (f"The near-rigid chains and their variants (mu1e12: compliance 1e-12; rigid: 0, avbd only, against "
               f"XPBD's fixed point), --reference, rtol = 1e-10 on ‖∇E‖, at most {args.iterations} sweeps per substep, "
               f"the first {args.frames} frames.")


def tune(args):
    t = pages.Table(COLUMNS)
    for beta in ("1e2", "1e3", "1e4", "1e5"):
        for start in ("1", "10", "100", "1000"):
            for scene, variant in (("heavy_rope", "none"), ("heavy_rope", "mu1e12"), ("pendulum", "none"),
                                   ("mass_chain", "none")):
                sets = ["rtol=1e-10", "atol=0", f"max_iterations={args.iterations}", f"frames={args.frames}",
                        f"variant={variant}", f"avbd.beta={beta}", f"avbd.stiffness_start={start}"]
                path = os.path.join(args.out, "tune", f"{scene}_{variant}_b{beta}_k{start}.h5")
                r, why = run(args, path, scene, "avbd", sets)
                t.row(summarise(f"{scene} {variant}, beta {beta}, start {start}", r, why))
    return t, ("avbd over avbd.beta × avbd.stiffness_start on the near-rigid chains, rtol = 1e-10, "
               f"at most {args.iterations} sweeps, {args.frames} frames: how the defaults were chosen.")


TITLES = {"scenes": "Every stock scene", "rigid": "The near-rigid chains", "tune": "AVBD's ramp and start"}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("claim", choices=["scenes", "rigid", "tune"])
    ap.add_argument("--bench", default=os.path.join(ROOT, "build", "xpbd-bench"))
    ap.add_argument("--out", default=os.path.join(ROOT, "plots", "vbd_claims"))
    ap.add_argument("--iterations", type=int, default=2000)
    ap.add_argument("--frames", type=int, default=3)
    ap.add_argument("--only", default="")
    ap.add_argument("--set", action="append", default=[])
    ap.add_argument("--fresh", action="store_true")
    ap.add_argument("--data", default="", help="write the table as stamped data for plots/pages.py")
    args = ap.parse_args()
    if not os.access(args.bench, os.X_OK):
        sys.exit(f"{args.bench}: not an executable (build first)")
    stamp = pages.stamp("python3 scripts/vbd_claims.py " + " ".join(sys.argv[1:]),
                        microbench=os.path.join(os.path.dirname(args.bench), "xb_microbench")) if args.data else None
    print(f"# {TITLES[args.claim]}; 1-min load {os.getloadavg()[0]:.2f}", flush=True)
    t, text = {"scenes": scenes, "rigid": rigid, "tune": tune}[args.claim](args)
    if args.data:
        pages.write_data(args.data, "vbd", "VBD and AVBD on the truth: the tables", TITLES[args.claim], stamp, [t.data()],
                         text, order=list(TITLES).index(args.claim))


if __name__ == "__main__":
    main()
