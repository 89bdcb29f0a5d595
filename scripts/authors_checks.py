#!/usr/bin/env python3
"""The paper's numbers re-measured under the authors' profile (problems/profiles/authors.toml).

usage: python3 scripts/authors_checks.py near_kernel    [--mesh bunny:50k] [--bench build/xpbd-bench] [--out DIR]
       python3 scripts/authors_checks.py setup_interval [--mesh bunny:12k] [--state-frame F] [--frames N]
       python3 scripts/authors_checks.py squash         [--mesh bunny:12k] [--variants ...]

near_kernel     the first solve (λ = 0) of the squash's `enlarge` start at 0.2 m: PCG iterations
                to 1e-6 with the profile's AMG for amg.near_kernel = ones, gs, gs_authors, beside
                the paper's 34 / 20 / 18 (its 270K bunny; ‖b‖ = √0.75·√rows there and here).
squash          mgpbd on the squash at 0.2 m from the collapsed start: outer iterations to 1e-2
                in the authors' metric and in the true one, the step rule and AMG variants given
                by --variants (each a comma-separated list of key=value), and the hierarchy.
setup_interval  one saved state (run --save-state after --state-frame frames), then mgpbd for
                --frames frames from it with amg.setup_interval 1/10/20/50/100: the relative
                residual after 100 outer iterations of the last frame, beside the paper's
                1.025e-2 … 1.452e-2. A hierarchy built at frame f0 is rebuilt at f0 + k, so the
                last frame's hierarchy is (frames − 1) mod k frames old (printed as `age`).

Every command it runs is printed; results go under --out (default /tmp/xb_authors_checks).
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tomllib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "plots"))
import xbruns  # noqa: E402

PAPER_NEAR_KERNEL = {"ones": 34, "gs": 20, "gs_authors": 18}
PAPER_INTERVAL = {1: 1.025e-2, 10: 1.219e-2, 20: 1.310e-2, 50: 1.404e-2, 100: 1.452e-2}


def profile_sets(table="amg"):
    """The profile's keys of one table as --set arguments (capture and solve take no --profile)."""
    with open(os.path.join(ROOT, "problems", "profiles", "authors.toml"), "rb") as f:
        prof = tomllib.load(f)
    out = []
    for k, v in prof.get(table, {}).items():
        out += ["--set", f"{table}.{k}={v}"]
    return out


def sh(cmd):
    print("$ " + " ".join(cmd), flush=True)
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"failed ({r.returncode}): {(r.stderr.strip().splitlines() or ['?'])[-1]}")
    return r.stdout


def report(bench, path):
    return json.loads(sh([bench, "report", path, "--format", "json"]))


def near_kernel(a):
    prefix = os.path.join(a.out, "enlarge_" + a.mesh.replace(":", "_"))
    sh([a.bench, "capture", "--scene", "squash", "--set", f"mesh={a.mesh}", "--set", "init=enlarge",
        "--set", "mesh_height=0.2", "--frame", "0", "--iteration", "0", "--out", prefix])
    print(f"\n| near_kernel | PCG iterations | final rel. residual | levels (rows) | paper (270K) |\n|---|---|---|---|---|")
    rows = []
    for nk in ("ones", "gs", "gs_authors"):
        out = f"{prefix}_{nk}.h5"
        if os.path.exists(out):
            os.remove(out)
        sh([a.bench, "solve", "--system", prefix + ".h5", "--solver", "mgpbd", "--tol", "1e-6", "--out", out] +
           profile_sets() + ["--set", "linear.max_iterations=1000", "--set", f"amg.near_kernel={nk}"])  # after the profile's
        r = report(a.bench, out)[0]
        rows.append(f"| {nk} | {r['iterations']} | {r['final_relative_residual']:.2g} | {r['levels']} "
                    f"({r['amg.near_kernel']}, {r['amg.prolongator']}) | "
                    f"{PAPER_NEAR_KERNEL[nk]} |")
    print(f"(‖b‖ = {r['rhs_norm']:.2f}, {r['rows']} rows)")
    print("\n".join(rows))


def first_to(run, tol, metric):
    d = run["data"]
    rel = d[xbruns.residual_key(metric, relative=True)]
    hit = [i for i, v in enumerate(rel) if v <= tol]
    return int(d["iteration"][hit[0]]) if hit else math.nan


