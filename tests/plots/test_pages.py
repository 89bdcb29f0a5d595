"""The results pages (plots/pages.py): the stamp taken when measuring, the pages written from the
data alone, and each measuring script's data on a small case, rendered into a stamped page.

The end-to-end cases run the harness (XB_BENCH, set by ctest; skipped without it) on the smallest
systems the scripts take."""
import json
import os
import stat
import subprocess
import sys
import types

import h5py
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "plots"))
import pages  # noqa: E402

BENCH = os.environ.get("XB_BENCH", "")
needs_bench = pytest.mark.skipif(not (BENCH and os.access(BENCH, os.X_OK)), reason="XB_BENCH not set")


def fake_microbench(tmp_path, rates):
    """An executable that answers like `xb_microbench --benchmark_format=json` with these rates."""
    out = {"benchmarks": [{"name": "triad/n:8388608", "run_type": "iteration", "bytes_per_second": r} for r in rates]
           + [{"name": "triad/n:8388608_mean", "run_type": "aggregate", "bytes_per_second": 1e15}]}
    path = tmp_path / "xb_microbench"
    path.write_text("#!/bin/sh\ncat <<'EOF'\n" + json.dumps(out) + "\nEOF\n")
    path.chmod(path.stat().st_mode | stat.S_IEXEC)
    return str(path)


def test_stamp_records_the_machine_the_load_and_the_triad(tmp_path):
    s = pages.stamp("python3 x.py --a", microbench=fake_microbench(tmp_path, [30e9, 34.5e9, 31e9]))
    assert s["command"] == "python3 x.py --a"
    assert s["cores"] == os.cpu_count()
    assert s["triad_gb_s"] == pytest.approx(34.5)  # the best repetition, aggregates ignored
    assert s["load_1min"] == pytest.approx(float(open("/proc/loadavg").read().split()[0]), abs=5)
    assert s["date"].endswith("UTC") and s["date"][:2] == "20"


def test_stamp_says_why_there_is_no_triad(tmp_path):
    s = pages.stamp("c", microbench=str(tmp_path / "missing"))
    assert s["triad_gb_s"] is None and s["triad_note"].startswith("not measured")
    assert "not measured" in pages.stamp_text(s)


def section(tmp_path, name, page="p", order=0, rows=(("a", 1),)):
    st = {"date": "2030-01-02 03:04 UTC", "cpu": "Test CPU", "cores": 7, "triad_gb_s": 12.345, "triad_note": "",
          "load_1min": 0.5, "commit": "abc1234", "command": f"python3 measure.py {name}"}
    return pages.write_data(str(tmp_path / "data" / f"{name}.json"), page, "A page", name, st,
                            [pages.table(["k", "v"], rows)], f"text of {name}", order=order)


def test_page_is_marked_stamped_and_ordered(tmp_path):
    section(tmp_path, "second", order=2, rows=[("x | y", 2.5)])
    section(tmp_path, "first", order=1)
    written = pages.write_pages(str(tmp_path / "data"), str(tmp_path / "out"))
    assert [os.path.basename(p) for p in written] == ["p.md"]
    text = open(written[0], encoding="utf-8").read()
    assert text.startswith(pages.GENERATED_MARKER)
    assert text.index("## first") < text.index("## second")
    assert "Measured 2030-01-02 03:04 UTC on Test CPU, 7 cores (STREAM triad 12.3 GB/s; 1-min load 0.50" in text
    assert "Reproduce: `python3 measure.py first`" in text and "commit abc1234" in text
    assert "| x \\| y | 2.5 |" in text  # a cell's bar escaped, the table intact


def test_the_budget_check_reads_the_marker(tmp_path):
    section(tmp_path, "s")
    pages.write_pages(str(tmp_path / "data"), str(tmp_path / "docs" / "results"))
    (tmp_path / "docs" / "hand.md").write_text("x" * 50)
    (tmp_path / "README.md").write_text("y" * 20)
    sys.path.insert(0, os.path.join(ROOT, "tests"))
    import test_doc_budget
    m = test_doc_budget.measure(str(tmp_path))
    assert m["hand-written docs/"][0] == 50
    assert test_doc_budget.main(["--root", str(tmp_path)]) == 0
    (tmp_path / "docs" / "hand.md").write_text("x" * 100_001)
    assert test_doc_budget.main(["--root", str(tmp_path)]) == test_doc_budget.SKIP
    assert test_doc_budget.main(["--root", str(tmp_path), "--strict"]) == 1


