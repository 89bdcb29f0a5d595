"""The race's rules (plots/race_rules.py), shared by its driver (figures/race.py) and its summary
(plots/race.py): a run's form, the target, failed runs, the lagged factor's note, and a small race
run end to end with the real binary."""
import os
import subprocess
import sys

import numpy as np
import pytest

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
sys.path.insert(0, os.path.join(ROOT, "plots"))
import race  # noqa: E402
import race_rules as rules  # noqa: E402


def fake(status="ok", wall=1.0, residuals=(1.0, 0.5, 0.1), rows=100, **attrs):
    """A run as xbruns.load gives it: attributes and the first substep's datasets."""
    n = len(residuals)
    data = {"iteration": np.arange(n), "frame": np.zeros(n, int), "substep": np.zeros(n, int),
            "wall_time": np.linspace(0, wall, n), "relative_dual_residual": np.asarray(residuals, float),
            "linear_iterations": np.full(n, 5.0)}
    return {"attrs": {"status": status, "wall_time": wall, "outer_iterations": n - 1, "rows": rows,
                      "relative_dual_residual": residuals[-1], **attrs}, "data": data}


def failed():
    return {"attrs": {"status": "failed", "exit": 137, "message": "Killed", "wall_time": 3.0}}


def test_form_is_the_finished_one_faster_per_outer_iteration():
    assert rules.choose_form({"dual": fake(wall=1.0), "primal": fake(wall=2.0)}) == "dual"
    # A faster run that broke down does not win (the plot used to ignore the status).
    assert rules.choose_form({"dual": fake("breakdown", wall=0.1), "primal": fake(wall=2.0)}) == "primal"
    assert rules.choose_form({"dual": fake("max_iterations", wall=1.0), "primal": fake(wall=2.0)}) == "dual"
    # A run out of time measured its pace (a breakdown or a divergence did not).
    assert rules.choose_form({"dual": fake("timeout", wall=1.0), "primal": fake(wall=2.0)}) == "dual"
    # Neither finished: primal (the driver's fallback, and now the plot's).
    assert rules.choose_form({"dual": fake("diverged"), "primal": failed()}) == "primal"
    assert rules.choose_form({"dual": None, "primal": None}) == "primal"


def test_target_only_from_a_finished_exact_run():
    assert rules.target(fake(residuals=(1, 0.2, 0.07))) == pytest.approx(0.07)
    assert np.isnan(rules.target(fake("breakdown", residuals=(1, 0.2, 0.07))))
    assert np.isnan(rules.target(failed()))
    r = fake(residuals=(1, 0.5, 0.104, 0.09), wall=3.0)
    assert rules.time_to(r, 0.1) == pytest.approx(2.0)  # 0.104 is within 5 % of 0.1
    assert np.isnan(rules.time_to(r, float("nan")))


def test_best_reaches_the_target_first():
    slow, quick, broke = fake(wall=4.0, residuals=(1, 0.3, 0.1)), fake(wall=1.0, residuals=(1, 0.3, 0.1)), \
        fake("diverged", wall=0.1, residuals=(1, 5.0))
    assert rules.best([slow, broke, quick], 0.1) is quick
    assert rules.best([broke, fake(wall=1.0, residuals=(1, 0.5))], 0.1)["attrs"]["status"] == "ok"


def entry(method, form, forcing, run):
    return dict(method=method, form=form, forcing=forcing, run=run)


SPEC = {"methods": {"cholmod": {}, "mgpbd": {}, "mgpbd-double": {"variant_of": "mgpbd"}, "cholmod-lagged": {}},
        "scenes": {"squash": {"sizes": [{"label": "s"}, {"label": "m"}]}}}