def squash(a):
    print("| variant | outer its to 1e-2 (authors' metric) | (true metric) | status | hierarchy rows |\n|---|---|---|---|---|")
    for i, v in enumerate(a.variants):
        out = os.path.join(a.out, f"squash_{i}.h5")
        if os.path.exists(out):
            os.remove(out)
        sets = [x for kv in v.split(",") if kv for x in ("--set", kv)]
        sh([a.bench, "run", "--scene", "squash", "--profile", "authors", "--solver", "mgpbd", "--set", f"mesh={a.mesh}",
            "--set", f"max_iterations={a.max_iterations}", "--set", "rtol=1e-3", "--out", out] + sets)
        r = xbruns.load(out, datasets=("iteration", "relative_dual_residual", "authors_relative_dual_residual",
                                       "level_rows"))[0]
        rows = " → ".join(str(int(x)) for x in r["data"].get("level_rows", []))
        print(f"| {v or 'profile as is'} | {first_to(r, 1e-2, 'authors')} | {first_to(r, 1e-2, 'true')} | "
              f"{r['attrs'].get('status')} | {rows} |", flush=True)


def setup_interval(a):
    state = os.path.join(a.out, "state.h5")
    # The state's frames stop as the scene does (bunny_squash.json: rtol 1e-2, 20 iterations); the
    # five runs from it take 100 outer iterations per frame.
    scene = ["--scene", "squash", "--profile", "authors", "--set", f"mesh={a.mesh}"]
    base = scene + ["--set", "rtol=0", "--set", "atol=0", "--set", "max_iterations=100"]
    if os.path.exists(state):
        print(f"reusing the saved state {state} (delete it to recompute)", flush=True)
    else:
        sh([a.bench, "run"] + scene + ["--solver", "mgpbd", "--set", f"frames={a.state_frame + 1}",
                                      "--save-state", state, "--frame-of-state", str(a.state_frame),
                                      "--out", os.path.join(a.out, "state_run.h5")])
    print("| setup_interval | age of P (frames) | rel. residual after 100 its, authors' metric | true metric | paper (270K, frame 99) |\n"
          "|---|---|---|---|---|")
    for k in a.intervals:
        out = os.path.join(a.out, f"interval_{k}.h5")
        if os.path.exists(out):
            os.remove(out)
        sh([a.bench, "run"] + base + ["--solver", "mgpbd", "--load-state", state, "--set", f"frames={a.frames}",
                                      "--set", f"amg.setup_interval={k}", "--out", out])
        r = xbruns.load(out, datasets=("frame", "substep", "iteration", "relative_dual_residual",
                                       "authors_relative_dual_residual"))[0]
        last = int(r["data"]["frame"][-1])
        va = xbruns.value_at_iteration(r, "authors_relative_dual_residual", 100, last, 0)
        vt = xbruns.value_at_iteration(r, "relative_dual_residual", 100, last, 0)
        print(f"| {k} | {(a.frames - 1) % k} | {va:.4g} | {vt:.4g} | {PAPER_INTERVAL[k]:.4g} |", flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("what", choices=("near_kernel", "squash", "setup_interval"))
    ap.add_argument("--bench", default=os.path.join(ROOT, "build", "xpbd-bench"))
    ap.add_argument("--out", default="/tmp/xb_authors_checks")
    ap.add_argument("--mesh", default=None, help="near_kernel: bunny:50k; others: bunny:12k")
    ap.add_argument("--max-iterations", type=int, default=150, help="squash: outer iterations at most")
    ap.add_argument("--variants", nargs="*",
                    default=["", "step=fixed", "amg.coarse_solver=direct,amg.jacobi_omega=per_level",
                             "step=fixed,amg.coarse_solver=direct,amg.jacobi_omega=per_level"],
                    help="squash: --set lists, one run each ('' = the profile as is)")
    ap.add_argument("--state-frame", type=int, default=2, help="setup_interval: the saved frame")
    ap.add_argument("--frames", type=int, default=3, help="setup_interval: frames run from the state")
    ap.add_argument("--intervals", type=lambda s: [int(x) for x in s.split(",")], default=[1, 10, 20, 50, 100],
                    help="setup_interval: the amg.setup_interval values, comma-separated")
    a = ap.parse_args()
    a.mesh = a.mesh or ("bunny:50k" if a.what == "near_kernel" else "bunny:12k")
    os.makedirs(a.out, exist_ok=True)
    {"near_kernel": near_kernel, "squash": squash, "setup_interval": setup_interval}[a.what](a)


if __name__ == "__main__":
    main()
