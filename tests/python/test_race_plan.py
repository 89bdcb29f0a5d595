"""The race's plan (figures/race_plan.py): predictions from the smaller sizes (a fitted power law,
one size with the default slope, else the prior), budgets, the skip of what would not fit in memory
or failed at a smaller size, and the cut to the campaign's total in priority order."""
import math
import os
import sys

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
sys.path.insert(0, os.path.join(ROOT, "figures"))
sys.path.insert(0, os.path.join(ROOT, "plots"))
import race_plan as plan  # noqa: E402

SPEC = {"time_budget": 1000, "overrun": 3,
        "outer": {"xpbd": {}, "newton": {"own_stop": True}},
        "plan": {"budget_factor": 3, "min_budget": 20, "slope": 1.2, "memory_slope": 1.1, "newton_iterations": 8,
                 "priority": ["newton.mgpbd", "newton.cholmod"],
                 "prior": {"default": {"seconds": 0.5, "slope": 1.0, "start": 1.0, "bytes": 4000, "memory_slope": 1.0},
                           "cholmod": {"seconds": 1.0, "slope": 1.5, "start": 0.0, "bytes": 1e4, "memory_slope": 1.3}}}}
SIZES = [{"label": "s", "rows": 1e4}, {"label": "m", "rows": 1e5}, {"label": "l", "rows": 1e6}]


def entries(pairs=(("newton", "mgpbd"), ("newton", "cholmod"), ("xpbd", "jacobi-pcg")), sizes=SIZES):
    out = []
    for i, z in enumerate(sizes):
        out.append(plan.Entry("squash", i, z, plan.REFERENCE, "cholmod", "none", f"data/squash/{z['label']}/_reference/run.h5"))
        for o, m in pairs:
            out.append(plan.Entry("squash", i, z, o, m, "fixed", f"data/squash/{z['label']}/{o}.{m}.fixed.h5"))
    return out


def done(es, timings, label, outer, linear, seconds, peak=1e8, status="ok"):
    e = next(e for e in es if e.size["label"] == label and e.outer == outer and e.linear == linear)
    e.done = True
    timings[e.rel] = dict(seconds=seconds, code="0", load=1.0, status=status, peak=peak, rows=e.rows)


def find(es, label, outer, linear):
    return next(e for e in es if e.size["label"] == label and e.outer == outer and e.linear == linear)


def test_fit_recovers_a_power_law():
    b, a, r2, how = plan.fit([(1e4, 2.0 * 1e4 ** 1.3), (1e5, 2.0 * 1e5 ** 1.3), (1e6, 2.0 * 1e6 ** 1.3)], 1.2)
    assert abs(b - 1.3) < 1e-9 and abs(math.exp(a) - 2.0) < 1e-6 and abs(r2 - 1) < 1e-12 and how.startswith("3 sizes")
    b, a, r2, how = plan.fit([(1e4, 5.0)], 1.2)  # one size: the default slope through it
    assert b == 1.2 and abs(math.exp(a + b * math.log(1e4)) - 5.0) < 1e-9 and how == "1 size, slope 1.2"
    assert plan.fit([], 1.2) is None


def test_predictions_come_from_the_smaller_sizes_else_the_prior():
    es, t = entries(), {}
    done(es, t, "s", "newton", "mgpbd", 1.0, peak=1e8)
    done(es, t, "m", "newton", "mgpbd", 10.0 ** 1.1, peak=1e9)
    plan.make_plan(SPEC, es, t, lambda e: 8, limit_gb=100)
    big = find(es, "l", "newton", "mgpbd")
    assert abs(big.seconds - 100.0 ** 1.1) < 1e-6 and big.how == "2 sizes, slope 1.10"  # extrapolated
    assert abs(big.bytes - 1e10) < 1e-3 * 1e10
    assert big.budget == min(1000, 3 * big.seconds)
    one = entries()
    t1 = {}
    done(one, t1, "s", "newton", "cholmod", 2.0)
    plan.make_plan(SPEC, one, t1, lambda e: 8, limit_gb=100)
    assert abs(find(one, "m", "newton", "cholmod").seconds - 2.0 * 10 ** 1.2) < 1e-9
    fresh = find(one, "s", "xpbd", "jacobi-pcg")  # nothing smaller: the prior (the default method's)
    assert fresh.how == "prior" and abs(fresh.seconds - (0.5 * 0.1 * 8 + 1.0)) < 1e-12
    assert find(one, "s", "newton", "cholmod").action == "done"


