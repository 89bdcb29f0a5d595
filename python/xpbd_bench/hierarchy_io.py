"""The exported hierarchy in a capture's HDF5 file (PREFIX.h5, beside the system), read by
gpu_bench with h5py alone (no C++ build). Layout of /hierarchy/<form> (form: dual | primal):
  attributes   precision, coarse_solver, block_size, num_levels, and the resolved amg.* settings
  matrix/      the form's matrix (dual A, primal K) as indptr, indices, data; rhs: b or f
  dual_map/    primal only: G = J_F M_F^-1 (constraints x rows of K), so that G r_K is the dual
               residual of a primal residual r_K; dual_rhs: the dual b (its norm is the scale)
  level_<l>/   A and P (CSR groups as matrix/; P absent on the coarsest level; R = P^T is not
               stored; level 0's A not either where it is the matrix: attribute A_is_matrix) and,
               where the level has one, smoother/ with attributes kind, polynomial, sweeps,
               degree, lambda_max, lower, upper and datasets steps (k x 2), inv_diag or node_start
               and block_inv (python/xpbd_bench/amg.py's export()).
Datasets are gzip-compressed (a device call carries at most 64 MiB: docs/gpu.md)."""
import numpy as np
import scipy.sparse

SMOOTHER_ATTRS = ("kind", "polynomial", "sweeps", "degree", "lambda_max", "lower", "upper")


def form_data(system, form):
    """The form's matrix and right-hand side, and the primal form's dual map, from a System."""
    if form == "dual":
        return {"matrix": system.A, "rhs": system.b}
    free = np.asarray(system.free_particles)
    cols = (3 * free[:, None] + np.arange(3)).ravel()
    w = np.repeat(np.asarray(system.inv_mass)[free], 3)
    G = scipy.sparse.csr_matrix(system.J)[:, cols] @ scipy.sparse.diags(w)
    return {"matrix": system.K, "rhs": system.f, "dual_map": scipy.sparse.csr_matrix(G), "dual_rhs": system.b}


def _put(g, name, a):
    a = np.asarray(a)
    if a.size < 1024:
        g[name] = a
    else:
        g.create_dataset(name, data=a, compression="gzip", compression_opts=4, shuffle=True)


def _write_csr(g, name, M):
    M = scipy.sparse.csr_matrix(M)
    s = g.create_group(name)
    s.attrs["shape"] = np.asarray(M.shape, dtype=np.int64)
    _put(s, "indptr", M.indptr.astype(np.int64))
    _put(s, "indices", M.indices.astype(np.int32))
    _put(s, "data", M.data)


def _same(A, B):
    A, B = scipy.sparse.csr_matrix(A), scipy.sparse.csr_matrix(B)
    return A.shape == B.shape and A.nnz == B.nnz and np.array_equal(A.indptr, B.indptr) and \
        np.array_equal(A.indices, B.indices) and np.array_equal(A.data, B.data)


def _read_csr(g):
    shape = tuple(int(v) for v in g.attrs["shape"]) if "shape" in g.attrs else None
    indptr = g["indptr"][()]
    if shape is None:
        shape = (len(indptr) - 1, len(indptr) - 1)
    return scipy.sparse.csr_matrix((g["data"][()], g["indices"][()].astype(np.int32), indptr.astype(np.int32)),
                                   shape=shape)


def write(path, form, export, data, options=None):
    """Writes (replaces) /hierarchy/<form> of the HDF5 file at path."""
    import h5py
    with h5py.File(path, "a") as f:
        top = f.require_group("hierarchy")
        if form in top:
            del top[form]
        g = top.create_group(form)
        for k in ("precision", "coarse_solver", "block_size"):
            g.attrs[k] = export[k]
        g.attrs["num_levels"] = len(export["levels"])
        for k, v in (options or {}).items():
            g.attrs[k] = v
        _write_csr(g, "matrix", data["matrix"])
        _put(g, "rhs", np.asarray(data["rhs"], dtype=np.float64))
        if "dual_map" in data:
            _write_csr(g, "dual_map", data["dual_map"])
            _put(g, "dual_rhs", np.asarray(data["dual_rhs"], dtype=np.float64))
        for l, L in enumerate(export["levels"]):
            lg = g.create_group(f"level_{l}")
            if l == 0 and _same(L["A"], data["matrix"]):
                lg.attrs["A_is_matrix"] = 1
            else:
                _write_csr(lg, "A", L["A"])
            if L.get("P") is not None:
                _write_csr(lg, "P", L["P"])
            s = L.get("smoother")
            if s is None:
                continue
            sg = lg.create_group("smoother")
            for k in SMOOTHER_ATTRS:
                sg.attrs[k] = s[k]
            for k in ("steps", "inv_diag", "node_start", "block_inv"):
                if s.get(k) is not None:
                    _put(sg, k, s[k])


