#!/usr/bin/env python3
"""The CI performance gate (scripts/perf.py).

1. The comparison rules at their boundaries, on hand-made metric files.
2. End to end with the real solvers: xb_perf_metrics run twice on an unchanged tree gives a
   passing gate (the metrics are deterministic); a baseline taken with two AMG smoothing sweeps
   against a run with one (a deliberately weakened mgpbd) fails, and the table names the metric.

Usage: test_perf_gate.py [--build DIR]   (default: $XB_BINARY_DIR, else build/)
"""
import io
import json
import os
import subprocess
import sys
import tempfile
import unittest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import perf  # noqa: E402

BUILD = os.environ.get("XB_BINARY_DIR", os.path.join(ROOT, "build"))


def metrics_file(metrics, unavailable=(), ratios=None):
    return {"deterministic": {"metrics": {k: {"kind": kind, "value": v} for k, (kind, v) in metrics.items()},
                              "unavailable_methods": list(unavailable)},
            "timed_ratios": ratios or {}}


def gate(base, cur):
    out = io.StringIO()
    rc = perf.print_table(perf.compare(base, cur), False, out)
    return rc, out.getvalue()


class CompareRules(unittest.TestCase):
    BASE = {
        "linear/s/r1/f1i0/mgpbd/iterations": ("iterations", 100),
        "linear/s/r1/f1i0/mgpbd/operator_complexity": ("operator_complexity", 1.50),
        "linear/s/r1/f1i0/mgpbd/status": ("status", "converged"),
        "linear/s/r1/f1i0/rows": ("size", 800),
        "sim/s/r1/xpbd-gs/outer_iterations_per_substep": ("outer_iterations", 20),
        "linear/s/r1/f1i0/hypre/iterations": ("iterations", 30),
        "linear/s/r1/f1i0/mgpbd/setup_time_total": ("info", 0.1),
    }

    def with_(self, **changes):
        m = dict(self.BASE)
        for k, v in changes.items():
            name = next(n for n in m if n.endswith(k.replace("__", "/")))
            m[name] = (m[name][0], v)
        return m

    def test_identical_passes(self):
        rc, out = gate(metrics_file(self.BASE), metrics_file(self.BASE))
        self.assertEqual(rc, 0, out)
        self.assertIn("perf gate: passed", out)

    def test_iterations_tolerance_is_ten_percent(self):
        rc, out = gate(metrics_file(self.BASE), metrics_file(self.with_(mgpbd__iterations=110)))
        self.assertEqual(rc, 0, out)
        rc, out = gate(metrics_file(self.BASE), metrics_file(self.with_(mgpbd__iterations=111)))
        self.assertEqual(rc, 1, out)
        self.assertIn("linear/s/r1/f1i0/mgpbd/iterations", out)
        self.assertIn("+11.0%", out)

    def test_fewer_iterations_pass_as_improved(self):
        rc, out = gate(metrics_file(self.BASE), metrics_file(self.with_(mgpbd__iterations=50)))
        self.assertEqual(rc, 0, out)
        self.assertIn("improved", out)

    def test_operator_complexity_tolerance_is_two_percent(self):
        rc, out = gate(metrics_file(self.BASE), metrics_file(self.with_(operator_complexity=1.529)))
        self.assertEqual(rc, 0, out)
        rc, out = gate(metrics_file(self.BASE), metrics_file(self.with_(operator_complexity=1.532)))
        self.assertEqual(rc, 1, out)
        self.assertIn("mgpbd/operator_complexity", out)

    def test_outer_iterations(self):
        rc, out = gate(metrics_file(self.BASE), metrics_file(self.with_(outer_iterations_per_substep=23)))
        self.assertEqual(rc, 1, out)
        self.assertIn("xpbd-gs/outer_iterations_per_substep", out)

    def test_status_leaving_converged_fails(self):
        rc, out = gate(metrics_file(self.BASE), metrics_file(self.with_(mgpbd__status="max_iterations")))
        self.assertEqual(rc, 1, out)
        self.assertIn("mgpbd/status", out)

    def test_counts_of_a_run_that_failed_in_the_baseline_are_not_gated(self):
        base = dict(self.BASE)
        base["linear/s/r1/f1i0/mgpbd/status"] = ("status", "breakdown")
        rc, out = gate(metrics_file(base), metrics_file(self.with_(mgpbd__iterations=300, mgpbd__status="converged")))
        self.assertEqual(rc, 0, out)
        self.assertIn("changed (baseline breakdown)", out)

    def test_changed_system_size_fails(self):
        rc, out = gate(metrics_file(self.BASE), metrics_file(self.with_(rows=801)))
        self.assertEqual(rc, 1, out)

    def test_info_metrics_are_not_gated(self):
        rc, out = gate(metrics_file(self.BASE), metrics_file(self.with_(setup_time_total=10.0)))
        self.assertEqual(rc, 0, out)

    def test_missing_metric_fails_unless_solver_unavailable(self):
        cur = dict(self.BASE)
        del cur["linear/s/r1/f1i0/hypre/iterations"]
        rc, out = gate(metrics_file(self.BASE), metrics_file(cur))
        self.assertEqual(rc, 1, out)
        self.assertIn("missing", out)
        rc, out = gate(metrics_file(self.BASE), metrics_file(cur, unavailable=["hypre"]))
        self.assertEqual(rc, 0, out)

    def test_slower_time_ratio_is_flagged_not_failed(self):
        base = metrics_file(self.BASE, ratios={"solve/mgpbd/cloth_hang/r16": 2.0, "spmv/cloth_hang/r16": 0.5})
        cur = metrics_file(self.BASE, ratios={"solve/mgpbd/cloth_hang/r16": 2.6, "spmv/cloth_hang/r16": 0.55})
        rc, out = gate(base, cur)
        self.assertEqual(rc, 0, out)
        self.assertIn("SLOWER", out)
        self.assertIn("solve/mgpbd/cloth_hang/r16", out)
        self.assertNotIn("spmv/cloth_hang/r16 ", out)  # +10 % is within the 25 %

    def test_timed_ratios_from_google_benchmark(self):
        gb = {"benchmarks": [
            {"name": "triad/n:8", "run_type": "iteration", "real_time": 2.0, "cpu_time": 1.0},
            {"name": "solve/cg/x", "run_type": "iteration", "real_time": 10.0, "cpu_time": 4.0},
            {"name": "solve/cg/x", "run_type": "iteration", "real_time": 12.0, "cpu_time": 6.0},
            {"name": "solve/cg/x_mean", "run_type": "aggregate", "real_time": 10.0, "cpu_time": 4.0},
            {"name": "solve/bad/x", "run_type": "iteration", "real_time": 0.0, "cpu_time": 0.0, "error_occurred": True},
        ]}
        self.assertEqual(perf.timed_ratios(gb, "cpu_time"), {"solve/cg/x": 4.0})
        self.assertEqual(perf.timed_ratios(gb, "real_time"), {"solve/cg/x": 5.0})

    def test_spmv_units_per_scene_are_reported_never_gated(self):
        gb = {"benchmarks": [
            {"name": "triad/n:8", "run_type": "iteration", "cpu_time": 1.0},
            {"name": "spmv/cloth/r16", "run_type": "iteration", "cpu_time": 2.0},
            {"name": "spmv/cloth/r16", "run_type": "iteration", "cpu_time": 3.0},
            {"name": "spmv/bar/r3", "run_type": "iteration", "cpu_time": 4.0},
            {"name": "amg_vcycle/cloth/r16", "run_type": "iteration", "cpu_time": 14.0},
            {"name": "amg_vcycle/bar/r3", "run_type": "iteration", "cpu_time": 20.0},
            {"name": "assembly/other/r1", "run_type": "iteration", "cpu_time": 5.0},
        ]}
        units = perf.spmv_unit_ratios(gb, "cpu_time")
        self.assertEqual(units, {"amg_vcycle/cloth/r16": 7.0, "amg_vcycle/bar/r3": 5.0})
        base = metrics_file(self.BASE)
        base["spmv_units"] = {"amg_vcycle/cloth/r16": 3.5}
        cur = metrics_file(self.BASE)
        cur["spmv_units"] = units
        rc, out = gate(base, cur)
        self.assertEqual(rc, 0, out)
        table = io.StringIO()
        perf.spmv_unit_table(base, cur, table)
        self.assertIn("+100% costlier", table.getvalue())

    def test_timings_measured_differently_are_not_compared(self):
        base = metrics_file(self.BASE, ratios={"solve/mgpbd/x": 2.0})
        cur = metrics_file(self.BASE, ratios={"solve/mgpbd/x": 4.0})
        base["timing"], cur["timing"] = {"threads": 1}, {"threads": 2}
        rc, out = gate(base, cur)
        self.assertEqual(rc, 0, out)
        self.assertNotIn("SLOWER", out)


