"""The paper's claims, measured from the results of the figure sweeps (figures/run.py runs them):
each claim_* reads its sweeps' results files, adds rows to a Summary and draws its figures.

Used by figures/run.py; the numbers beside ours are the paper's (shared/paper/paper_and_code_notes.md).
"""
import os
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import xbruns  # noqa: E402
from claim_data import DATA, failed, fmt, last_substep, runs_of  # noqa: E402
import profile_claims  # noqa: E402

# --only NAME for a claim whose inputs are several specs (a sweep spec has one scene).
GROUPS = {"dual_primal": ["dual_primal", "dual_primal_bar"]}


def status_note(run):
    a = run["attrs"]
    s = a.get("status")
    return "" if s in ("ok", "max_iterations") else f"{s}: {a.get('message', '')}"[:160]


class Summary:
    def __init__(self):
        self.rows = []  # (claim, quantity, paper, measured, note)
        self.figures = []
        self.sections = []  # (title, Markdown): a claim's own table after the main one
        self.paired = []  # (claim, quantity, paper, authors' profile, harness): plots/profile_claims.py
        self.verdicts = []  # (claim, one line)

    def add(self, claim, quantity, paper, measured, note=""):
        self.rows.append((claim, quantity, paper, measured, note))

    def not_run(self, claim, reason):
        self.rows.append((claim, "—", "—", f"not run: {reason}", ""))


def tets(run):
    return fmt(xbruns.as_number(run["attrs"].get("rows")))


def claim_squash(summary, files, notes, out):
    claim = "squash: XPBD stalls, MGPBD reaches 1e-2 in 55–59"
    paper_x = {"bunny:5k": "0.969", "bunny:12k": "0.771", "bunny:270k": "0.727"}
    paper_m = {"bunny:5k": ("118", "7.8 s", "4.0e-4 at 500"), "bunny:12k": ("55", "3.7 s", "3.7e-6 at 500"),
               "bunny:50k": ("68", "8.28 s", "—"), "bunny:270k": ("59", "15.1 s", "1.1e-6 at 459")}
    rx = runs_of(files.get("squash_xpbd"), datasets=DATA)
    rm = runs_of(files.get("squash_mgpbd"), datasets=DATA)
    for key in ("squash_xpbd", "squash_mgpbd"):
        if key in notes:
            summary.add(claim, f"inputs of {key}", "—", f"not run: {notes[key]}" if not (rx if key == 'squash_xpbd' else rm)
                  else f"partly run: {notes[key]}")
    for r in rx:
        m = r["attrs"].get("mesh")
        if failed(r):
            summary.add(claim, f"{r['attrs'].get('solver')} rel. dual residual after 10⁴ its, {m}", paper_x.get(m, "—"),
                  f"not run: {status_note(r)}")
            continue
        its = int(r["data"]["iteration"][-1])
        summary.add(claim, f"{r['attrs'].get('solver')} relative dual residual after {its} its ({tets(r)} tets, {m})",
              paper_x.get(m, "—"),
              f"{fmt(float(r['data']['relative_dual_residual'][-1]))} ({fmt(float(r['attrs']['wall_time']))} s)",
              status_note(r))
    for r in rm:
        m = r["attrs"].get("mesh")
        p = paper_m.get(m, ("—", "—", "—"))
        if failed(r):
            summary.add(claim, f"MGPBD iterations to 1e-2, {m}", p[0], f"not run: {status_note(r)}")
            continue
        it, t = xbruns.to_tolerance(r, 1e-2)
        summary.add(claim, f"mgpbd outer iterations / time to 1e-2 ({tets(r)} tets, {m})", f"{p[0]} / {p[1]}",
              f"{fmt(it)} / {fmt(t)} s", status_note(r))
        summary.add(claim, f"mgpbd relative dual residual at the end ({m})", p[2],
              f"{fmt(float(r['data']['relative_dual_residual'][-1]))} at {int(r['data']['iteration'][-1])}")
    if not rx and not rm:
        if "squash_xpbd" not in notes and "squash_mgpbd" not in notes:
            summary.not_run(claim, "no results")
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.4))
    for r in rx + rm:
        if failed(r):
            continue
        lab = f"{r['attrs'].get('solver')} {r['attrs'].get('mesh')}"
        rel = np.maximum(np.asarray(r["data"]["relative_dual_residual"]), 1e-300)
        it = np.asarray(r["data"]["iteration"])
        axes[0].loglog(np.maximum(it, 1), rel, label=lab)
        axes[1].loglog(np.maximum(np.asarray(r["data"]["wall_time"]), 1e-4), rel, label=lab)
    for ax, xl in zip(axes, ("outer iteration", "wall time (s)")):
        ax.axhline(1e-2, color="k", lw=0.6, ls=":")
        ax.set_xlabel(xl)
        ax.set_ylabel("relative dual residual")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("squash (frame 0): one-sweep XPBD against MGPBD")
    fig.tight_layout()
    xbruns.save(fig, os.path.join(out, "squash_residual.png"))
    summary.figures.append("squash_residual.png")


