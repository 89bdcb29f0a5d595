#!/usr/bin/env python3
"""Writes the hostile-input corpus (tests/data/hostile/): malformed results, system and state HDF5
files, scene TOMLs, sweep specs and meshes. The files are committed; rerun this after changing it:
    python3 tests/data/hostile/make_hostile.py
CASES.tsv (written by hand) says what each command line must answer."""
import os
import sys

import h5py
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
STR = h5py.string_dtype("utf-8")


def path(name):
    return os.path.join(HERE, name)


def text(name, body):
    with open(path(name), "w") as f:
        f.write(body)


# ---- results files: one good run, then the damage ----------------------------------------------
def good_run(g, name, solver):
    r = g.create_group(name)
    for k, v in {"level": "simulation", "scene": "cloth_hang", "solver": solver, "status": "ok",
                 "form_used": "dual", "message": ""}.items():
        r.attrs.create(k, v, dtype=STR)
    r.attrs["outer_iterations"] = np.int64(2)
    r.attrs["final_dual_residual"] = 1e-15
    r.create_dataset("dual_residual", data=np.array([1.0, 1e-15]))
    return r


def results(name, damage):
    with h5py.File(path(name), "w") as f:
        f.attrs["schema_version"] = np.int64(1)
        f.attrs.create("generator", "xpbd-bench", dtype=STR)
        runs = f.create_group("runs")
        good_run(runs, "0001_cloth_hang_cholmod", "cholmod")
        damage(f, runs)


def bad_attr(value, **kw):
    def damage(f, runs):
        r = good_run(runs, "0002_cloth_hang_bad", "xpbd-gs")
        del r.attrs["status"]
        r.attrs.create("status", value, **kw)
    return damage


def results_corpus():
    results("attr_int_array.h5", bad_attr(np.array([1, 2, 3], dtype=np.int64)))
    results("attr_float_2d.h5", bad_attr(np.ones((2, 2))))
    results("attr_fixed_string_array.h5", bad_attr(np.array([b"ok", b"error"], dtype="S5")))
    results("attr_vlen_string_array.h5", bad_attr(np.array(["ok", "nan"], dtype=object), dtype=STR))
    results("attr_empty_array.h5", bad_attr(np.zeros(0)))
    results("attr_null.h5", bad_attr(h5py.Empty("f8")))
    results("attr_compound.h5", bad_attr(np.array((1, 2.0), dtype=[("a", "i4"), ("b", "f8")])))
    results("attr_bool.h5", bad_attr(np.bool_(True)))
    results("attr_fixed_string_scalar.h5", bad_attr(np.bytes_(b"fixedok\0\0")))  # readable: not damage
    results("attr_huge_fixed_string.h5", bad_attr(np.bytes_(b"x" * 4096)))  # readable too

    def dangling(f, runs):
        runs["0002_cloth_hang_bad"] = h5py.SoftLink("/nowhere")
    results("run_dangling_link.h5", dangling)

    def external(f, runs):
        runs["0002_cloth_hang_bad"] = h5py.ExternalLink("no_such_file.h5", "/x")
    results("run_external_link.h5", external)

    def dataset(f, runs):
        runs.create_dataset("0002_cloth_hang_bad", data=np.arange(3.0))
    results("run_is_dataset.h5", dataset)

    def datasets_bad(f, runs):
        r = good_run(runs, "0002_cloth_hang_bad", "xpbd-gs")
        r.create_dataset("iteration", data=np.zeros((2, 3)))
    results("run_dataset_2d.h5", datasets_bad)

    def all_bad(f, runs):
        del runs["0001_cloth_hang_cholmod"]
        runs["0001_a"] = h5py.SoftLink("/nowhere")
        runs.create_dataset("0002_b", data=np.arange(3.0))
    results("all_runs_bad.h5", all_bad)

    with h5py.File(path("no_runs.h5"), "w") as f:
        f.attrs["schema_version"] = np.int64(1)
        f.create_group("other")
    with h5py.File(path("runs_is_dataset.h5"), "w") as f:
        f.create_dataset("runs", data=np.arange(4))
    with h5py.File(path("runs_dangling.h5"), "w") as f:
        f["runs"] = h5py.SoftLink("/gone")
    text("not_hdf5.h5", "this is not an HDF5 file\n")
    text("empty.h5", "")
    with open(path("attr_int_array.h5"), "rb") as f:
        head = f.read(1200)
    with open(path("truncated.h5"), "wb") as f:
        f.write(head)


