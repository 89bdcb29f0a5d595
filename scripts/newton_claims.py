#!/usr/bin/env python3
"""The card's claims about XPBD's simplifications and Newton's method, measured (docs/newton.md).

usage: python3 scripts/newton_claims.py tournier | chen | macklin | omega | mgpbd_k
           [--bench build/xpbd-bench] [--out DIR] [--mesh bunny:12k] [--data FILE.json]

tournier  heavy_rope and pendulum (problems/scenes/), variants none, mu1e12, mass_ratio_1e4,
          dt_30hz; XPBD with xpbd.geometric_stiffness none | diagonal | full and Newton, cholmod,
          --reference (Newton's): status, outer iterations, worst final position error and
          relative Newton residual of any substep; and Tournier's claim itself, stability: the
          light particles' largest speed after the last frame (--save-state) and the largest
          distance of any particle from where Newton's trajectory ends (30 frames).
chen      squash (--mesh) and twist_bar 7e9 (resolution 6), cholmod, 100 outer iterations with
          xpbd.primal_residual zero | keep: the relative Newton and dual residuals over iterations.
macklin   mass_chain (256 links, masses graded to mass_ratio), dual against primal form with
          cg and jacobi-pcg (linear.tol 1e-6, fixed), under mass ratio (1 … 1e6, compliance 1e-8)
          and compliance (1e-4 … 1e-10, mass ratio 1); bar_hang under stiffness 1e5 … 1e11:
          mean (P)CG iterations per solve.
omega     squash (--mesh): XPBD at omega 1 and 0.25 against Newton, cholmod, --reference.
mgpbd_k   squash (--mesh): mgpbd on XPBD's K and on Newton's K (linear.forcing fixed, tol 1e-8):
          levels, operator complexity, PCG iterations per outer iteration.

Each run is its own process; every command is printed, with the 1-min load before it. A position
error is printed only where the run's references are certified to judge it (their error estimate
at most 1/100 of it, plots/xbruns.py: error_text); elsewhere "reference not fine enough".
--data: the claim's table as stamped data (plots/pages.py: the machine, its triad and load taken at
the start), which `python3 plots/pages.py publish FILE.json` makes a section of the results page
`newton` (docs/results/).
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
import xbruns  # noqa: E402

SCENES = os.path.join(ROOT, "problems", "scenes")


def run(args, name, scene, solver, sets=(), profile=None, reference=False, state_frame=None):
    """One run in its own process; with state_frame, data["velocities"] holds v after that frame."""
    out = os.path.join(args.out, name + ".h5")
    state = os.path.join(args.out, name + ".state.h5")
    for f in (out, state):
        if os.path.exists(f):
            os.remove(f)
    cmd = [args.bench, "run", "--scene", scene, "--solver", solver, "--out", out, "--quiet"]
    cmd += ["--save-state", state, "--frame-of-state", str(state_frame)] if state_frame is not None else []
    cmd += ["--profile", profile] if profile else []
    cmd += ["--reference"] if reference else []
    for s in sets:
        cmd += ["--set", s]
    load = open("/proc/loadavg").read().split()[0]
    print(f"# load {load}: {' '.join(cmd)}", flush=True)
    subprocess.run(cmd, check=False, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with h5py.File(out) as f:
        r = f["runs"][list(f["runs"])[0]]
        attrs = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in r.attrs.items()}
        data = {k: np.array(r[k]) for k in ("iteration", "relative_newton_residual", "relative_dual_residual",
                                             "position_error", "linear_iterations", "wall_time", "final_positions",
                                             "reference/error_estimate")
                if k in r}
    if state_frame is not None and os.path.exists(state):
        with h5py.File(state) as f:
            data["velocities"] = np.array(f["velocities"]).reshape(-1, 3)
    return attrs, data


def substep_ends(data):
    """Indices of each substep's last entry."""
    it = data["iteration"]
    return [i for i in range(len(it)) if i + 1 == len(it) or it[i + 1] == 0]


TOURNIER_FRAMES = 30  # the scenes' own (half a second)


