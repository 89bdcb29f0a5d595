"""The in-house AMG hierarchy from Python (docs/gpu.md): the C++ setup of mgpbd for a matrix and
amg.* settings, its levels as scipy/numpy objects (solvers/amg/hierarchy_export.hpp), a refresh
of values on the same pattern, and the levels written into a capture's HDF5 file for gpu_bench."""
import os

import numpy as np
import scipy.sparse

from . import _core, hierarchy_io


def _text(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    return repr(v) if isinstance(v, float) else str(v)


def _csr(A, what):
    if not scipy.sparse.issparse(A):
        raise _core.Error(f"{what}: A must be a scipy.sparse matrix (got {type(A).__name__})")
    A = scipy.sparse.csr_matrix(A)
    if A.shape[0] != A.shape[1]:
        raise _core.Error(f"{what}: A must be square (got {A.shape[0]} x {A.shape[1]})")
    if not A.has_canonical_format:
        A = A.copy()
        A.sum_duplicates()
    return (np.ascontiguousarray(A.indptr, dtype=np.int32), np.ascontiguousarray(A.indices, dtype=np.int32),
            np.ascontiguousarray(A.data, dtype=np.float64), A.shape[0])


class AmgHierarchy:
    """mgpbd's hierarchy for A: `set` holds amg.* keys (and seed) as mgpbd reads them, same
    defaults; block_size 3 and near_kernel (rows x k, the rigid modes) for the primal form.

    export(): {precision, coarse_solver, block_size, levels: [{A, P, R, smoother}]}, the levels as
    the V-cycle applies them (A, P, R: scipy CSR; smoother: kind, polynomial, sweeps, degree,
    lambda_max, lower, upper, steps (k x 2: d = c1 d + c2 D^-1 (b - A x), x += d), inv_diag or
    node_start + block_inv (row-major node blocks of D^-1); None on the coarsest level under
    coarse_solver = direct: Cholesky of its A). refresh(A): new values, same pattern; False when
    the hierarchy is stale (a new setup is due)."""

    def __init__(self, A, block_size=1, near_kernel=None, set=None):
        indptr, indices, data, n = _csr(A, "amg_hierarchy")
        if near_kernel is not None:
            near_kernel = np.ascontiguousarray(near_kernel, dtype=np.float64)
        settings = {str(k): _text(v) for k, v in (set or {}).items()}
        self._h = _core.AmgHierarchy(n, indptr, indices, data, int(block_size), near_kernel, settings)

    def refresh(self, A):
        indptr, indices, data, _ = _csr(A, "AmgHierarchy.refresh")
        return self._h._refresh(indptr, indices, data)

    def export(self):
        return self._h.export()

    def vcycle(self, b):
        """The C++ V-cycle (Hierarchy::vcycle) of b, for comparisons."""
        return self._h._vcycle(np.ascontiguousarray(b, dtype=np.float64))

    @property
    def options(self):
        return self._h.options

    @property
    def num_levels(self):
        return self._h.num_levels

    @property
    def operator_complexity(self):
        return self._h.operator_complexity


def amg_hierarchy(A, block_size=1, near_kernel=None, set=None):
    """AmgHierarchy(A, block_size, near_kernel, set)."""
    return AmgHierarchy(A, block_size, near_kernel, set)


def capture_settings(system, set=None):
    """The amg.* keys and seed a capture was made with (what `solve` reads), then `set`'s."""
    out = {k: _text(v) for k, v in system.attrs.items() if k.startswith("amg.") or k == "seed"}
    out.update({str(k): _text(v) for k, v in (set or {}).items()})
    return out


def export_hierarchy(path, forms=("dual", "primal"), set=None):
    """Writes mgpbd's hierarchy of each form of the capture PREFIX.h5 into that file
    (/hierarchy/<form>: hierarchy_io.py's layout), with the capture's amg.* settings and seed
    overridden by `set`. A form the capture lacks (primal without J or with a zero alpha~) is
    skipped. Returns the forms written."""
    from . import load_system
    system = load_system(os.fspath(path))
    settings = capture_settings(system, set)
    written = []
    for form in (forms,) if isinstance(forms, str) else forms:
        if form not in ("dual", "primal"):
            raise _core.Error(f"export_hierarchy: form '{form}': use dual or primal")
        if form == "primal" and system.K is None:
            continue
        h = AmgHierarchy(system.A, set=settings) if form == "dual" else \
            AmgHierarchy(system.K, 3, system.rigid_modes, settings)
        hierarchy_io.write(system.path, form, h.export(), hierarchy_io.form_data(system, form), h.options)
        written.append(form)
    return written
