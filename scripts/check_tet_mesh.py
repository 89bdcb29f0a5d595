#!/usr/bin/env python3
"""Checks that a TetGen .node/.ele pair is a valid closed tet mesh (scripts/get_meshes.sh runs it
on every mesh it writes):

    python3 scripts/check_tet_mesh.py MESH.node MESH.ele

valid: every tet has a volume and one orientation for all, every vertex is in a tet, no face is
shared by more than two tets, and the boundary (the faces of one tet only) is closed: every
boundary edge is in exactly two boundary faces. Prints the counts on stderr; exits 1 with one line
naming what is wrong otherwise.
"""
import sys

import numpy as np


def table(path):
    """(count in the header, the rows after it), '#' comments dropped."""
    with open(path) as f:
        rows = [line.split("#")[0].split() for line in f]
    rows = [r for r in rows if r]
    if not rows:
        raise ValueError(f"{path}: empty")
    return int(rows[0][0]), rows[1:]


def check(node, ele):
    """A one-line summary of a valid mesh; raises ValueError naming what is wrong."""
    nv, vrows = table(node)
    nt, trows = table(ele)
    if len(vrows) != nv or len(trows) != nt or nt == 0:
        raise ValueError(f"{ele}: {len(vrows)} vertices and {len(trows)} tets listed, the headers say {nv} and {nt}")
    first = int(vrows[0][0])  # TetGen numbers from 0 or 1
    V = np.array([r[1:4] for r in vrows], float)
    T = np.array([r[1:5] for r in trows], np.int64) - first
    if T.min() < 0 or T.max() >= nv:
        raise ValueError(f"{ele}: a tet names a vertex outside {first}..{nv - 1 + first}")
    a, b, c, d = (V[T[:, k]] for k in range(4))
    vol = np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) / 6
    tiny = 1e-12 * np.abs(vol).mean()
    if not ((vol > tiny).all() or (vol < -tiny).all()):
        raise ValueError(f"{ele}: {(np.abs(vol) <= tiny).sum()} flat tets, {(vol < -tiny).sum()} negative and "
                         f"{(vol > tiny).sum()} positive: not one orientation")
    unused = nv - len(np.unique(T))
    if unused:
        raise ValueError(f"{ele}: {unused} vertices in no tet")
    faces = np.sort(np.concatenate([T[:, [1, 2, 3]], T[:, [0, 2, 3]], T[:, [0, 1, 3]], T[:, [0, 1, 2]]]), axis=1)
    uf, count = np.unique(faces, axis=0, return_counts=True)
    if count.max() > 2:
        raise ValueError(f"{ele}: {(count > 2).sum()} faces shared by more than two tets")
    boundary = uf[count == 1]
    edges = np.sort(np.concatenate([boundary[:, [0, 1]], boundary[:, [1, 2]], boundary[:, [0, 2]]]), axis=1)
    _, ecount = np.unique(edges, axis=0, return_counts=True)
    if len(boundary) == 0 or (ecount != 2).any():
        raise ValueError(f"{ele}: the boundary is not closed: {(ecount != 2).sum()} boundary edges are not in "
                         "exactly two boundary faces")
    return (f"{nt} tets, {nv} vertices, {len(boundary)} boundary faces (closed), volume {np.abs(vol).sum():.6g}")


def main(argv):
    if len(argv) != 2:
        sys.exit("usage: check_tet_mesh.py MESH.node MESH.ele")
    try:
        print(f"check_tet_mesh: {check(*argv)}", file=sys.stderr)
    except (ValueError, OSError) as e:
        sys.exit(f"check_tet_mesh: {e}")


if __name__ == "__main__":
    main(sys.argv[1:])