def scene():
    small = [entry("cholmod", "dual", "fixed", fake(wall=2.0)), entry("cholmod", "primal", "fixed", fake(wall=1.0)),
             entry("mgpbd", "dual", "fixed", fake("breakdown", wall=0.1)), entry("mgpbd", "primal", "fixed", fake()),
             entry("mgpbd-double", "primal", "fixed", fake(wall=1.5)),
             entry("cholmod-lagged", "primal", "fixed", fake(wall=3.0, **{
                 "lagged_setups": 19.0, "refactorisations_in_solve": 18.0, "factorisations": 20.0,
                 "cholmod.lagged_max_iterations": 30}))]
    medium = [entry("cholmod", "primal", "fixed", fake("breakdown", rows=400)),
              entry("mgpbd", "primal", "fixed", fake(rows=400)), entry("mgpbd", "dual", "fixed", fake(rows=400)),
              entry("mgpbd-double", "primal", "eisenstat_walker", failed())]
    return race.Scene("squash", {"s": small, "m": medium}, SPEC)


def test_summary_keeps_every_size_failed_runs_and_says_what_it_left_out():
    sc = scene()
    assert sc.forms["mgpbd"] == "primal" and sc.forms["cholmod"] == "primal"
    assert sc.forms["mgpbd-double"] == "primal"  # a variant takes its method's form
    dual_mgpbd = race.Scene("squash", {"s": [entry("mgpbd", "dual", "fixed", fake(wall=0.5)),
                                             entry("mgpbd", "primal", "fixed", fake(wall=1.0)),
                                             entry("mgpbd-double", "primal", "fixed", fake(wall=0.1))]}, SPEC)
    assert dual_mgpbd.forms == {"mgpbd": "dual", "mgpbd-double": "dual"}
    text = race.summary([sc])
    medium = text[text.index("### m"):]
    assert "| mgpbd | primal |" in medium  # the larger size is kept in the chosen form
    assert "failed (exit 137: Killed)" in medium  # a process that left no run has its row
    assert "target nan" in medium  # exact CHOLMOD broke down there: no target
    assert "mgpbd [dual] at m" in text  # a run in the other form is named, not dropped silently
    assert "hit the bound of 30 CG iterations" in text and "18" in text and "wasted CG iterations" in text
    head = text[text.index("## Each method at its best"):text.index("## squash")]
    assert "| squash s (100) | 0.1 | 1.00 |" in head and "| squash m (400) | nan | — (breakdown) |" in head
    # One line per method in the main panels: mgpbd-double is mgpbd's variant.
    assert set(sc.best_by_family("s")) == {"cholmod", "mgpbd", "cholmod-lagged"}


def test_a_small_race_end_to_end(bench, tmp_path):
    """figures/race.py with the real binary: the forms it chose are the summary's, and a run whose
    process failed (an invalid value) has its row."""
    spec = tmp_path / "race.toml"
    spec.write_text('''forcing = ["fixed"]
time_budget = 60
[methods.cholmod]
solver = "cholmod"
forcing = false
[methods.jacobi-pcg]
solver = "jacobi-pcg"
[methods.broken]
solver = "cholmod"
set = { "cholmod.refactor" = "sometimes" }
[scenes.bar]
scene = "bar_hang"
set = { rtol = 0, atol = 0, max_iterations = 4, resolution = 2 }
quick_size = "r2"
sizes = [ { label = "r2" } ]
''')
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, os.path.join(ROOT, "figures", "race.py"), "--bench", bench, "--spec", str(spec),
                           "--out", str(out), "--quick", "--quiet"], capture_output=True, text=True, timeout=240)
    assert done.returncode == 0, done.stdout + done.stderr
    forms = next(line for line in done.stdout.splitlines() if line.startswith("race: bar forms:"))
    summary = (out / "summary.md").read_text()
    for item in forms.split(":", 2)[2].split(","):
        method, form = item.split()
        assert f"{method} {form} (" in summary, (method, form, summary)
    assert "| broken | primal |" in summary and "failed (exit" in summary
    assert (out / "race_bar.png").exists() and (out / "race_crossover.png").exists()
