"""The results store from Python (results/README.md): xb.repair rebuilds an index deleted by hand
and says what it found; xb.read leaves out a run whose file is gone with one warning naming it."""
import os
import warnings

import h5py
import xpbd_bench as xb


def small_file(tmp_path):
    out = os.path.join(tmp_path, "r.h5")
    xb.run("cloth_hang", solvers=["xpbd-gs", "cholmod", "cg"], out=out, frames=1, set={"resolution": 4})
    return out


def test_repair_rebuilds_an_index_deleted_by_hand(tmp_path):
    out = small_file(tmp_path)
    os.remove(out)
    found = xb.repair(out)
    assert found["runs"] == 3 and len(found["relinked"]) == 3 and not found["dangling"], found
    with h5py.File(out, "r") as f:
        assert sorted(f["runs"]) == ["0001_cloth_hang_xpbd-gs", "0002_cloth_hang_cholmod", "0003_cloth_hang_cg"]
        assert all("status" in g.attrs for g in f["runs"].values())
    assert xb.repair(out)["relinked"] == []  # nothing more to find


def test_read_names_a_run_whose_file_is_gone(tmp_path):
    out = small_file(tmp_path)
    with h5py.File(out, "r") as f:
        store = f.attrs["store"]
    os.remove(os.path.join(out + ".runs", store, "0002_cloth_hang_cholmod.h5"))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        runs = xb.read(out)
    assert [r["name"] for r in runs] == ["0001_cloth_hang_xpbd-gs", "0003_cloth_hang_cg"]
    said = [str(w.message) for w in caught]
    assert len(said) == 1 and "0002_cloth_hang_cholmod" in said[0] and "is gone" in said[0], said
    found = xb.repair(out)
    assert found["runs"] == 2 and [d.split(":")[0] for d in found["dangling"]] == ["0002_cloth_hang_cholmod"], found