def claim_scaling(summary, files, notes, out):
    claim = "time per outer iteration linear in size"
    runs = runs_of(files.get("scaling"), datasets=())
    if not runs:
        summary.not_run(claim, notes.get("scaling", "no results"))
        return
    import scaling
    data = scaling.per_iteration(runs, "rows")
    for s, (n, t) in sorted(data.items()):
        if len(n) < 2:
            summary.add(claim, f"{s}: R² of the linear fit", "0.998", f"not run: only {len(n)} size(s) finished")
            continue
        k, b, r2 = xbruns.linear_fit(n, t)
        summary.add(claim, f"{s}: R² of t = a·tets + b over {len(n)} sizes ({int(n.min())}–{int(n.max())} tets)",
              "0.9978 (mgpbd)" if s == "mgpbd" else "—", f"{r2:.4f}")
        summary.add(claim, f"{s}: slope a / intercept b", "0.662 ms per 1K tets / 78.2 ms (RTX 4090)" if s == "mgpbd" else "—",
              f"{k * 1e3:.3g} ms per 1K / {b:.3g} ms (this CPU)")
    if "scaling" in notes:
        summary.add(claim, "inputs", "—", f"partly run: {notes['scaling']}")
    plot(summary, "scaling.py", files["scaling"], os.path.join(out, "scaling.png"))


def claim_near_kernel(summary, files, notes, out):
    claim = "near-kernel: 34 (B = 1) vs 18 (GS) PCG iterations"
    runs = runs_of(files.get("near_kernel"), datasets=DATA)
    if not runs:
        summary.not_run(claim, notes.get("near_kernel", "no results"))
        return
    paper = {"ones": "34 (rel. res. 6.4e-7)", "gs": "— (adaptive SA: 20)", "gs_authors": "18 (rel. res. 7.9e-7)"}
    for r in runs:
        nk = r["attrs"].get("amg.near_kernel")
        if failed(r) or "linear_iterations" not in r["data"] or len(r["data"]["linear_iterations"]) < 2:
            summary.add(claim, f"PCG iterations, B = {nk}", paper.get(nk, "—"), f"not run: {status_note(r) or 'no solve'}")
            continue
        summary.add(claim, f"PCG iterations of the first solve, near_kernel = {nk} ({tets(r)} tets)", paper.get(nk, "—"),
              f"{int(r['data']['linear_iterations'][1])} (rel. res. {fmt(float(r['data']['linear_relative_residual'][1]))})")


def claim_setup_interval(summary, files, notes, out):
    claim = "setup interval 1 → 100: residual after 100 its 1.03e-2 → 1.45e-2"
    runs = runs_of(files.get("setup_interval"), datasets=DATA)
    if not runs:
        summary.not_run(claim, notes.get("setup_interval", "no results"))
        return
    paper = {1: "1.025e-2", 10: "1.219e-2", 20: "1.310e-2", 50: "1.404e-2", 100: "1.452e-2"}
    for r in sorted(runs, key=lambda r: int(r["attrs"].get("amg.setup_interval", 0))):
        k = int(r["attrs"].get("amg.setup_interval", 0))
        if failed(r):
            summary.add(claim, f"interval {k}", paper.get(k, "—"), f"not run: {status_note(r)}")
            continue
        fr, sub = last_substep(r)
        v = xbruns.value_at_iteration(r, "relative_dual_residual", 100, fr, sub)
        summary.add(claim, f"rel. dual residual after 100 its, frame {fr}, setup_interval = {k} ({tets(r)} tets)",
              paper.get(k, "—"), fmt(v), status_note(r))
    plot(summary, "sweep.py", files["setup_interval"], os.path.join(out, "setup_interval.png"),
         ["--metric", "relative_dual_residual"])


