"""The race's rules (plots/race_rules.py), shared by its driver (figures/race.py) and its summary
(plots/race.py): the time to a position error, a run that never reaches it, a reference that did
not converge, the best entry, failed runs, and a small race run end to end with the real binary."""
import math
import os
import subprocess
import sys

import numpy as np

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
sys.path.insert(0, os.path.join(ROOT, "plots"))
import race  # noqa: E402
import race_rules as rules  # noqa: E402
import xbruns  # noqa: E402


def fake(errors=(1.0, 0.1, 0.005, 5e-5), wall=3.0, status="ok", reference="converged", rows=100, substeps=None,
         estimate=1e-9, **attrs):
    """A run as xbruns.load gives it: attributes and datasets. `substeps`: the substep of each entry
    (default: one substep); `reference`: the status of each substep's reference (its success as the
    harness writes it: converged or rounding_floor); `estimate`: its certificate's error estimate
    (inf: not certified)."""
    n = len(errors)
    sub = np.zeros(n, int) if substeps is None else np.asarray(substeps)
    it = np.concatenate([np.arange(np.sum(sub == k)) for k in np.unique(sub)])
    refs = [reference] if isinstance(reference, str) else list(reference)
    m = len(refs)
    data = {"iteration": it, "frame": np.zeros(n, int), "substep": sub, "wall_time": np.linspace(0, wall, n),
            "position_error": np.asarray(errors, float), "linear_iterations": np.full(n, 5.0),
            "reference/status": np.array(refs), "reference/relative_energy_gradient": np.full(m, 2.5e-4),
            "reference/success": np.array([int(r in ("converged", "rounding_floor")) for r in refs]),
            "reference/error_estimate": np.full(m, estimate),
            "reference/certified": np.full(m, int(math.isfinite(estimate))),
            "reference/certified_threshold": np.full(m, 100 * estimate),
            "reference/certificate_note": np.array(["" if math.isfinite(estimate) else "the last step did not contract"] * m)}
    return {"attrs": {"status": status, "wall_time": wall, "outer_iterations": n - 1, "rows": rows, **attrs}, "data": data}


def failed():
    return {"attrs": {"status": "failed", "exit": 137, "message": "Killed", "wall_time": 3.0}}


def test_time_to_a_position_error_is_the_first_entry_at_or_below_it():
    r = fake(errors=(1.0, 0.1, 0.01, 5e-5), wall=3.0)
    assert rules.time_to(r, 1e-2) == 2.0  # at the threshold counts
    assert rules.time_to(r, 1e-4) == 3.0
    assert rules.verdict(r, 1e-1) == (1.0, "")
    # Only the judged substep (the run's first): a later substep's smaller error does not count.
    two = fake(errors=(1.0, 0.5, 1.0, 1e-6), wall=3.0, substeps=(0, 0, 1, 1), reference=("converged", "converged"))
    assert math.isnan(rules.time_to(two, 1e-4)) and rules.smallest_error(two) == 0.5


def test_a_run_that_never_reaches_it_says_how_close_it_came():
    r = fake(errors=(1.0, 0.3, 0.25, 0.26))
    assert rules.verdict(r, 1e-2) == (None, rules.NEVER)
    assert rules.smallest_error(r) == 0.25
    e = dict(outer="xpbd", linear="cholmod", forcing="fixed", run=r)
    assert race.cell(e, 1e-2) == "— (0.25)"


def test_a_reference_that_did_not_converge_times_nothing():
    r = fake(errors=(1.0, 1e-3, 1e-6), reference="stagnated")
    assert rules.verdict(r, 1e-2) == (None, rules.UNCONVERGED)
    assert math.isnan(rules.time_to(r, 1e-4))
    e = dict(outer="newton", linear="mgpbd", forcing="eisenstat_walker", run=r)
    assert race.cell(e, 1e-2) == "— (reference unconverged)"
    assert race.reference_text(r) == "stagnated at ‖∇E‖ 0.00025 of its start"
    # A run without a reference, and a process that left no run, are not timed either.
    plain = fake()
    del plain["data"]["position_error"]
    assert rules.verdict(plain, 1e-2) == (None, rules.NO_REFERENCE)
    assert rules.verdict(failed(), 1e-2) == (None, rules.NO_DATA)


