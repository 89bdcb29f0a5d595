#!/usr/bin/env python3
"""How far each solver leaves a hanging cloth stretched (the paper's Fig. 8).

usage: python3 plots/cloth_stretch.py RESULTS.h5 [-o OUT.png]

For every cloth_hang run: the final positions (dataset final_positions) and the edges with their
rest lengths (datasets distance_edges, distance_rest_length; older files: the N×N grid with one
diagonal per quad rebuilt from attributes resolution, size); edge strain = |p−q|/l0 − 1.
One view along x (z, y) per run, vertices coloured by the largest strain of their edges, titled with
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



def cloth_strains(run):
    """(per-edge strain |p−q|/l0 − 1, per-vertex largest strain, positions) of a cloth run.

    Edges and rest lengths from the datasets distance_edges / distance_rest_length when the run
    has them, else the grid of problems/generators make_cloth_grid(N) (vertex (i, k) = i·(N+1)+k,
    edges along k, along i and one diagonal per quad) from the attributes resolution and size.
    """
    d = run["data"]
    x = np.asarray(d["final_positions"], dtype=float).reshape(-1, 3)
    if "distance_edges" in d and "distance_rest_length" in d:
        e = np.asarray(d["distance_edges"]).astype(int).reshape(-1, 2)
        l0 = np.asarray(d["distance_rest_length"], dtype=float)
    else:
        a = run["attrs"]
        n, size = int(a["resolution"]), float(a["size"])
        n1 = n + 1
        if x.shape[0] != n1 * n1:
            raise ValueError(f"{run['name']}: {x.shape[0]} positions, expected {n1 * n1} for a {n}x{n} cloth")
        idx = np.arange(n1 * n1).reshape(n1, n1)
        e = np.concatenate([np.stack([idx[:, :-1].ravel(), idx[:, 1:].ravel()], 1),
                            np.stack([idx[:-1, :].ravel(), idx[1:, :].ravel()], 1),
                            np.stack([idx[:-1, :-1].ravel(), idx[1:, 1:].ravel()], 1)])
        k, i = np.meshgrid(np.arange(n1), np.arange(n1))
        rest = np.stack([size * k.ravel() / n, np.zeros(n1 * n1), size * i.ravel() / n], 1)
        l0 = np.linalg.norm(rest[e[:, 0]] - rest[e[:, 1]], axis=1)
    s = np.linalg.norm(x[e[:, 0]] - x[e[:, 1]], axis=1) / l0 - 1.0
    per_vertex = np.zeros(x.shape[0])
    np.maximum.at(per_vertex, e[:, 0], s)
    np.maximum.at(per_vertex, e[:, 1], s)
    return s, per_vertex, x


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("results")
    ap.add_argument("-o", "--out", default=None)
    a = ap.parse_args()
    runs = [r for r in xbruns.load(a.results, datasets=("final_positions", "distance_edges", "distance_rest_length"))
            if r["attrs"].get("scene") == "cloth_hang" and len(r["data"].get("final_positions", [])) > 0]
    if not runs:
        sys.exit(f"{a.results}: no cloth_hang runs with final positions")
    data = [(r, *cloth_strains(r)) for r in runs]
    vmax = max(float(pv.max()) for _, _, pv, _ in data) or 1e-12
    fig, axes = plt.subplots(1, len(data), figsize=(5.4 * len(data), 4.4), squeeze=False)
    for ax, (r, s, pv, x) in zip(axes[0], data):
        sc = ax.scatter(x[:, 2], x[:, 1], c=pv, s=6, cmap="magma", vmin=0, vmax=vmax)
        at = r["attrs"]
        ax.set_title(f"{at.get('solver')}: max strain {s.max():.3g}, mean {s.mean():.3g}\n"
                     f"{at.get('status')}, dual residual {float(at.get('final_dual_residual', 'nan')):.1e}",
                     fontsize=8)
        ax.set_xlabel("z (m)")
        ax.set_ylabel("y (m)")
        print(f"{r['name']}\t{at.get('solver')}\tmax_strain={s.max():.6g}\tmean_strain={s.mean():.6g}\t"
              f"status={at.get('status')}\tfinal_dual_residual={at.get('final_dual_residual')}")
    fig.colorbar(sc, ax=list(axes[0]), label="largest edge strain at the vertex")
    fig.suptitle("hanging cloth after the run, seen along x (the pinned corners are at x = size)", y=1.03)
    xbruns.save(fig, a.out or xbruns.default_out(a.results, "cloth_stretch"))


if __name__ == "__main__":
    main()