def claim_twist(summary, files, notes, out):
    claim = "twist bar at 7e9: relative energy 0.03 (MGPBD) vs 0.75 (XPBD)"
    runs = runs_of(files.get("twist_bar"), datasets=DATA)
    if not runs:
        summary.not_run(claim, notes.get("twist_bar", "no results"))
        return
    paper = {("mgpbd", 7e7): "0.695", ("mgpbd", 7e8): "0.253", ("mgpbd", 7e9): "0.0315",
             ("xpbd", 7e7): "0.639", ("xpbd", 7e8): "0.694", ("xpbd", 7e9): "0.749"}
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    stiff = sorted({float(r["attrs"].get("stiffness")) for r in runs})
    fig, axes = plt.subplots(1, len(stiff), figsize=(4.4 * len(stiff), 4), squeeze=False)
    for r in sorted(runs, key=lambda r: (float(r["attrs"]["stiffness"]), r["attrs"]["solver"])):
        mu, s = float(r["attrs"]["stiffness"]), r["attrs"]["solver"]
        pk = paper.get(("mgpbd" if s == "mgpbd" else "xpbd" if s.startswith("xpbd") else s, mu), "—")
        if failed(r) or "energy" not in r["data"]:
            summary.add(claim, f"{s}, μ = {mu:.0e}", pk, f"not run: {status_note(r)}")
            continue
        m = xbruns.substep_mask(r, 0, 0)
        en = np.asarray(r["data"]["energy"])[m]
        it = np.asarray(r["data"]["iteration"])[m]
        rel = en / en[0] if en[0] > 0 else en
        k = np.flatnonzero(it <= 100)[-1]
        summary.add(claim, f"{s}: E(it {int(it[k])}) / E(0), μ = {mu:.0e} ({tets(r)} tets)", pk, fmt(float(rel[k])),
              status_note(r))
        ax = axes[0][stiff.index(mu)]
        ax.semilogy(it, rel, label=s)
        ax.set_title(f"μ = {mu:.0e} Pa")
        ax.set_xlabel("outer iteration")
        ax.set_ylabel("incremental energy / its value at x̃")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    xbruns.save(fig, os.path.join(out, "twist_bar_energy.png"))
    summary.figures.append("twist_bar_energy.png")


def claim_cloth(summary, files, notes, out):
    claim = "hanging cloth: XPBD stretches at the same dual residual (Fig. 8)"
    runs = runs_of(files.get("cloth_stretch"), datasets=("final_positions", "distance_edges", "distance_rest_length"))
    if not runs:
        summary.not_run(claim, notes.get("cloth_stretch", "no results"))
        return
    for r in runs:
        if failed(r):
            summary.add(claim, f"{r['attrs'].get('solver')} max strain", "—", f"not run: {status_note(r)}")
            continue
        s, _, _ = xbruns.cloth_strains(r)
        a = r["attrs"]
        summary.add(claim, f"{a.get('solver')}: max / mean edge strain (length/rest − 1) after {a.get('frames')} frames "
                     f"({a.get('resolution')}², stop at dual residual {a.get('atol')})",
              "XPBD visibly stretched, global solve not", f"{s.max():.3g} / {s.mean():.3g}",
              f"{a.get('substeps_converged')}/{a.get('substeps_total')} substeps reached it; {a.get('status')}")
    if "cloth_stretch" in notes:
        summary.add(claim, "inputs", "—", f"partly run: {notes['cloth_stretch']}")
    plot(summary, "cloth_stretch.py", files["cloth_stretch"], os.path.join(out, "cloth_stretch.png"))