def test_a_reference_not_fine_enough_times_no_threshold_below_100_times_its_error():
    """A reference whose certificate bounds its own error by 1e-5 judges 1e-2 (and 1e-3) but not
    1e-4: the race says so and times nothing there; one without a certificate judges nothing."""
    r = fake(errors=(1.0, 1e-3, 1e-6), wall=2.0, estimate=1e-5)
    assert rules.verdict(r, 1e-2) == (1.0, "") and rules.verdict(r, 1e-3) == (1.0, "")
    assert rules.verdict(r, 1e-4) == (None, rules.NOT_FINE)
    e = dict(outer="newton", linear="mgpbd", forcing="fixed", run=r)
    assert race.cell(e, 1e-4) == "— (reference not fine enough)"
    assert race.reference_text(r) == "converged, certified: error ≤ 1e-05 (trusted to 0.001)"
    assert rules.best([r, fake(errors=(1.0, 1e-3, 1e-6), wall=4.0)], [1e-2, 1e-4])["attrs"]["wall_time"] == 4.0
    bare = fake(estimate=math.inf)
    assert rules.verdict(bare, 1e-2) == (None, rules.UNCERTIFIED)
    assert "the last step did not contract" in race.reference_text(bare)
    # Printing a run's error: only where every substep's reference can judge it.
    a = {"reference_substeps_unconverged": 0, "reference_certified_threshold": 1e-3}
    assert xbruns.error_text(2e-3, a) == "0.002"
    assert xbruns.error_text(2e-4, a) == "reference not fine enough (it judges ≥ 0.001)"
    assert xbruns.error_text(2e-4, {**a, "reference_substeps_unconverged": 1}) == "0.0002 (reference unconverged)"


def test_best_reaches_the_smallest_threshold_first_then_the_next_then_the_error():
    ths = [1e-2, 1e-4]
    slow, quick = fake(wall=6.0), fake(wall=3.0)
    never_small = fake(errors=(1, 1e-3, 5e-4), wall=0.5)
    assert rules.best([slow, never_small, quick, failed()], ths) is quick
    near, far = fake(errors=(1, 0.3, 0.2)), fake(errors=(1, 0.5, 0.4), wall=0.1)
    assert rules.best([far, near], ths) is near
    # Neither reaches 1e-4: the one that reaches 1e-2 first.
    early_big, late_small = fake(errors=(1, 5e-3, 4e-3), wall=1.0), fake(errors=(1, 0.5, 5e-3), wall=4.0)
    assert rules.best([late_small, early_big], ths) is early_big
    assert rules.first_to([slow, quick], 1e-4) is quick and rules.first_to([near, far], 1e-2) is None
    assert rules.best([failed()], ths)["attrs"]["status"] == "failed"


def test_the_anchor_frame_bounds_the_budget():
    anchor = fake(wall=6.0, errors=(1, 0.5, 0.4, 0.3, 0.3, 0.3, 0.3))  # 6 outer iterations, 1 s each
    assert rules.anchor_frame(anchor, 2) == 2.0
    assert rules.anchor_frame(failed(), 2) is None


SPEC = {"thresholds": [1e-2, 1e-4],
        "outer": {"xpbd": {"label": "XPBD"}, "newton": {"label": "Newton"}},
        "linear": {"cholmod": {}, "mgpbd": {}},
        "scenes": {"squash": {"sizes": [{"label": "s"}, {"label": "m"}]}}}


def entry(outer, linear, forcing, run):
    return dict(outer=outer, linear=linear, forcing=forcing, run=run)


