#!/usr/bin/env python3
"""Every projection strategy of Newton on E on every stock scene (docs/newton.md, issue 36).

usage: python3 scripts/newton_variants.py [--bench build/xpbd-bench] [--out DIR]
           [--strategies clamp,abs,...] [--scenes a,b] [--meshes bunny:12k,bunny:50k]
           [--solver cholmod] [--no-reference] [--data FILE.json]

For each scene of `xpbd-bench list` (two frames; ball_drop twelve, through its contact) and each
value of xpbd.hessian_projection: `run --profile newton --reference` with the solver. Then, for
each --meshes entry, the squash on that mesh (one frame, max_iterations 40, no reference).
Columns: status, outer iterations summed over the substeps, substeps ended at the rounding floor,
the worst final relative ‖∇E‖ of any substep, linear solves (CHOLMOD: factorisations), the
reference's statuses, and the CPU seconds of the process (user + system: comparable under load,
unlike wall time). Each run is its own process; every command is printed with the 1-min load.
--data: the table as stamped data (plots/pages.py: the machine, its triad and load taken at the
start), which `python3 plots/pages.py publish FILE.json` makes a section of the results page
`newton` (docs/results/).
"""
import argparse
import os
import resource
import subprocess
import sys

import h5py
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "plots"))
import pages  # noqa: E402

COLUMNS = ["scene", "strategy", "status", "outer its", "floor substeps", "worst final rel. ‖∇E‖", "factorisations",
           "reference", "CPU s"]
STRATEGIES = ["clamp", "abs", "adaptive", "on_demand", "progressive", "rho_switch"]


def cpu_seconds():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run(args, name, scene, sets, reference):
    out = os.path.join(args.out, name + ".h5")
    if os.path.exists(out):
        os.remove(out)
    cmd = [args.bench, "run", "--scene", scene, "--solver", args.solver, "--profile", "newton", "--out", out, "--quiet"]
    cmd += ["--reference"] if reference else []
    for s in sets:
        cmd += ["--set", s]
    load = open("/proc/loadavg").read().split()[0]
    print(f"# load {load}: {' '.join(cmd)}", file=sys.stderr, flush=True)
    before = cpu_seconds()
    subprocess.run(cmd, check=False, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    cpu = cpu_seconds() - before
    with h5py.File(out) as f:
        r = f["runs"][list(f["runs"])[0]]
        a = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in r.attrs.items()}
        it = np.array(r["iteration"])
        rel = np.array(r["relative_newton_residual"])
        ends = [i for i in range(len(it)) if i + 1 == len(it) or it[i + 1] == 0]
        sub = [s.decode() for s in r["substep_status"][()]] if "substep_status" in r else []
        ref = [s.decode() for s in r["reference/status"][()]] if "reference/status" in r else []
    solves = a.get("factorisations", np.nan)
    refs = ", ".join(f"{s} {ref.count(s)}" for s in sorted(set(ref))) if ref else "-"
    return [a.get("status"), a.get("outer_iterations"), sub.count("rounding_floor"), f"{max(rel[i] for i in ends):.2g}",
            f"{solves:.0f}", refs, f"{cpu:.2f}"]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bench", default=os.path.join(ROOT, "build", "xpbd-bench"))
    ap.add_argument("--out", default="/tmp/xb_newton_variants")
    ap.add_argument("--strategies", default=",".join(STRATEGIES))
    ap.add_argument("--scenes", default="")
    ap.add_argument("--meshes", default="")
    ap.add_argument("--solver", default="cholmod")
    ap.add_argument("--no-reference", action="store_true")
    ap.add_argument("--data", default="", help="write the table as stamped data for plots/pages.py")
    args = ap.parse_args()
    stamp = pages.stamp("python3 scripts/newton_variants.py " + " ".join(sys.argv[1:]),
                        microbench=os.path.join(os.path.dirname(args.bench), "xb_microbench")) if args.data else None
    os.makedirs(args.out, exist_ok=True)
    listed = subprocess.run([args.bench, "list"], capture_output=True, text=True, check=True).stdout.splitlines()
    scenes = listed[listed.index("scenes:") + 1:listed.index("solvers:")]
    scenes = [s.strip() for s in scenes]
    if args.scenes:
        scenes = args.scenes.split(",")
    t = pages.Table(COLUMNS)
    for scene in scenes:
        frames = 12 if scene == "ball_drop" else 2
        for s in args.strategies.split(","):
            row = run(args, f"{scene}_{s}", scene, [f"frames={frames}", f"xpbd.hessian_projection={s}"],
                      not args.no_reference)
            t.row([scene, s] + row)
    for mesh in filter(None, args.meshes.split(",")):
        for s in args.strategies.split(","):
            row = run(args, f"squash_{mesh.replace(':', '_')}_{s}", "squash",
                      [f"mesh={mesh}", "max_iterations=40", f"xpbd.hessian_projection={s}"], False)
            t.row([f"squash {mesh}", s] + row)
    if args.data:
        pages.write_data(args.data, "newton", "Newton on E: the tables", "Every projection strategy on every stock scene",
                         stamp, [t.data()], description(), order=1)


def description():
    """The paragraph of this file's usage text that says what is run and what each column is."""
    text = next(p for p in __doc__.split("\n\n") if p.startswith("For each scene"))
    return " ".join(text.split("\n--data")[0].split())


if __name__ == "__main__":
    sys.exit(main())
