#!/usr/bin/env python3
"""The smoother cost-per-digit table: for each captured system, mgpbd with each smoother
(dual: jacobi, chebyshev of degree 2-4, gs, one sweep; primal: the same and block_jacobi,
block_chebyshev, block_gs, 1 and 2 sweeps, the Chebyshev kinds also of degree 4 and 5 once) solved from zero to linear.tol; setup, solve, iterations and the time per decade of the
relative residual, one Markdown table (xb_bench --xb_mode=smoothers on each system in turn).

  smoother_table.py SYSTEM.h5... [--build DIR] [--tol 1e-8] [--threads 2]
"""
import argparse
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("systems", nargs="+", help="captured systems (xpbd-bench capture), with the primal data")
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--tol", default="1e-8", help="linear.tol of every solve")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--clock", choices=("wall", "cpu"), default="cpu",
                    help="cpu: the process's CPU time (robust on a loaded machine); wall: elapsed time")
    a = ap.parse_args(argv)
    exe = os.path.join(a.build, "xb_bench")
    if not os.path.exists(exe):
        sys.exit(f"smoother_table: {exe} not found (build it: ninja -C {a.build} xb_bench)")
    env = dict(os.environ, OMP_NUM_THREADS=str(a.threads), OMP_WAIT_POLICY="passive")
    with open("/proc/loadavg") as f:
        print(f"load average at start: {f.read().split()[0]}; {a.threads} threads; {a.clock} time; linear.tol {a.tol}\n")
    header = True
    for path in a.systems:
        if not os.path.exists(path):
            sys.exit(f"smoother_table: no such system file: {path}")
        r = subprocess.run([exe, f"--xb_system={path}", "--xb_mode=smoothers", "--xb_min_rows=0", f"--xb_clock={a.clock}",
                            f"--xb_set=linear.tol={a.tol}"], env=env, capture_output=True, text=True)
        if r.returncode != 0:
            sys.exit(f"smoother_table: xb_bench failed on {path} (exit {r.returncode}):\n{r.stderr[-2000:]}")
        lines = r.stdout.splitlines()
        print("\n".join(lines if header else lines[2:]), flush=True)
        header = False
    return 0


if __name__ == "__main__":
    sys.exit(main())