def test_summary_and_readme_table(tmp_path):
    small = [entry("xpbd", "cholmod", "fixed", fake(errors=(1, 0.4, 0.3))),
             entry("xpbd", "mgpbd", "eisenstat_walker", fake(errors=(1, 0.35, 0.29))),
             entry("newton", "cholmod", "fixed", fake(wall=2.0)),
             entry("newton", "mgpbd", "eisenstat_walker", fake(wall=1.0)),
             entry("newton", "mgpbd", "fixed", fake(wall=4.0))]
    medium = [entry("xpbd", "cholmod", "fixed", fake(rows=400, reference="max_iterations")),
              entry("newton", "mgpbd", "eisenstat_walker", failed())]
    sc = race.Scene("squash", {"m": medium, "s": small}, SPEC)
    assert sc.order == ["s", "m"] and sc.outers == ["xpbd", "newton"]
    assert sc.pair_best("s")[("newton", "mgpbd")]["forcing"] == "eisenstat_walker"
    text = race.summary([sc])
    head = text[text.index("## Each outer method"):text.index("## squash")]
    # One row per size; each cell the time to every threshold, the linear method once.
    assert "| squash s (100) | — (0.29) | 0.67 / 1.00 (mgpbd (EW)) |" in head, head
    assert "| squash m (400) | — (reference unconverged) | — (failed) |" in head, head
    medium_text = text[text.index("### m"):]
    assert "failed (exit 137: Killed)" in medium_text and "max_iterations at ‖∇E‖" in medium_text
    readme = tmp_path / "README.md"
    readme.write_text(f"intro\n{race.README_BEGIN}\nold table\n{race.README_END}\nrest\n")
    race.write_readme(str(readme), [sc])
    new = readme.read_text()
    assert "old table" not in new and "| squash s (100) | — (0.29) |" in new and new.endswith(f"{race.README_END}\nrest\n")
    # Different linear methods at different thresholds are named per threshold.
    mixed = [entry("newton", "cholmod", "fixed", fake(errors=(1, 5e-3, 4e-3, 4e-3), wall=0.3)),
             entry("newton", "mgpbd", "fixed", fake(errors=(1, 0.5, 0.1, 1e-5), wall=3.0))]
    line = race.outer_cell(race.Scene("squash", {"s": mixed}, SPEC), "s", "newton")
    assert line == "0.10 (cholmod) / 3.00 (mgpbd)", line


def test_a_small_race_end_to_end(bench, tmp_path):
    """figures/race.py with the real binary: every entry runs with --reference, Newton's keeps its
    profile's stop test, the summary times the position error, and a process that failed (an
    invalid value) has its row."""
    spec = tmp_path / "race.toml"
    spec.write_text('''thresholds = [1e-2, 1e-4]
forcing = ["fixed"]
time_budget = 60
overrun = 2
[outer.xpbd]
label = "XPBD"
[outer.newton]
label = "Newton"
profile = "newton"
own_stop = true
[linear.cholmod]
solver = "cholmod"
forcing = false
[linear.jacobi-pcg]
solver = "jacobi-pcg"
[linear.broken]
solver = "cholmod"
set = { "cholmod.refactor" = "sometimes" }
[linear.xpbd-gs]
solver = "xpbd-gs"
local = true
[scenes.bar]
scene = "bar_hang"
set = { rtol = 0, atol = 0, max_iterations = 4, resolution = 2 }
quick_size = "r2"
sizes = [ { label = "r2" } ]
''')
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, os.path.join(ROOT, "figures", "race.py"), "--bench", bench, "--spec", str(spec),
                           "--out", str(out), "--quick", "--quiet"], capture_output=True, text=True, timeout=400)
    assert done.returncode == 0, done.stdout + done.stderr
    every = [line for line in done.stdout.splitlines() if line.startswith("race: ") and " run " in line]
    # The size's reference pass first (one sweep), then the entries, every one reading its file.
    assert "--solver xpbd-jacobi" in every[0] and "--set max_iterations=1" in every[0]
    cmds = every[1:]
    ref = str(out / "data" / "bar" / "r2" / "_reference" / "reference.h5")
    assert cmds and all(f"--reference-file {ref}" in c and "--memory-limit" in c for c in every)
    assert "--set max_iterations=8" in cmds[0] and "cholmod" in cmds[0]  # the anchor first, at overrun × 4
    newton = [c for c in cmds if "--profile newton" in c]
    assert len(newton) == 3 and not any("rtol=" in c or "max_iterations=" in c for c in newton)
    assert not any("xpbd-gs" in c and "--profile" in c for c in cmds)  # a sweep runs only under XPBD
    summary = (out / "summary.md").read_text()
    assert "| Newton | cholmod | fixed |" in summary and "converged, certified: error ≤" in summary
    assert "reference computed once" in summary and "5 of 5 entries read the size's stored reference" in summary
    assert (out / "plan.txt").exists() and "plan:" in done.stdout
    assert "| XPBD | broken | fixed |" in summary and "failed (exit" in summary
    assert (out / "race_bar.png").exists() and (out / "timings.tsv").exists()
