#!/usr/bin/env python3
"""CI performance tracking: run, record, compare.

  perf.py run [--build DIR] [--short] [--baseline FILE] [--write-baseline] [--out FILE]
      Runs the deterministic metrics (xb_perf_metrics) and the Google Benchmark microbenchmarks
      (xb_microbench), writes results/perf/<git-sha>.json (benchmarks + deterministic metrics +
      machine description) and compares it with the committed baseline
      (results/baselines/perf.json). Exit 1 when a deterministic metric is outside its tolerance.
      --write-baseline: also (re)write the baseline on purpose, no comparison.
      --short: the CI gate's short form (small sizes only, short benchmark times).
  perf.py compare BASELINE CURRENT [--all]
      Compares two perf JSON files (or bare xb_perf_metrics outputs). Same exit code.

Gate: deterministic metrics fail when worse than their tolerance: iterations and outer
iterations +10 %, operator and grid complexity +2 %, AMG levels +10 %, a status that leaves
converged/ok, a system whose size changed, a metric that disappeared (unless its solver is not
available in this build). Counts of a run whose baseline status was not converged/ok are shown,
not gated. Timed metrics are read as ratios to the triad reference of the same
run; a ratio more than 25 % above the baseline's is flagged SLOWER but does not fail. The
benchmarks run single-threaded by default and the ratios are of CPU times: on a shared, loaded
machine wall-clock times of OpenMP teams vary several-fold, CPU times of one thread do not.
Kernel costs in SpMV units (a kernel's time over the SpMV of the same scene in the same run:
assembly, AMG setup/refresh, V-cycle, smoother sweeps, solves) are recorded and listed beside the
baseline's; a change is shown, never gated.
"""
import argparse
import datetime
import json
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from perf_measure import (TRIAD_PREFIX, git_info, machine_description, run_benchmarks,  # noqa: E402,F401
                          run_metrics, spmv_unit_ratios, timed_ratios, timing_field)
DEFAULT_BASELINE = os.path.join(ROOT, "results", "baselines", "perf.json")

# kind -> (relative tolerance on an increase, what it means)
TOLERANCES = {
    "iterations": 0.10,
    "outer_iterations": 0.10,
    "levels": 0.10,
    "operator_complexity": 0.02,
    "grid_complexity": 0.02,
}
TIME_TOLERANCE = 0.25
SPMV_UNIT_TOLERANCE = 0.5  # shown as "costlier" beyond this; report-only
GOOD_STATUS = {"converged", "ok"}


def spmv_unit_table(base, cur, out=sys.stdout):
    """Kernel costs in SpMV units, this run beside the baseline's (report-only, never a failure)."""
    base = base or {}
    cu, bu = cur.get("spmv_units", {}), base.get("spmv_units")
    if bu is None:  # a baseline recorded before the field: from its raw benchmarks
        bu = spmv_unit_ratios(base.get("google_benchmark"), base.get("timing", {}).get("field", "cpu_time"))
    if not cu:
        return
    print("\nkernel cost in SpMV units (time / SpMV time of the same scene, this run; report-only):", file=out)
    print(f"  {'kernel':<52s} {'baseline':>9s} {'current':>9s}  note", file=out)
    for k in sorted(cu):
        b = bu.get(k)
        note = ""
        if b:
            change = cu[k] / b - 1
            note = f"{change:+.0%}" + (" costlier" if change > SPMV_UNIT_TOLERANCE else "")
        print(f"  {k:<52s} {fmt(b) if b else '-':>9s} {cu[k]:9.3g}  {note}", file=out)


# ---------------------------------------------------------------------------------------- compare
def load(path):
    with open(path) as f:
        d = json.load(f)
    if "deterministic" not in d and "metrics" in d:  # a bare xb_perf_metrics output
        d = {"deterministic": d, "timed_ratios": {}}
    return d


def method_of(name):
    # linear/<scene>/<res>/<capture>/<solver>/<stat>, sim/<scene>/<res>/<method>/<stat>
    parts = name.split("/")
    return parts[-2] if len(parts) >= 2 else ""


def fmt(v):
    if isinstance(v, str):
        return v
    if v is None:
        return "-"
    if float(v).is_integer() and abs(v) < 1e15:
        return str(int(v))
    return f"{v:.4g}"