# ---- captured systems: a 4-row SPD system with its primal data, then the damage -----------------
def system(name, damage=None):
    n, npart = 4, 5
    A = 4 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    indptr, indices, data = [0], [], []
    for i in range(n):
        for j in range(n):
            if A[i, j] != 0:
                indices.append(j)
                data.append(A[i, j])
        indptr.append(len(indices))
    # J: constraint i couples particles i and i+1 (3 columns each).
    jp, ji, jd = [0], [], []
    for i in range(n):
        for p in (i, i + 1):
            for d in range(3):
                ji.append(3 * p + d)
                jd.append(1.0 if p == i else -1.0)
        jp.append(len(ji))
    with h5py.File(path(name), "w") as f:
        f.attrs.create("kind", "dual_system", dtype=STR)
        f.attrs.create("scene", "cloth_hang", dtype=STR)
        f.attrs["rows"] = np.int64(n)
        f.attrs["nnz"] = np.int64(len(data))
        f["A/indptr"] = np.array(indptr, dtype=np.int64)
        f["A/indices"] = np.array(indices, dtype=np.int64)
        f["A/data"] = np.array(data)
        f["b"] = np.ones(n)
        f["J/indptr"] = np.array(jp, dtype=np.int64)
        f["J/indices"] = np.array(ji, dtype=np.int64)
        f["J/data"] = np.array(jd)
        f["inverse_mass"] = np.ones(npart)
        f["alpha_tilde"] = np.full(n, 1e-3)
        f["positions"] = np.zeros(3 * npart)
        if damage:
            damage(f)


def replace(name, value):
    def damage(f):
        del f[name]
        f[name] = value
    return damage


def system_corpus():
    system("system_good.h5")
    system("indptr_overrun.h5", replace("A/indptr", np.array([0, 2, 1 << 40, 7, 10], dtype=np.int64)))
    system("indptr_last_overrun.h5", replace("A/indptr", np.array([0, 2, 5, 8, 99], dtype=np.int64)))
    system("indptr_short.h5", replace("A/indptr", np.array([0, 2, 5], dtype=np.int64)))
    system("indptr_nonzero_start.h5", replace("A/indptr", np.array([1, 2, 5, 8, 10], dtype=np.int64)))
    system("indptr_decreasing.h5", replace("A/indptr", np.array([0, 5, 2, 8, 10], dtype=np.int64)))
    system("indptr_floats.h5", replace("A/indptr", np.array([0, 2, 5, 8, 10], dtype=np.float64)))
    system("indptr_strings.h5", replace("A/indptr", np.array(["0", "2", "5", "8", "10"], dtype=object).astype(STR)))
    system("indptr_2d.h5", replace("A/indptr", np.zeros((5, 2), dtype=np.int64)))
    system("indices_out_of_range.h5", replace("A/indices", np.array([0, 1, 0, 1, 2, 1, 2, 3, 2, 99], dtype=np.int64)))
    system("indices_unsorted.h5", replace("A/indices", np.array([1, 0, 0, 1, 2, 1, 2, 3, 2, 3], dtype=np.int64)))
    system("indices_data_mismatch.h5", replace("A/indices", np.array([0, 1, 0, 1, 2], dtype=np.int64)))
    system("indices_compound.h5", replace("A/indices", np.zeros(10, dtype=[("a", "i4"), ("b", "f8")])))
    system("b_missing.h5", lambda f: f.__delitem__("b"))
    system("b_group.h5", replace("b", None) if False else (lambda f: (f.__delitem__("b"), f.create_group("b"))))
    system("b_dangling.h5", lambda f: (f.__delitem__("b"), f.__setitem__("b", h5py.SoftLink("/nothing"))))
    system("b_empty.h5", replace("b", np.zeros(0)))
    system("b_scalar.h5", replace("b", np.float64(1.0)))
    system("b_huge_extent.h5", lambda f: (f.__delitem__("b"), f.create_dataset("b", shape=(1 << 40,), dtype="f8", chunks=(1024,))))
    # Declared extents the file does not store (found by fuzzing): read, they would be allocated in full.
    system("J_indptr_unwritten_chunks.h5", lambda f: (f.__delitem__("J/indptr"),
                                                      f.create_dataset("J/indptr", shape=(1 << 27,), dtype="i1", chunks=(64,))))
    system("b_unwritten.h5", lambda f: (f.__delitem__("b"), f.create_dataset("b", shape=(1 << 28,), dtype="f8")))
    system("A_is_dataset.h5", lambda f: (f.__delitem__("A"), f.create_dataset("A", data=np.eye(4))))
    system("A_dangling.h5", lambda f: (f.__delitem__("A"), f.__setitem__("A", h5py.SoftLink("/Z"))))
    system("kind_missing.h5", lambda f: f.attrs.__delitem__("kind"))
    system("kind_array.h5", lambda f: f.attrs.__setitem__("kind", np.array([b"dual_system", b"x"], dtype="S12")))
    system("kind_int.h5", lambda f: f.attrs.__setitem__("kind", np.int64(7)))
    system("rows_attr_array.h5", lambda f: f.attrs.__setitem__("rows", np.arange(4)))
    system("J_is_dataset.h5", lambda f: (f.__delitem__("J"), f.create_dataset("J", data=np.zeros(3))))
    system("J_no_inverse_mass.h5", lambda f: f.__delitem__("inverse_mass"))
    system("alpha_tilde_short.h5", replace("alpha_tilde", np.ones(2)))
    system("positions_short.h5", replace("positions", np.zeros(7)))
    system("J_five_particles.h5", replace("J/indices", np.array(  # row 0: particles 0, 1, 2, 3, 4
        [0, 3, 6, 9, 12, 13, 3, 4, 5, 6, 7, 8, 6, 7, 8, 9, 10, 11, 9, 10, 11, 12, 13, 14], dtype=np.int64)))
    system("J_indices_out_of_range.h5", replace("J/indices", np.array(
        [0, 1, 2, 3, 4, 5, 3, 4, 5, 6, 7, 8, 6, 7, 8, 9, 10, 11, 9, 10, 11, 12, 13, 99], dtype=np.int64)))
    system("A_data_nan_indptr_overrun.h5", lambda f: (replace("A/indptr", np.array([0, 2, 5, 8, 11], dtype=np.int64))(f)))