def stability(d, newton_end):
    """The light particles' largest speed after the last frame (every free particle but the heavy
    last one; the first is pinned) and the largest distance of a particle from Newton's end."""
    v = d.get("velocities")
    speed = float(np.max(np.linalg.norm(v[1:-1], axis=1))) if v is not None else float("nan")
    x = d["final_positions"].reshape(-1, 3)
    drift = float(np.max(np.linalg.norm(x - newton_end, axis=1))) if newton_end is not None else float("nan")
    return speed, drift


def tournier(args):
    t = pages.Table(["scene", "variant", "outer method", "status", "outer its", "worst position error",
                     "reference's error estimate", "worst rel. Newton res.", "light particles' end speed m/s",
                     "distance from Newton's end m"])
    for scene in ("heavy_rope", "pendulum"):
        for variant in ("none", "mu1e12", "mass_ratio_1e4", "dt_30hz"):
            newton_end = None
            for method in ("newton", "none", "diagonal", "full"):  # Newton first: the others' distance from it
                sets = [f"variant={variant}"]
                sets += [f"xpbd.geometric_stiffness={method}"] if method != "newton" else []
                a, d = run(args, f"t_{scene}_{variant}_{method}", scene, "cholmod", sets,
                           profile="newton" if method == "newton" else None, reference=True,
                           state_frame=TOURNIER_FRAMES - 1)
                ends = substep_ends(d) if "iteration" in d else []
                pe = max((d["position_error"][i] for i in ends), default=float("nan")) if "position_error" in d else float("nan")
                nr = max((d["relative_newton_residual"][i] for i in ends), default=float("nan"))
                speed, drift = stability(d, newton_end)
                if method == "newton":
                    newton_end = d["final_positions"].reshape(-1, 3)
                label = "Newton" if method == "newton" else f"XPBD, {method}"
                est = a.get("reference_error_estimate", float("nan"))
                t.row([scene, variant, label, a.get("status"), a.get("outer_iterations"), xbruns.error_text(pe, a),
                       f"{est:.2e}", f"{nr:.2e}", f"{speed:.3g}", "—" if method == "newton" else f"{drift:.3g}"])
    return t


def chen(args):
    cases = [("squash", [f"mesh={args.mesh}"]), ("twist_bar", ["stiffness=7e9", "resolution=6"])]
    marks = [1, 5, 10, 20, 40, 60, 100]
    t = pages.Table(["scene", "g"] + [f"it {k}" for k in marks] + ["final position error"])
    for scene, sets in cases:
        for keep in ("zero", "keep"):
            a, d = run(args, f"c_{scene}_{keep}", scene, "cholmod",
                       sets + [f"xpbd.primal_residual={keep}", "max_iterations=100", "rtol=0", "atol=0"], reference=True)
            nr, dr = d["relative_newton_residual"], d["relative_dual_residual"]
            cells = [f"{nr[k]:.3g} / {dr[k]:.3g}" if k < len(nr) else "—" for k in marks]
            t.row([scene, keep] + cells + [xbruns.error_text(a.get("final_position_error"), a)])
    return t


def macklin(args):
    t = pages.Table(["case", "dual CG", "primal CG", "dual Jacobi-PCG", "primal Jacobi-PCG"])
    cases = [(f"mass_ratio {m:g}", [f"mass_ratio={m}"]) for m in (1, 1e2, 1e4, 1e6)]
    cases += [(f"compliance {c:g}", [f"compliance={c}", "mass_ratio=1"]) for c in (1e-4, 1e-7, 1e-10)]
    for label, sets in cases:
        cells = []
        for solver in ("cg", "jacobi-pcg"):
            for form in ("dual", "primal"):
                a, d = run(args, f"m_{label.replace(' ', '_')}_{solver}_{form}", "mass_chain", solver,
                           sets + [f"form={form}", "resolution=256", "linear.forcing=fixed", "linear.tol=1e-6",
                                   "linear.max_iterations=100000", "frames=2"])
                li = d["linear_iterations"][d["linear_iterations"] > 0]
                cells.append((f"{li.mean():.1f}" if len(li) else "—") + ("" if a.get("status") == "ok" else f" ({a.get('status')})"))
        t.row([f"mass_chain 256, {label}"] + cells)
    for mu in (1e5, 1e7, 1e9, 1e11):  # a 3D case under stiffness: bar_hang, 4 cubes across (1.5K tets)
        cells = []
        for solver in ("cg", "jacobi-pcg"):
            for form in ("dual", "primal"):
                a, d = run(args, f"m_bar_{mu:g}_{solver}_{form}", "bar_hang", solver,
                           [f"stiffness={mu}", f"form={form}", "linear.forcing=fixed", "linear.tol=1e-6",
                            "linear.max_iterations=100000", "frames=2"])
                li = d["linear_iterations"][d["linear_iterations"] > 0]
                cells.append((f"{li.mean():.1f}" if len(li) else "—") + ("" if a.get("status") == "ok" else f" ({a.get('status')})"))
        t.row([f"bar_hang, stiffness {mu:g}"] + cells)
    return t