def compare(base, cur):
    """Rows (metric, kind, baseline, current, change, tolerance, verdict); verdict FAIL fails."""
    rows = []
    bm = base["deterministic"]["metrics"]
    cm = cur["deterministic"]["metrics"]
    unavailable = set(cur["deterministic"].get("unavailable_methods", []))
    for name, b in bm.items():
        kind = b["kind"]
        if kind == "info":
            continue
        if name not in cm:
            skipped = method_of(name) in unavailable
            rows.append((name, kind, fmt(b["value"]), "-", "", "", "skipped (unavailable)" if skipped else "FAIL missing"))
            continue
        bv, cv = b["value"], cm[name]["value"]
        if kind == "status":
            if bv == cv:
                verdict = "ok"
            elif bv in GOOD_STATUS and cv not in GOOD_STATUS:
                verdict = "FAIL"
            else:
                verdict = "changed"
            rows.append((name, kind, bv, cv, "", "", verdict))
            continue
        if kind == "size":
            rows.append((name, kind, fmt(bv), fmt(cv), "", "exact", "ok" if bv == cv else "FAIL"))
            continue
        tol = TOLERANCES.get(kind)
        # A run that did not converge in the baseline (breakdown, max_iterations) has counts
        # that measure where it stopped, not how fast it converged: shown, not gated.
        base_status = bm.get(name.rsplit("/", 1)[0] + "/status", {}).get("value", "ok")
        if tol is not None and base_status not in GOOD_STATUS:
            rows.append((name, kind, fmt(bv), fmt(cv), "", "", "ok" if bv == cv else f"changed (baseline {base_status})"))
            continue
        if tol is None or bv is None or cv is None:
            rows.append((name, kind, fmt(bv), fmt(cv), "", "", "ok" if bv == cv else "changed"))
            continue
        change = (cv - bv) / bv if bv else (0.0 if cv == bv else float("inf"))
        if cv > bv * (1 + tol) + 1e-12:
            verdict = "FAIL"
        elif cv < bv * (1 - tol) - 1e-12:
            verdict = "improved"
        else:
            verdict = "ok"
        rows.append((name, kind, fmt(bv), fmt(cv), f"{change:+.1%}", f"+{tol:.0%}", verdict))
    for name, c in cm.items():
        if name not in bm and c["kind"] != "info":
            rows.append((name, c["kind"], "-", fmt(c["value"]), "", "", "new"))
    # Timed: ratio to the triad of the same run, compared only when measured the same way.
    br, cr = base.get("timed_ratios", {}), cur.get("timed_ratios", {})
    if base.get("timing") != cur.get("timing"):
        br = {}
    for name in cr:
        if name not in br:
            continue
        change = cr[name] / br[name] - 1
        verdict = "SLOWER (flag)" if change > TIME_TOLERANCE else ("faster" if change < -TIME_TOLERANCE else "ok")
        rows.append((name, "time/triad", f"{br[name]:.4g}", f"{cr[name]:.4g}", f"{change:+.1%}",
                     f"+{TIME_TOLERANCE:.0%}", verdict))
    return rows


def print_table(rows, show_all, out=sys.stdout):
    # Timed "faster" rows are listed with --all only: on a shared machine the triad itself moves.
    shown = [r for r in rows if show_all or r[6] not in ("ok", "faster")]
    head = ("metric", "kind", "baseline", "current", "change", "tol", "verdict")
    if shown:
        w = [max(len(str(r[i])) for r in shown + [head]) for i in range(7)]
        line = "  ".join(h.ljust(w[i]) for i, h in enumerate(head))
        print(line, file=out)
        print("-" * len(line), file=out)
        for r in shown:
            print("  ".join(str(v).ljust(w[i]) for i, v in enumerate(r)), file=out)
    n_det = sum(1 for r in rows if r[1] != "time/triad")
    n_time = len(rows) - n_det
    fails = [r for r in rows if r[6].startswith("FAIL")]
    flagged = [r for r in rows if r[6].startswith("SLOWER")]
    faster = [r for r in rows if r[6] == "faster"]
    print(f"\nperf gate: {n_det} deterministic metrics, {len(fails)} outside tolerance; "
          f"{n_time} timed ratios, {len(flagged)} flagged slower (not failing), {len(faster)} faster", file=out)
    if fails:
        print("perf gate: FAILED: " + ", ".join(r[0] for r in fails), file=out)
    else:
        print("perf gate: passed", file=out)
    return 1 if fails else 0