def test_bad_data_is_refused_and_publish_copies(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"format": 99}))
    with pytest.raises(ValueError, match="format"):
        pages.read_data(str(bad))
    bad.write_text(json.dumps({"format": pages.FORMAT, "page": "p"}))
    with pytest.raises(ValueError, match="missing"):
        pages.read_data(str(bad))
    src = section(tmp_path, "s")
    written = pages.publish([src], str(tmp_path / "pub"), str(tmp_path / "out"))
    assert os.path.exists(tmp_path / "pub" / "s.json") and len(written) == 1


def load_script(path, name):
    import importlib.util
    spec = importlib.util.spec_from_file_location(name, os.path.join(ROOT, path))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_figures_driver_writes_claims_data_with_the_runs_dates(tmp_path):
    run = load_script("figures/run.py", "figures_run")
    h5 = tmp_path / "s.h5"
    with h5py.File(h5, "w") as f:
        for i, (created, load) in enumerate((("2030-01-01T00:00:00Z", 0.3), ("2030-01-02T00:00:00Z", 1.7))):
            g = f.create_group(f"runs/{i:04d}")
            g.attrs["created"], g.attrs["load_average"] = created, load
    S = run.claims.Summary()
    S.add("a claim", "a quantity", "1", "2")
    S.verdicts.append(("a claim", "holds"))
    args = types.SimpleNamespace(data=str(tmp_path / "claims.json"), out=str(tmp_path), size="default")
    run.write_data(S, args, {"x": str(h5), "y": None}, pages.stamp("cmd", triad=False))
    text = open(pages.write_pages(str(tmp_path), str(tmp_path / "out"))[0], encoding="utf-8").read()
    assert "made 2030-01-01T00:00:00Z – 2030-01-02T00:00:00Z; 1-min load at their start 0.30–1.70" in text
    assert "| a claim | a quantity | 1 | 2 |  |" in text and "**a claim**: holds" in text


@needs_bench
def test_form_table_data(tmp_path):
    out = tmp_path / "forms.json"
    r = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "form_table.py"), "--bench", BENCH, "--dir",
                        str(tmp_path), "--only", "bar_r4", "--solvers", "cholmod,mgpbd", "--data", str(out)],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    d = pages.read_data(str(out))
    assert d["page"] == "forms" and len(d["tables"][0]["rows"]) == 4  # two solvers, two forms
    assert d["stamp"]["command"].startswith("python3 scripts/form_table.py")
    assert "Reproduce" in open(pages.write_pages(str(tmp_path), str(tmp_path / "out"))[0]).read()


@needs_bench
def test_determinism_data(tmp_path):
    out = tmp_path / "det.json"
    r = subprocess.run([sys.executable, os.path.join(ROOT, "tests", "harness", "sim", "test_thread_determinism.py"),
                        "--binary", BENCH, "--threads", "1,2", "--only", "solve", "--data", str(out)],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    d = pages.read_data(str(out))
    (case, command, runs, keys, threads, differing), = d["tables"][0]["rows"]
    assert case == "solve" and "SYSTEM.h5" in command and threads == "1,2" and differing == "0"
    assert int(runs) == 6 and int(keys) > 6  # cg, jacobi-pcg, mgpbd in both forms


@needs_bench
def test_newton_variants_data(tmp_path):
    out = tmp_path / "nv.json"
    r = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "newton_variants.py"), "--bench", BENCH,
                        "--out", str(tmp_path), "--scenes", "pendulum", "--strategies", "clamp", "--data", str(out)],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    d = pages.read_data(str(out))
    assert d["page"] == "newton" and d["tables"][0]["rows"][0][:3] == ["pendulum", "clamp", "ok"]
    assert d["text"].startswith("For each scene")


def test_another_generator_keeps_the_stamp_beside_its_data(tmp_path):
    s = pages.stamp("python3 figures/race.py", triad=False)
    pages.write_stamp(str(tmp_path / "stamp.json"), s)
    assert pages.read_stamp(str(tmp_path / "stamp.json")) == s
    head = pages.marker("plots/race.py", "DATA")
    sys.path.insert(0, os.path.join(ROOT, "tests"))
    import test_doc_budget
    assert head.startswith(test_doc_budget.GENERATED_PREFIX) and "plots/race.py" in head
