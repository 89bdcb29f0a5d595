#!/usr/bin/env python3
"""The "dual vs primal" claim of `make figures`: every global method in both forms of
the linear step, across resolution, on cloth_hang and the 5%-stretched bar_hang.

usage: python3 plots/dual_primal.py RESULTS.h5 [RESULTS2.h5 ...] [-o OUT.png]

Reads sweeps of figures/dual_primal.toml and figures/dual_primal_bar.toml (runs carry `form_used`
and per-outer-iteration linear_iterations / linear_setup_time / linear_solve_time). Per run it
averages over the run's linear solves (outer iterations > 0); both forms stop every solve on the
dual residual ‖b − AΔλ‖ ≤ linear.tol·‖b‖, so iterations and times compare directly. figures.py
calls `claim` (summary rows, the "dual vs primal" section, the figure); run alone, this script
draws the figure and prints the table and the verdicts.
"""
import argparse
import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import xbruns  # noqa: E402

DATA = ("frame", "iteration", "linear_iterations", "linear_setup_time", "linear_solve_time",
        "linear_relative_residual", "step_time")
METHOD_ORDER = ["jacobi-pcg", "cg", "mgpbd", "cholmod", "hypre", "muelu"]
COLOURS = {"jacobi-pcg": "#1f77b4", "cg": "#17becf", "mgpbd": "#d62728", "cholmod": "#2ca02c",
           "hypre": "#9467bd", "muelu": "#ff7f0e"}
# A solve whose recomputed dual residual is above this multiple of linear.tol did not reach the
# tolerance (the solvers judge their own tracked residual, which can differ in the last digit).
TOL_SLACK = 2.0


def _num(v, default=math.nan):
    x = xbruns.as_number(v)
    return default if x is None else x


def measure(run):
    """One row of the table: a dict with the run's size, method, form, means and status text."""
    a, d = run["attrs"], run["data"]
    form = str(a.get("form_used") or "")
    if form in ("", "none"):  # a run that failed before choosing reports the form it was asked for
        form = str(a.get("form", "?"))
    row = dict(scene=str(a.get("scene")), resolution=int(_num(a.get("resolution"), 0)), rows=_num(a.get("rows")),
               primal_rows=_num(a.get("primal_rows")), method=str(a.get("solver")), form=form,
               tol=_num(a.get("linear.tol")), per_solve=([], []), solves=0, iterations=math.nan, time=math.nan,
               step=math.nan, unconverged=0)
    it = np.asarray(d.get("iteration", []))
    m = it > 0  # iteration 0 is the predicted state: no solve before it
    if "frame" in d:
        m &= np.asarray(d["frame"]) == 0
    if "linear_iterations" in d and m.any():
        li = np.asarray(d["linear_iterations"], dtype=float)[m]
        st = (np.asarray(d["linear_setup_time"], dtype=float) + np.asarray(d["linear_solve_time"], dtype=float))[m]
        rel = np.asarray(d["linear_relative_residual"], dtype=float)[m]
        tol = _num(a.get("linear.tol"), 1e-8)
        cap = _num(a.get("linear.max_iterations"), math.inf)
        row.update(per_solve=(li.tolist(), st.tolist()), solves=int(m.sum()), iterations=float(li.mean()),
                   time=float(st.mean()),
                   step=float(np.asarray(d["step_time"], dtype=float)[m].mean()) if "step_time" in d else math.nan,
                   unconverged=int(np.sum((rel > TOL_SLACK * tol) | ~np.isfinite(rel) | (li >= cap))))
    row["status"] = status_text(a, row)
    row["ok"] = row["solves"] > 0 and row["unconverged"] == 0 and a.get("status") in ("ok", "max_iterations")
    return row


def status_text(a, row):
    """ok, or what went wrong, in a few words (the table's last column)."""
    s = str(a.get("status", "?"))
    parts = []
    # rtol = atol = 0 in the specs: max_iterations is the intended end of every run.
    if s not in ("ok", "max_iterations"):
        msg = short_message(a.get("message", ""))
        parts.append(f"{s} after {row['solves']} solve(s): {msg}" if msg else f"{s} after {row['solves']} solve(s)")
    if row["unconverged"]:
        parts.append(f"{row['unconverged']} of {row['solves']} solves did not reach linear.tol")
    if not parts and row["solves"] == 0:
        parts.append("no solve recorded")
    return "; ".join(parts) if parts else "ok"


def short_message(message, width=140):
    """A library's multi-line message in one cell: Trilinos puts the sentence that says what went
    wrong last and the source location first, so those two, in that order."""
    lines = [" ".join(x.split()) for x in str(message).splitlines() if x.strip()]
    if len(lines) > 1:
        text = f"{lines[-1]} ({os.path.basename(lines[0].rstrip(':'))})"
    else:
        text = lines[0] if lines else ""
    return text if len(text) <= width else text[:width - 1] + "…"


def load_rows(paths):
    rows = []
    for p in paths:
        if p and os.path.exists(p):
            rows += [measure(r) for r in xbruns.load(p, datasets=DATA)]
    return sorted(rows, key=lambda r: (r["scene"], 0 if math.isnan(r["rows"]) else r["rows"], _order(r["method"]),
                                       r["form"]))