def claim_sweeps(summary, files, notes, out):
    claim = "θ_s sweep and stiffness sweep"
    for key, axis in (("theta", "amg.strength_threshold"), ("stiffness", "stiffness")):
        runs = runs_of(files.get(key), datasets=DATA)
        if not runs:
            summary.not_run(claim, f"{key}: " + notes.get(key, "no results"))
            continue
        for r in sorted(runs, key=lambda r: (r["attrs"]["solver"], float(r["attrs"].get(axis, 0)))):
            a = r["attrs"]
            if failed(r):
                summary.add(claim, f"{a['solver']}, {axis} = {fmt(float(a.get(axis)))}", "—", f"not run: {status_note(r)}")
                continue
            i2, t2 = xbruns.to_tolerance(r, 1e-2, metric="own")  # vbd, avbd: relative ‖∇E‖
            i4, t4 = xbruns.to_tolerance(r, 1e-4, metric="own")
            summary.add(claim, f"{a['solver']}, {axis} = {fmt(float(a.get(axis)))}: its / time to 1e-2, to 1e-4 ({tets(r)} tets)",
                  "θ_s “small, e.g. 0.25”" if key == "theta" else "—",
                  f"{fmt(i2)} / {fmt(t2)} s, {fmt(i4)} / {fmt(t4)} s", status_note(r))
        if key in notes:
            summary.add(claim, f"{key} inputs", "—", f"partly run: {notes[key]}")
        for metric in ("iterations_to_tolerance", "time_to_tolerance"):
            plot(summary, "sweep.py", files[key], os.path.join(out, f"{key}_{metric}.png"), ["--metric", metric, "--tol", "1e-2"])
        if key == "stiffness":
            plot(summary, "stability.py", files[key], os.path.join(out, "stiffness_stability.png"))


def claim_error_time(summary, files, notes, out):
    claim = "error against run time (Pareto view; no paper number)"
    runs = runs_of(files.get("error_time"), datasets=DATA + xbruns.REFERENCE_DATASETS)
    if not runs:
        summary.not_run(claim, notes.get("error_time", "no results"))
        return
    for r in runs:
        a = r["attrs"]
        if failed(r) or "position_error" not in r["data"]:
            summary.add(claim, f"{a.get('solver')}", "—", f"not run: {status_note(r)}")
            continue
        pe = np.asarray(r["data"]["position_error"])
        wt = np.asarray(r["data"]["wall_time"])
        hit = np.flatnonzero(pe <= 1e-3)
        trusted, why = xbruns.reference_trusted(r, 1e-3)
        time = (fmt(float(wt[hit[0]])) + " s" if len(hit) else "never") if trusted else why
        est = r["data"].get("reference/error_estimate")
        summary.add(claim, f"{a.get('solver')}: time to position error 1e-3; final error ({tets(r)} tets)", "—",
              f"{time}; {xbruns.error_text(float(pe[-1]), a)}",
              f"reference's own error estimate {fmt(float(np.max(est))) if est is not None and len(est) else '—'}")
    if "error_time" in notes:
        summary.add(claim, "inputs", "—", f"partly run: {notes['error_time']}")
    plot(summary, "error_time.py", files["error_time"], os.path.join(out, "error_time.png"))


def claim_profiles(summary, files, notes, out):
    # each claim under the authors' profile and under the true metric
    profile_claims.claim(summary, files, notes)


def claim_dual_primal(summary, files, notes, out):
    import dual_primal  # the claim's code lives in its own module (this one stays short)
    dual_primal.claim(summary, files, notes, out, GROUPS["dual_primal"])


def plot(summary, script, results, out, extra=()):
    r = subprocess.run([sys.executable, os.path.join(HERE, script), results, "-o", out] + list(extra),
                       capture_output=True, text=True)
    if r.returncode == 0:
        summary.figures.append(os.path.basename(out))
    else:
        summary.add("figures", script, "—", f"not drawn: {(r.stderr.strip().splitlines() or ['?'])[-1]}")


# Every claim, in the order of summary.md.
CLAIMS = (claim_squash, claim_scaling, claim_near_kernel, claim_setup_interval, claim_twist, claim_cloth,
          claim_sweeps, claim_error_time, claim_dual_primal, claim_profiles)