def omega(args):
    t = pages.Table(["outer method", "status", "outer its", "wall time s", "final position error",
                     "final rel. Newton res."])
    for label, sets, profile in (("XPBD, omega = 1", ["omega=1"], None), ("XPBD, omega = 0.25", [], None),
                                 ("Newton", [], "newton")):
        a, d = run(args, f"o_{label.split(',')[-1].strip().replace(' ', '')}", "squash", "cholmod",
                   [f"mesh={args.mesh}"] + sets, profile=profile, reference=True)
        t.row([label, a.get("status"), a.get("outer_iterations"), f"{a.get('wall_time'):.3g}",
               xbruns.error_text(a.get("final_position_error"), a), f"{a.get('final_relative_newton_residual'):.3g}"])
    return t


def mgpbd_k(args):
    t = pages.Table(["K", "levels", "operator complexity", "PCG iterations per outer iteration"])
    for label, profile in (("XPBD's (M + Jᵀα̃⁻¹J)", None), ("Newton's (M + Σπ(H_j))", "newton")):
        a, d = run(args, f"k_{'newton' if profile else 'xpbd'}", "squash", "mgpbd",
                   [f"mesh={args.mesh}", "linear.forcing=fixed", "linear.tol=1e-8", "max_iterations=8"], profile=profile)
        its = " ".join(str(int(v)) for v in d["linear_iterations"][1:])
        t.row([label, a.get("levels"), f"{a.get('operator_complexity', float('nan')):.3g}", its])
    return t


def claim_text(claim):
    """The claim's paragraph of this file's usage text."""
    lines, out = __doc__.split("\n"), []
    for line in lines:
        if out and line[:1] not in (" ", ""):
            break
        if out or line.startswith(claim + " "):
            out.append(line[len(claim):].strip() if not out else line.strip())
    return " ".join(x for x in out if x)


TITLES = {"tournier": "Tournier: geometric stiffness on stiff and high-mass-ratio cases",
          "chen": "Chen: the Newton residual with g zeroed and kept",
          "macklin": "Macklin: dual against primal form",
          "omega": "The squash's ω under XPBD and Newton",
          "mgpbd_k": "mgpbd on XPBD's K and on Newton's K"}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("claim", choices=["tournier", "chen", "macklin", "omega", "mgpbd_k"])
    ap.add_argument("--bench", default=os.path.join(ROOT, "build", "xpbd-bench"))
    ap.add_argument("--out", default="/tmp/xb_newton_claims")
    ap.add_argument("--mesh", default="bunny:12k")
    ap.add_argument("--data", default="", help="write the table as stamped data for plots/pages.py")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    stamp = pages.stamp("python3 scripts/newton_claims.py " + " ".join(sys.argv[1:]),
                        microbench=os.path.join(os.path.dirname(args.bench), "xb_microbench")) if args.data else None
    t = globals()[args.claim](args)
    if args.data:
        pages.write_data(args.data, "newton", "Newton on E: the tables", TITLES[args.claim], stamp, [t.data()],
                         claim_text(args.claim), order=2 + list(TITLES).index(args.claim))


if __name__ == "__main__":
    sys.exit(main())
