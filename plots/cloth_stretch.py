#!/usr/bin/env python3
"""How far each solver leaves a hanging cloth stretched (the paper's Fig. 8).

usage: python3 plots/cloth_stretch.py RESULTS.h5 [-o OUT.png]

For every cloth_hang run: the final positions (dataset final_positions) and the N×N grid with one
diagonal per quad that the scene builds (attributes resolution, size); edge strain = |p−q|/l0 − 1.
One front view (x, y) per run, vertices coloured by the largest strain of their edges, titled with
the max and mean strain and the final dual residual. Prints one line per run. Writes PNG and PDF.
"""
import argparse
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import xbruns  # noqa: E402


def cloth_edges(n):
    """Edges of problems/generators make_cloth_grid(N): vertex (i, k) is i·(N+1) + k."""
    n1 = n + 1
    idx = np.arange(n1 * n1).reshape(n1, n1)
    e = [np.stack([idx[:, :-1].ravel(), idx[:, 1:].ravel()], 1),
         np.stack([idx[:-1, :].ravel(), idx[1:, :].ravel()], 1),
         np.stack([idx[:-1, :-1].ravel(), idx[1:, 1:].ravel()], 1)]
    return np.concatenate(e)


def strains(run):
    """(per-edge strain, per-vertex max strain, positions) of a cloth_hang run."""
    a = run["attrs"]
    n = int(a["resolution"])
    size = float(a["size"])
    x = np.asarray(run["data"]["final_positions"], dtype=float).reshape(-1, 3)
    if x.shape[0] != (n + 1) ** 2:
        raise ValueError(f"{run['name']}: {x.shape[0]} positions, expected {(n + 1) ** 2}")
    n1 = n + 1
    k, i = np.meshgrid(np.arange(n1), np.arange(n1))
    rest = np.stack([size * k.ravel() / n, np.zeros(n1 * n1), size * i.ravel() / n], 1)
    e = cloth_edges(n)
    l0 = np.linalg.norm(rest[e[:, 0]] - rest[e[:, 1]], axis=1)
    s = np.linalg.norm(x[e[:, 0]] - x[e[:, 1]], axis=1) / l0 - 1.0
    per_vertex = np.zeros(n1 * n1)
    np.maximum.at(per_vertex, e[:, 0], s)
    np.maximum.at(per_vertex, e[:, 1], s)
    return s, per_vertex, x


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("results")
    ap.add_argument("-o", "--out", default=None)
    a = ap.parse_args()
    runs = [r for r in xbruns.load(a.results, datasets=("final_positions",))
            if r["attrs"].get("scene") == "cloth_hang" and len(r["data"].get("final_positions", [])) > 0]
    if not runs:
        sys.exit(f"{a.results}: no cloth_hang runs with final positions")
    data = [(r, *strains(r)) for r in runs]
    vmax = max(float(pv.max()) for _, _, pv, _ in data) or 1e-12
    fig, axes = plt.subplots(1, len(data), figsize=(4.2 * len(data), 4.2), squeeze=False)
    for ax, (r, s, pv, x) in zip(axes[0], data):
        sc = ax.scatter(x[:, 0], x[:, 1], c=pv, s=4, cmap="magma", vmin=0, vmax=vmax)
        at = r["attrs"]
        ax.set_title(f"{at.get('solver')}: max strain {s.max():.2%}, mean {s.mean():.2%}\n"
                     f"{at.get('status')}, dual residual {float(at.get('final_dual_residual', np.nan)):.1e}",
                     fontsize=9)
        ax.set_aspect("equal")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        print(f"{r['name']}\t{at.get('solver')}\tmax_strain={s.max():.6g}\tmean_strain={s.mean():.6g}\t"
              f"status={at.get('status')}\tfinal_dual_residual={at.get('final_dual_residual')}")
    fig.colorbar(sc, ax=list(axes[0]), label="largest edge strain at the vertex")
    fig.suptitle("hanging cloth after the run (front view)")
    xbruns.save(fig, a.out or xbruns.default_out(a.results, "cloth_stretch"))


if __name__ == "__main__":
    main()