# ---- state files --------------------------------------------------------------------------------
def state(name, damage=None, n=25):
    with h5py.File(path(name), "w") as f:
        f.attrs.create("kind", "state", dtype=STR)
        f.attrs["frame"] = np.int64(1)
        f.attrs["particles"] = np.int64(n)
        f["positions"] = np.zeros(3 * n)
        f["velocities"] = np.zeros(3 * n)
        if damage:
            damage(f)


def state_corpus():
    state("state_frame_string.h5", lambda f: f.attrs.create("frame", "one", dtype=STR))
    state("state_frame_huge.h5", lambda f: f.attrs.__setitem__("frame", np.int64(1 << 40)))
    state("state_particles_negative.h5", lambda f: f.attrs.__setitem__("particles", np.int64(-3)))
    state("state_positions_short.h5", replace("positions", np.zeros(5)))
    state("state_no_velocities.h5", lambda f: f.__delitem__("velocities"))
    state("state_positions_strings.h5", replace("positions", np.array(["a"] * 75, dtype=object).astype(STR)))
    state("state_kind_array.h5", lambda f: f.attrs.__setitem__("kind", np.array([b"state", b"state"], dtype="S5")))
    state("state_wrong_particles.h5", n=7)
    state("state_velocities_dangling.h5", lambda f: (f.__delitem__("velocities"), f.__setitem__("velocities", h5py.SoftLink("/v"))))


