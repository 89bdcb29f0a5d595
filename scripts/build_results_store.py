#!/usr/bin/env python3
"""Builds a results file of N small runs in seconds, for the tests and timings of the results store
(tests/harness/cli/test_store.py, scripts/store_timings.py): one real run is made with the CLI
(`run`, cloth_hang 4x4, one frame, xpbd-gs, 5 iterations: ~10 KB), its run file is copied N times into a new store
folder, each copy with its run's number written into the name its group has (the bytes of the
name, the same length: HDF5's name heap of a group holds it, no checksum covers it), and the index
is built from the store by `xpbd-bench repair`. Numbers past 9999 have a longer name: those runs
are copied through h5py instead (slower, but few). What the file holds is what the CLI would
have written after N appends of that run, but for `created`.

    python3 scripts/build_results_store.py --binary build/xpbd-bench --runs 10000 --out big.h5
"""
import argparse
import os
import secrets
import shutil
import subprocess
import sys
import tempfile

import h5py

TEMPLATE_NAME = "0001_cloth_hang_xpbd-gs"


def template(binary, work):
    """The bytes of one real run file and its run's name."""
    out = os.path.join(work, "template.h5")
    p = subprocess.run([binary, "run", "--scene", "cloth_hang", "--solver", "xpbd-gs", "--set", "resolution=4", "--set",
                        "threads=1", "--set", "max_iterations=5", "--frames", "1", "--out", out, "--quiet"],
                       capture_output=True, text=True,
                       env=dict(os.environ, OMP_NUM_THREADS="1"))
    if p.returncode != 0:
        sys.exit(f"build_results_store: the template run failed: {p.stderr[-1000:]}")
    with h5py.File(out, "r") as f:
        store = f.attrs["store"]
        store = store.decode() if isinstance(store, bytes) else store
    folder = os.path.join(out + ".runs", store)
    (name,) = [f for f in os.listdir(folder) if f.endswith(".h5")]
    with open(os.path.join(folder, name), "rb") as fh:
        return fh.read(), out, folder + "/" + name


def build(binary, runs, out):
    """Writes OUT (replacing it) with `runs` runs; returns OUT."""
    work = tempfile.mkdtemp(prefix="xb_build_store_")
    try:
        data, _, template_file = template(binary, work)
        if data.count(TEMPLATE_NAME.encode()) < 1:
            sys.exit("build_results_store: the template's run name is not in its bytes")
        for p in (out, out + ".runs"):
            if os.path.isdir(p):
                shutil.rmtree(p)
            elif os.path.exists(p):
                os.remove(p)
        folder = os.path.join(out + ".runs", secrets.token_hex(4))
        os.makedirs(folder)
        for i in range(1, runs + 1):
            name = f"{i:04d}" + TEMPLATE_NAME[4:]
            path = os.path.join(folder, name + ".h5")
            if len(name) == len(TEMPLATE_NAME):
                with open(path, "wb") as fh:
                    fh.write(data.replace(TEMPLATE_NAME.encode(), name.encode()))
                continue
            with h5py.File(template_file, "r") as src, h5py.File(path, "w") as dst:
                dst.attrs.update(src.attrs)
                dst.create_group("runs")
                src.copy(src["runs"][TEMPLATE_NAME], dst["runs"], name=name)
        p = subprocess.run([binary, "repair", out], capture_output=True, text=True)
        if p.returncode != 0:
            sys.exit(f"build_results_store: repair failed: {p.stdout[-500:]} {p.stderr[-1000:]}")
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--binary", required=True)
    ap.add_argument("--runs", type=int, required=True)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    build(os.path.abspath(a.binary), a.runs, a.out)
    print(f"build_results_store: {a.out} holds {a.runs} runs")


if __name__ == "__main__":
    main()
