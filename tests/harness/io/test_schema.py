#!/usr/bin/env python3
"""The results schema is one list (harness/io/schema.cpp) that the writers, results/README.md and
plots/ follow: results/schema.json is exactly `xpbd-bench schema`'s output, the README documents
every name, and a real run's file holds only names the schema lists (with their types).

usage: test_schema.py --binary build/xpbd-bench --root SOURCE_DIR
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

ap = argparse.ArgumentParser()
ap.add_argument("--binary", required=True)
ap.add_argument("--root", required=True)
a = ap.parse_args()
sys.path.insert(0, os.path.join(a.root, "plots"))
import xbruns  # noqa: E402

problems = []
printed = subprocess.run([a.binary, "schema"], capture_output=True, text=True, check=True).stdout
committed_path = os.path.join(a.root, "results", "schema.json")
if open(committed_path).read() != printed:
    problems.append("results/schema.json differs from `xpbd-bench schema` (regenerate it: xpbd-bench schema > results/schema.json)")
schema = json.loads(printed)
readme = open(os.path.join(a.root, "results", "README.md")).read()
for n in schema["attributes"] + schema["datasets"]:
    if f"`{n['name']}`" not in readme:
        problems.append(f"results/README.md does not document `{n['name']}`")

# A run and a solve write only listed names; the loader refuses an unlisted dataset.
with tempfile.TemporaryDirectory() as d:
    env = dict(os.environ, OMP_WAIT_POLICY="passive", OMP_NUM_THREADS="1")
    sim = os.path.join(d, "sim.h5")
    subprocess.run([a.binary, "run", "--scene", "cloth_hang", "--set", "resolution=4", "--set", "max_iterations=3",
                    "--solver", "xpbd-gs,cholmod", "--form", "dual,primal", "--reference", "--out", sim],
                   env=env, check=True, capture_output=True)
    runs = xbruns.load(sim, datasets=tuple(sorted(xbruns.dataset_names("simulation"))))
    if len(runs) != 3 or not all(r["data"].get("dual_residual") is not None for r in runs):
        problems.append(f"xbruns.load read {len(runs)} runs with their datasets from {sim}, expected 3")
    try:
        xbruns.load(sim, datasets=("no_such_dataset",))
        problems.append("xbruns.load accepted a dataset the schema does not list")
    except ValueError:
        pass

for p in problems:
    print(p)
print(f"schema: {len(problems)} problem(s)")
sys.exit(1 if problems else 0)