def forms(path):
    """The forms with an exported hierarchy in the file."""
    import h5py
    with h5py.File(path, "r") as f:
        return sorted(f["hierarchy"].keys()) if "hierarchy" in f else []


def read(path, form):
    """(export, data): the hierarchy as AmgHierarchy.export() gives it, and form_data's dict."""
    import h5py
    with h5py.File(path, "r") as f:
        if "hierarchy" not in f or form not in f["hierarchy"]:
            raise ValueError(f"{path}: no exported hierarchy of the {form} form (xpbd_bench.export_hierarchy writes it)")
        g = f["hierarchy"][form]
        export = {k: g.attrs[k] for k in ("precision", "coarse_solver")}
        export = {k: v.decode() if isinstance(v, bytes) else str(v) for k, v in export.items()}
        export["block_size"] = int(g.attrs["block_size"])
        data = {"matrix": _read_csr(g["matrix"]), "rhs": g["rhs"][()]}
        export["levels"] = [_read_level(g[f"level_{l}"], data["matrix"]) for l in range(int(g.attrs["num_levels"]))]
        if "dual_map" in g:
            data["dual_map"], data["dual_rhs"] = _read_csr(g["dual_map"]), g["dual_rhs"][()]
        data["attrs"] = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}
        return export, data


def _read_level(lg, matrix):
    L = {name: _read_csr(lg[name]) if name in lg else None for name in ("A", "P")}
    if lg.attrs.get("A_is_matrix", 0):
        L["A"] = matrix
    L["R"] = L["P"].T.tocsr() if L["P"] is not None else None
    L["smoother"] = None
    if "smoother" in lg:
        sg = lg["smoother"]
        s = {k: sg.attrs[k] for k in SMOOTHER_ATTRS}
        s["kind"] = s["kind"].decode() if isinstance(s["kind"], bytes) else str(s["kind"])
        s["polynomial"] = bool(s["polynomial"])
        for k in ("steps", "inv_diag", "node_start", "block_inv"):
            s[k] = sg[k][()] if k in sg else None
        L["smoother"] = s
    return L


def slim_copy(src, dst):
    """What gpu_bench reads of a capture, compressed, into dst: the root attributes, /b, /J,
    /inverse_mass, /alpha_tilde (the dual A is J M^-1 J^T + alpha~) and /hierarchy."""
    import h5py
    with h5py.File(src, "r") as f, h5py.File(dst, "w") as g:
        for k, v in f.attrs.items():
            g.attrs[k] = v
        for name in ("b", "inverse_mass", "alpha_tilde"):
            _put(g, name, f[name][()])
        J = g.create_group("J")
        for k in ("indptr", "indices", "data"):
            _put(J, k, f["J"][k][()])
        f.copy(f["hierarchy"], g, "hierarchy")


def dual_matrix(f):
    """The capture's dual A: /A, or J M^-1 J^T + alpha~ from /J (a slim copy)."""
    if "A" in f:
        return _read_csr(f["A"])
    w = np.repeat(f["inverse_mass"][()], 3)
    Jg = f["J"]
    indptr = Jg["indptr"][()]
    J = scipy.sparse.csr_matrix((Jg["data"][()], Jg["indices"][()], indptr), shape=(len(indptr) - 1, w.size))
    return scipy.sparse.csr_matrix(J @ scipy.sparse.diags(w) @ J.T + scipy.sparse.diags(f["alpha_tilde"][()]))