def test_what_would_not_fit_or_failed_smaller_is_skipped_before_it_starts():
    es, t = entries(), {}
    done(es, t, "s", "newton", "cholmod", 1.0, peak=1e8)
    done(es, t, "m", "newton", "cholmod", 10.0, peak=2e9)  # memory ×20 per decade: 40 GB at l
    done(es, t, "m", "xpbd", "jacobi-pcg", 900.0, status="over_budget")  # ≥ 900 × 10^1.2 s at l
    done(es, t, "m", "newton", "mgpbd", 5.0, status="out_of_memory")
    plan.make_plan(SPEC, es, t, lambda e: 8, limit_gb=20)
    assert find(es, "l", "newton", "cholmod").action.startswith("skip: predicted 40.0 GB > the 20.0 GB limit")
    late = find(es, "l", "xpbd", "jacobi-pcg")
    assert late.action.startswith("skip: predicted 14264 s > the time budget") and late.how.startswith("over its budget at m")
    assert find(es, "l", "newton", "mgpbd").action == "skip: out_of_memory at m"
    slow = entries(pairs=(("newton", "mgpbd"),))
    t2 = {}
    done(slow, t2, "s", "newton", "mgpbd", 10.0)
    done(slow, t2, "m", "newton", "mgpbd", 200.0)  # 4000 s at l: past the 1000 s time budget
    plan.make_plan(SPEC, slow, t2, lambda e: 8, limit_gb=100)
    assert find(slow, "l", "newton", "mgpbd").action.startswith("skip: predicted 4000 s > the time budget")


def test_the_total_cuts_the_lowest_priority_first_and_counts_what_was_spent():
    es, t = entries(), {}
    for o, m, sec in (("newton", "mgpbd", 1.0), ("newton", "cholmod", 1.0), ("xpbd", "jacobi-pcg", 1.0)):
        done(es, t, "s", o, m, sec)
        done(es, t, "m", o, m, 10 * sec)
    spent, planned = plan.make_plan(SPEC, es, t, lambda e: 8, total=184, limit_gb=100)
    assert spent == 3 + 30
    # Left: l's reference (the prior: 0.5 s × 10 × 8 iterations + 1 s = 41 s, first), then l's
    # entries at 100 s each (slope 1 from s and m): newton.mgpbd fits, newton.cholmod would pass the
    # total, and so would xpbd + jacobi-pcg (no priority); m's reference is not needed.
    assert find(es, "l", plan.REFERENCE, "cholmod").action == "run"
    assert find(es, "l", "newton", "mgpbd").action == "run"
    assert find(es, "l", "newton", "cholmod").action.startswith("cut: the campaign's 184 s (33 spent, 141 planned")
    assert find(es, "l", "xpbd", "jacobi-pcg").action.startswith("cut:")
    assert find(es, "m", plan.REFERENCE, "cholmod").action.startswith("cut: no entry")
    assert abs(planned - 141) < 1e-9
    # A size none of whose entries runs does not compute its reference.
    es2, t3 = entries(pairs=(("newton", "mgpbd"),), sizes=SIZES[:1]), {}
    done(es2, t3, "s", "newton", "mgpbd", 1.0)
    plan.make_plan(SPEC, es2, t3, lambda e: 8, limit_gb=100)
    assert find(es2, "s", plan.REFERENCE, "cholmod").action.startswith("cut: no entry")


def test_timings_old_and_new_lines(tmp_path):
    p = tmp_path / "timings.tsv"
    p.write_text("2026-01-01T00:00:00Z\tdata/a.h5\t3.0\t0\t1.50\n"
                 "2026-01-01T00:00:05Z\tdata/b.h5\t4.0\t0\t1.20\tover_budget\t2000000000\t314827\n")
    t = plan.read_timings(str(p))
    assert t["data/a.h5"]["seconds"] == 3.0 and math.isnan(t["data/a.h5"]["peak"]) and t["data/a.h5"]["status"] == ""
    assert t["data/b.h5"]["status"] == "over_budget" and t["data/b.h5"]["peak"] == 2e9 and t["data/b.h5"]["rows"] == 314827