# ---- scene TOMLs, sweep specs, meshes ------------------------------------------------------------
SCENES = {
    "scene_empty.toml": "",
    "scene_comments_only.toml": "# nothing here\n",
    "scene_no_scene_key.toml": "resolution = 4\n",
    "scene_malformed.toml": "scene = \"cloth_hang\"\nresolution = = 4\n",
    "scene_unknown_key.toml": "scene = \"cloth_hang\"\ncolour = 3\n",
    "scene_list_value.toml": "scene = \"cloth_hang\"\nresolution = [4, 8]\n",
    "scene_dt_underflow.toml": "scene = \"cloth_hang\"\ndt = 1e-320\n",
    "scene_dt_nan.toml": "scene = \"cloth_hang\"\ndt = nan\n",
    "scene_dt_inf.toml": "scene = \"cloth_hang\"\ndt = inf\n",
    "scene_dt_string.toml": "scene = \"cloth_hang\"\ndt = \"fast\"\n",
    "scene_resolution_fraction.toml": "scene = \"cloth_hang\"\nresolution = 4.5\n",
    "scene_resolution_huge.toml": "scene = \"cloth_hang\"\nresolution = 1e12\n",
    "scene_unknown_builder.toml": "scene = \"teapot\"\n",
    "scene_mesh_on_cloth.toml": "scene = \"cloth_hang\"\nmesh = \"ball\"\n",
    "scene_twist_on_cloth.toml": "scene = \"cloth_hang\"\ntwist = 1.0\n",
    "scene_prestretch_on_squash.toml": "scene = \"squash\"\nresolution = 3\nprestretch = 1.1\n",
    "scene_init_on_cloth.toml": "scene = \"cloth_hang\"\ninit = \"enlarge\"\n",
    "scene_mesh_height_on_cloth.toml": "scene = \"cloth_hang\"\nmesh_height = 0.2\n",
    "scene_date_value.toml": "scene = \"cloth_hang\"\ndt = 1979-05-27\n",
    "scene_builder_number.toml": "scene = 3\n",
    "scene_bad_variant.toml": "scene = \"cloth_hang\"\nvariant = \"mushy\"\n",
    "scene_nested_unknown.toml": "scene = \"cloth_hang\"\n[a.b]\nc = 1\n",
    "scene_duplicate_key.toml": "scene = \"cloth_hang\"\ndt = 0.1\ndt = 0.2\n",
    "scene_zero_iterations.toml": "scene = \"cloth_hang\"\nmax_iterations = 0\n",
    "scene_negative_frames.toml": "scene = \"cloth_hang\"\nframes = -1\n",
    "scene_solvers_key.toml": "scene = \"cloth_hang\"\nsolvers = [\"cholmod\"]\n",
    "scene_negative_compliance.toml": "scene = \"cloth_hang\"\ncompliance = -1e-8\n",
    "scene_overflow.toml": "scene = \"cloth_hang\"\ngravity = 1e999\n",
    "scene_mesh_directory.toml": "scene = \"squash\"\nmesh = \"tests/data\"\n",
    "scene_mesh_missing.toml": "scene = \"squash\"\nmesh = \"no/such/mesh.msh\"\n",
    "scene_mesh_unknown_format.toml": "scene = \"squash\"\nmesh = \"tests/data/broken/cube.obj\"\n",
    "scene_array_of_tables.toml": "scene = \"cloth_hang\"\n[[runs]]\nx = 1\n",
    # Valid inputs, for the cases where an output names an input.
    "scene_valid.toml": "scene = \"cloth_hang\"\nresolution = 4\n",
    "capture_scene_A.mtx": "scene = \"cloth_hang\"\nresolution = 4\n",
    "profile_valid.toml": "rtol = 1e-6\n",
}

HEAD = "scene = \"cloth_hang\"\nsolvers = [\"cholmod\"]\n[set]\nresolution = 4\n"
axes16 = "".join("\"%s\" = [%s]\n" % (k, ", ".join(repr(v) for v in vals)) for k, vals in [
    ("gravity", [-1.0 - i for i in range(16)]), ("compliance", [1e-8 * (i + 1) for i in range(16)]),
    ("particle_mass", [1.0 + i for i in range(16)]), ("dt", [1e-3 * (i + 1) for i in range(16)]),
    ("size", [1.0 + i for i in range(16)]), ("rtol", [1e-6 * (i + 1) for i in range(16)]),
    ("atol", [1e-12 * (i + 1) for i in range(16)]), ("omega", [0.1 * (i + 1) for i in range(16)]),
    ("seed", [i for i in range(16)]), ("mass_ratio", [1.0 + i for i in range(16)]),
    ("linear.tol", [1e-8 * (i + 1) for i in range(16)]), ("amg.strength_threshold", [0.05 * i for i in range(16)]),
    ("stiffness", [1e6 * (i + 1) for i in range(16)]), ("substeps", [i + 1 for i in range(16)]),
    ("max_iterations", [i + 1 for i in range(16)]), ("linear.max_iterations", [i + 1 for i in range(16)])])