def _order(method):
    return METHOD_ORDER.index(method) if method in METHOD_ORDER else len(METHOD_ORDER)


def _e(v, digits=3):
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "—"
    if float(v).is_integer() and abs(v) < 1e7:
        return str(int(v))
    return f"{v:.{digits}g}"


def table(rows):
    """The summary section's Markdown table."""
    out = ["| scene | resolution | rows (dual) | rows (K) | method | form | mean linear iterations | "
           "mean setup+solve (s) | mean step (s) | solves | status |",
           "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        cells = [r["scene"], r["resolution"], _e(r["rows"]), _e(r["primal_rows"]), r["method"], r["form"],
                 _e(round(r["iterations"], 1)) if not math.isnan(r["iterations"]) else "—",
                 _e(r["time"]), _e(r["step"]), r["solves"], r["status"]]
        out.append("| " + " | ".join(str(c).replace("|", "/") for c in cells) + " |")
    return "\n".join(out) + "\n"


def _pick(rows, scene, method, form, resolution):
    for r in rows:
        if (r["scene"], r["method"], r["form"], r["resolution"]) == (scene, method, form, resolution):
            return r
    return None


def _solved(r):
    return r is not None and r["solves"] > 0


def verdicts(rows):
    """Per scene, (scene, largest resolution, text, iteration ratio or NaN), all computed from the rows.

    The ratio is primal mgpbd's mean iterations over dual jacobi-pcg's at the largest resolution
    where both have solves; the text also compares primal mgpbd's time with the best dual method's.
    """
    out = []
    for scene in sorted({r["scene"] for r in rows}):
        res = sorted({r["resolution"] for r in rows if r["scene"] == scene})
        both = [k for k in res if _solved(_pick(rows, scene, "mgpbd", "primal", k))
                and _solved(_pick(rows, scene, "jacobi-pcg", "dual", k))]
        top = res[-1] if res else None
        pm_top = _pick(rows, scene, "mgpbd", "primal", top)
        if not both:
            why = pm_top["status"] if pm_top else "no primal mgpbd run"
            out.append((scene, top, f"{scene}: no size where both primal mgpbd and dual jacobi-pcg solved "
                                    f"(primal mgpbd at resolution {top}: {why})", math.nan))
            continue
        k = both[-1]
        p, q = _pick(rows, scene, "mgpbd", "primal", k), _pick(rows, scene, "jacobi-pcg", "dual", k)
        # Over the outer iterations both runs reached: later solves differ from the first (the bar's
        # get harder), so a run that ended early is compared on its own solves only.
        n = min(p["solves"], q["solves"])
        its_p, its_q = np.mean(p["per_solve"][0][:n]), np.mean(q["per_solve"][0][:n])
        ratio = its_p / its_q
        duals = [r for r in rows if r["scene"] == scene and r["resolution"] == k and r["form"] == "dual" and r["ok"]]

        def first_n(r):  # setup+solve time over the same solves
            return float(np.mean(r["per_solve"][1][:n]))

        best = min(duals, key=first_n) if duals else None
        text = (f"{scene} resolution {k} ({_e(p['rows'])} dual rows): primal mgpbd {_e(round(its_p, 1))} "
                f"iterations per solve = {ratio:.2g}× dual jacobi-pcg's {_e(round(its_q, 1))}")
        if n < max(p["solves"], q["solves"]):
            text += f" (first {n} solve(s) of each)"
        if best:
            text += (f"; its setup+solve {_e(first_n(p))} s = {first_n(p) / first_n(best):.2g}× the best dual "
                     f"method's ({best['method']}, {_e(first_n(best))} s)")
        if p["status"] != "ok":
            text += f" [primal mgpbd: {p['status']}]"
        if k != top:
            text += f" [largest size {top} not comparable: primal mgpbd {pm_top['status'] if pm_top else 'missing'}]"
        out.append((scene, k, text, ratio))
    return out


def growth(rows, scene, method="mgpbd", form="primal"):
    """(first resolution, last resolution, mean iterations there, solves compared) of a method × form
    over a scene's sizes, both means over the same first solves (a run may have ended early)."""
    pts = sorted((r["resolution"], r) for r in rows
                 if (r["scene"], r["method"], r["form"]) == (scene, method, form) and r["solves"])
    if len(pts) < 2:
        return None
    (k0, r0), (k1, r1) = pts[0], pts[-1]
    n = min(r0["solves"], r1["solves"])
    return k0, k1, float(np.mean(r0["per_solve"][0][:n])), float(np.mean(r1["per_solve"][0][:n])), n