def solver_ratio_table(cur, out=sys.stdout):
    """Each solver's times over the triad's, per captured system: setup from scratch (structure),
    values-only setup, solve, and the full solve from scratch (structure setup + solve)."""
    ratios = cur.get("timed_ratios", {})
    keys = {}
    for k in ratios:
        m = re.match(r"(setup_structure|setup_values|solve)/([^/]+)/(.+)$", k)
        if m:
            keys.setdefault((m.group(3), m.group(2)), {})[m.group(1)] = ratios[k]
    if not keys:
        return
    field = cur.get("timing", {}).get("field", "time")
    nan = float("nan")
    print(f"\nsolver {field} / triad {field} (this run; full = setup_structure + solve):", file=out)
    print(f"  {'system':<18s} {'solver':<11s} {'setup_structure':>15s} {'setup_values':>13s} {'solve':>10s} "
          f"{'full':>10s}", file=out)
    for (system, solver), v in sorted(keys.items()):
        full = v.get("setup_structure", nan) + v.get("solve", nan)
        print(f"  {system:<18s} {solver:<11s} {v.get('setup_structure', nan):15.3f} "
              f"{v.get('setup_values', nan):13.3f} {v.get('solve', nan):10.3f} {full:10.3f}", file=out)


# ---------------------------------------------------------------------------------------- main
def cmd_run(a):
    if a.threads < 1:
        sys.exit("perf: --threads must be >= 1")
    build = os.path.abspath(a.build)
    git = git_info()
    det = run_metrics(build)
    gb = run_benchmarks(build, a.short, a.threads, a.filter) if not a.no_bench else None
    field = timing_field(a.threads)
    record = {
        "schema": "xpbd-bench perf 1",
        "created": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "git": git,
        "short": bool(a.short),
        "machine": machine_description(build),
        "timing": {"threads": a.threads, "field": field},
        "deterministic": det,
        "timed_ratios": timed_ratios(gb, field),
        "spmv_units": spmv_unit_ratios(gb, field),
        "google_benchmark": gb,
    }
    out = a.out or os.path.join(ROOT, "results", "perf", f"{git['sha']}.json")
    os.makedirs(os.path.dirname(out), exist_ok=True)
    with open(out, "w") as f:
        json.dump(record, f, indent=1)
    print(f"perf: wrote {os.path.relpath(out, ROOT)}")
    if a.write_baseline:
        if a.short:
            sys.exit("perf: a baseline is written from a full run, not --short")
        os.makedirs(os.path.dirname(a.baseline), exist_ok=True)
        with open(a.baseline, "w") as f:
            json.dump(record, f, indent=1)
        print(f"perf: wrote the baseline {os.path.relpath(a.baseline, ROOT)}")
        solver_ratio_table(record)
        spmv_unit_table(None, record)
        return 0
    if not os.path.exists(a.baseline):
        sys.exit(f"perf: no baseline at {a.baseline} (make perf-baseline writes it)")
    rows = compare(load(a.baseline), record)
    base = load(a.baseline)
    rc = print_table(rows, a.all)
    solver_ratio_table(record)
    spmv_unit_table(base, record)
    return rc


def cmd_compare(a):
    base, cur = load(a.baseline), load(a.current)
    rc = print_table(compare(base, cur), a.all)
    spmv_unit_table(base, cur)
    return rc


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run", help="measure, record and compare with the baseline")
    r.add_argument("--build", default=os.path.join(ROOT, "build"))
    r.add_argument("--short", action="store_true", help="CI short form: small sizes, short times")
    r.add_argument("--baseline", default=DEFAULT_BASELINE)
    r.add_argument("--write-baseline", action="store_true")
    r.add_argument("--out", help="default: results/perf/<git-sha>.json")
    r.add_argument("--filter", help="Google Benchmark regex (the triad is always kept)")
    r.add_argument("--no-bench", action="store_true", help="deterministic metrics only")
    r.add_argument("--threads", type=int, default=1,
                   help="OpenMP threads of the benchmarks (1: ratios of CPU times; more: of wall times)")
    r.add_argument("--all", action="store_true", help="show every row, not only what changed")
    r.set_defaults(fn=cmd_run)
    c = sub.add_parser("compare", help="compare two perf JSON files")
    c.add_argument("baseline")
    c.add_argument("current")
    c.add_argument("--all", action="store_true")
    c.set_defaults(fn=cmd_compare)
    a = ap.parse_args(argv)
    if getattr(a, "filter", None):
        a.filter = f"({a.filter})|^{re.escape(TRIAD_PREFIX)}"
    return a.fn(a)


if __name__ == "__main__":
    sys.exit(main())