SPECS = {
    "spec_grid_2_64.toml": "scene = \"cloth_hang\"\nsolvers = [\"cholmod\"]\n[set]\nresolution = 4\n[grid]\n" + axes16,
    "spec_no_scene.toml": "solvers = [\"cholmod\"]\n",
    "spec_no_solvers.toml": "scene = \"cloth_hang\"\n",
    "spec_empty.toml": "",
    "spec_empty_grid_list.toml": HEAD + "[grid]\ndt = []\n",
    "spec_bad_grid_value.toml": HEAD + "[grid]\ndt = [0.001, -1]\n",
    "spec_unknown_key.toml": HEAD.replace("[set]", "colour = 1\n[set]"),
    "spec_duplicate_grid_value.toml": HEAD + "[grid]\ndt = [0.001, 1e-3]\n",
    "spec_repeats_zero.toml": HEAD.replace("[set]", "repeats = 0\n[set]"),
    "spec_repeats_huge.toml": HEAD.replace("[set]", "repeats = 1e12\n[set]"),
    "spec_time_budget_negative.toml": HEAD.replace("[set]", "time_budget = -1\n[set]"),
    "spec_time_budget_text.toml": HEAD.replace("[set]", "time_budget = \"long\"\n[set]"),
    "spec_reference_no.toml": HEAD.replace("[set]", "reference = \"no\"\n[set]"),
    "spec_set_and_grid.toml": HEAD + "[grid]\nresolution = [4, 5]\n",
    "spec_grid_scene.toml": HEAD + "[grid]\nscene = [\"cloth_hang\", \"bar_hang\"]\n",
    "spec_solver_twice.toml": "scene = \"cloth_hang\"\nsolvers = [\"cholmod\", \"cholmod\"]\n",
    "spec_unknown_solver.toml": "scene = \"cloth_hang\"\nsolvers = [\"cholmod\", \"warp-drive\"]\n",
    "spec_mesh_on_cloth.toml": HEAD + "mesh = \"ball\"\n",
    "spec_grid_dt_underflow.toml": HEAD + "[grid]\ndt = [1e-3, 1e-320]\n",
    "spec_scene_missing_file.toml": "scene = \"nowhere/scene.toml\"\nsolvers = [\"cholmod\"]\n",
    "spec_set_list.toml": HEAD + "dt = [1, 2]\n",
    "spec_grid_scalar.toml": HEAD + "[grid]\ndt = 0.001\n",
    "spec_sizes_not_table.toml": HEAD.replace("[set]", "sizes = 3\n[set]"),
    "spec_frames_huge.toml": HEAD.replace("[set]", "frames = 1e12\n[set]"),
    "spec_good.toml": HEAD,
}

MESHES = {
    # Declared counts larger than the data: the message must be about the count.
    "count_big.mesh": "MeshVersionFormatted 2\nDimension 3\nVertices\n10\n0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\n"
                      "Tetrahedra\n1\n1 2 3 4 0\nEnd\n",
    "count_big_tets.mesh": "MeshVersionFormatted 2\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\n"
                           "Tetrahedra\n5\n1 2 3 4 0\nEnd\n",
    "count_big22.msh": "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n10\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n"
                       "$Elements\n1\n1 4 2 0 0 1 2 3 4\n$EndElements\n",
    "count_big_elements22.msh": "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n"
                                "$EndNodes\n$Elements\n7\n1 4 2 0 0 1 2 3 4\n$EndElements\n",
    "count_big.node": "10 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n",
    "count_big.ele": "1 4 0\n0 0 1 2 3\n",
    "count_big_tets.node": "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n",
    "count_big_tets.ele": "6 4 0\n0 0 1 2 3\n",
}


def main():
    results_corpus()
    system_corpus()
    state_corpus()
    for name, body in {**SCENES, **SPECS, **MESHES}.items():
        text(name, body)
    os.makedirs(path("a_directory.toml"), exist_ok=True)
    text(os.path.join("a_directory.toml", "README"), "A directory named like a scene file.\n")
    text("results_is_text.h5", "not a results file\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