class GateEndToEnd(unittest.TestCase):
    """The real metrics tool and solvers: unchanged passes, one smoothing sweep fewer fails."""

    @classmethod
    def setUpClass(cls):
        cls.exe = os.path.join(BUILD, "xb_perf_metrics")
        if not os.path.exists(cls.exe):
            raise unittest.SkipTest(f"{cls.exe} not built")
        cls.tmp = tempfile.mkdtemp(prefix="perf_gate_")

    def metrics(self, name, *sets):
        out = os.path.join(self.tmp, name + ".json")
        cmd = [self.exe, "--only", "linear", "--methods", "mgpbd,jacobi-pcg", "--cases", "cloth_hang/r16,bar_hang/r3",
               "--out", out]
        for s in sets:
            cmd += ["--set", s]
        r = subprocess.run(cmd, capture_output=True, text=True)
        self.assertEqual(r.returncode, 0, r.stderr)
        return out

    def compare(self, base, cur):
        return subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "perf.py"), "compare", base, cur],
                              capture_output=True, text=True)

    def test_unchanged_passes_weakened_fails(self):
        strong = self.metrics("two_sweeps", "amg.smoother_sweeps=2")
        again = self.metrics("two_sweeps_again", "amg.smoother_sweeps=2")
        weak = self.metrics("one_sweep", "amg.smoother_sweeps=1")

        r = self.compare(strong, again)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertIn("0 outside tolerance", r.stdout)
        with open(strong) as f:
            m = json.load(f)["metrics"]
        self.assertIn("linear/cloth_hang/r16/f1i0/mgpbd/iterations", m)
        self.assertIn("linear/cloth_hang/r16/f1i0/mgpbd/operator_complexity", m)

        r = self.compare(strong, weak)
        self.assertEqual(r.returncode, 1, r.stdout + r.stderr)
        self.assertIn("FAIL", r.stdout)
        self.assertIn("linear/cloth_hang/r16/f1i0/mgpbd/iterations", r.stdout)
        # jacobi-pcg does not use the AMG: its metrics must not be blamed.
        self.assertNotIn("jacobi-pcg/iterations", r.stdout)

    def test_bad_key_is_one_clear_error(self):
        r = subprocess.run([self.exe, "--set", "amg.smoother_sweeps=zero"], capture_output=True, text=True)
        self.assertEqual(r.returncode, 2)
        self.assertIn("amg.smoother_sweeps", r.stderr)


if __name__ == "__main__":
    args = sys.argv[1:]
    if len(args) >= 2 and args[0] == "--build":
        BUILD = os.path.abspath(args[1])
        args = args[2:]
    unittest.main(argv=[sys.argv[0], *args])