def draw(rows, out):
    """Two columns (iterations, setup+solve time per solve) × one row per scene, log-log against the
    dual rows; colour per method, dual dashed, primal solid; a cross over a point whose solves did
    not all reach linear.tol or whose run ended early."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker  # noqa: F401 (NullLocator below)
    scenes = sorted({r["scene"] for r in rows})
    fig, axes = plt.subplots(len(scenes), 2, figsize=(13, 4.3 * len(scenes)), squeeze=False)
    for i, scene in enumerate(scenes):
        sr = [r for r in rows if r["scene"] == scene and r["solves"]]
        for method in sorted({r["method"] for r in sr}, key=_order):
            for form, ls, mk in (("dual", "--", "o"), ("primal", "-", "s")):
                pts = sorted((r for r in sr if r["method"] == method and r["form"] == form), key=lambda r: r["rows"])
                if not pts:
                    continue
                x = [r["rows"] for r in pts]
                for j, (key, yl) in enumerate((("iterations", "mean linear iterations per solve"),
                                               ("time", "mean setup + solve time per solve (s)"))):
                    ax = axes[i][j]
                    ax.loglog(x, [max(r[key], 1e-5) for r in pts], ls=ls, marker=mk, ms=4,
                              color=COLOURS.get(method, "k"), label=f"{method} {form}")
                    bad = [r for r in pts if not r["ok"]]
                    if bad:
                        ax.loglog([r["rows"] for r in bad], [max(r[key], 1e-5) for r in bad], ls="none", marker="x",
                                  ms=10, color="k")
                    ax.set_ylabel(yl)
        tol = ", ".join(sorted({_e(r["tol"]) for r in rows if r["scene"] == scene}))
        sizes = sorted({r["rows"] for r in sr})
        for j in range(2):
            ax = axes[i][j]
            # ticks at the measured sizes: matplotlib's log ticks collide on a narrow range
            ax.set_xticks(sizes, [f"{s / 1e3:.3g}K" for s in sizes])
            ax.xaxis.set_minor_locator(matplotlib.ticker.NullLocator())
            ax.set_xlabel("dual rows (constraints)")
            ax.set_title(f"{scene}: {'iterations' if j == 0 else 'time'} per solve to dual rel. residual {tol}",
                         fontsize=10)
            ax.grid(True, which="both", alpha=0.3)
        axes[i][1].legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    fig.suptitle("dual (A Δλ = b, dashed) vs primal (K Δx = Jᵀα̃⁻¹b, solid); "
                 "× = did not reach tol / run ended early", fontsize=10)
    fig.tight_layout()
    xbruns.save(fig, out)


def claim(S, files, notes, out, keys):
    """figures.py's claim: summary rows, the "dual vs primal" section and the figure (S: figures.Summary)."""
    claim = "dual vs primal"
    rows = load_rows([files.get(k) for k in keys])
    for k in keys:
        if k in notes:
            S.add(claim, f"inputs of {k}", "—", f"{'partly run' if rows else 'not run'}: {notes[k]}")
    if not rows:
        if not any(k in notes for k in keys):
            S.not_run(claim, "no results")
        return
    # The primal form's targets, from a scipy/pyamg prototype on the same kinds of system.
    target = {"cloth_hang": "≤ 0.1 (prototype, cloth 100²: 33 / 826 = 0.04)",
              "bar_hang": "≤ 0.2 (prototype, stretched bunny: 157 / 1275 = 0.12)"}
    found = verdicts(rows)
    for scene, k, text, ratio in found:
        S.add(claim, f"{scene}: primal mgpbd / dual jacobi-pcg iterations per solve at resolution {k}",
              target.get(scene, "—"), _e(ratio), text)
    g = growth(rows, "bar_hang")
    if g:
        S.add(claim, f"bar_hang: primal mgpbd iterations per solve, resolution {g[0]} → {g[1]} (first {g[4]} solves)",
              "within ±30% as resolution doubles twice",
              f"{_e(round(g[2], 1))} → {_e(round(g[3], 1))} ({(g[3] / g[2] - 1) * 100:+.0f}%)")
    scenes = sorted({r["scene"] for r in rows})
    per_run = ", ".join(f"{s}: {max(r['solves'] for r in rows if r['scene'] == s)}" for s in scenes)
    tols = ", ".join(sorted({_e(r["tol"]) for r in rows}))
    text = ("Every global method in both forms, one frame, each solve from Δλ = 0 to the dual relative "
            f"residual `linear.tol` = {tols} (specs " + ", ".join(f"`figures/{k}.toml`" for k in keys) + "). "
            f"Means over each run's linear solves (one per outer iteration; at most {per_run}). "
            "setup+solve is the solver's "
            "`linear_setup_time + linear_solve_time`: for the primal form it includes assembling K and "
            "recovering Δλ, for the dual form it excludes assembling A; step time includes every assembly.\n\n"
            + table(rows) + "\nVerdict: " + " — ".join(v[2] for v in found) + ".\n")
    S.sections.append(("dual vs primal", text))
    draw(rows, os.path.join(out, "dual_primal.png"))
    S.figures.append("dual_primal.png")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("results", nargs="+")
    ap.add_argument("-o", "--out", default=None)
    args = ap.parse_args()
    rows = load_rows(args.results)
    if not rows:
        sys.exit("dual_primal: no runs in " + ", ".join(args.results))
    draw(rows, args.out or xbruns.default_out(args.results[0], "dual_primal"))
    print(table(rows))
    for v in verdicts(rows):
        print(v[2])


if __name__ == "__main__":
    main()
