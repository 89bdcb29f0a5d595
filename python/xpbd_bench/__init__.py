"""xpbd_bench: the XPBD solver benchmark from Python (docs/python.md).

    import xpbd_bench as xb
    xb.scenes(); xb.solvers(); xb.parameters()           # what `xpbd-bench list` prints
    xb.run("squash", solvers=["mgpbd", MySolver()], out="r.h5", frames=1, set={"mesh": "bunny:12k"})
    sys = xb.capture("cloth_hang", frame=0, iteration=0, set={"resolution": 16})
    xb.solve(sys, solvers=["cholmod", MySolver()], form="primal", tol=1e-8, out="s.h5")
    runs = xb.read("r.h5")
    xb.pack("r.h5", "one.h5")                            # every run in one file, to hand on
    xb.repair("r.h5")                                    # the index rebuilt from the run files

A solver is any object with `name`, `setup(A, info)` and `solve(b, tol)` returning x or
(x, iterations); it runs inside the C++ stepper as the method py:<name>. run, capture and solve
are the CLI's commands (same checks, same files, same records); calls from several threads at
once are safe, and many processes may append to one results file (docs/failures.md). xpbd_bench.gpu.MgpbdGpu is mgpbd
with its solve phase on a GPU (docs/gpu.md); amg_hierarchy gives mgpbd's levels.

Without the built module _core, only the modules that do not need it import (xpbd_bench.gpu's
solve phase, xpbd_bench.gpu_bench); the calls here then raise ImportError naming it.
"""
import os
import sys
import tempfile

# OpenMP threads that sleep at barriers (the reason is in the Makefile): libgomp reads these when
# it loads, which is when _core is imported, so they are set first unless the user chose.
if "OMP_WAIT_POLICY" not in os.environ:
    os.environ["OMP_WAIT_POLICY"] = "passive"
    os.environ.setdefault("GOMP_SPINCOUNT", "10000")
# A Python solver's BLAS on one thread unless the user chose (read when numpy loads, so only if
# it has not yet): OpenBLAS's threads spin after each call and took the cores of the harness's
# OpenMP team (pyamg on a small primal squash, 2 cores: 14 s -> 0.3 s of solve; docs/python.md).
if "numpy" not in sys.modules:
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

try:
    from . import _core  # noqa: E402
except ImportError as _missing:  # a GPU machine with the Python files only (gpu_bench)
    _core_error = _missing

    class _Missing:
        def __getattr__(self, name):
            raise ImportError(f"xpbd_bench._core is not built ({_core_error}): build the project (docs/python.md)")

    _core = _Missing()

    class Error(ValueError):
        """xpbd_bench's error (the built module's, when it is there)."""
else:
    from ._core import Error, System, WriteError, scenes, parameters  # noqa: E402
    from .amg import AmgHierarchy, amg_hierarchy, export_hierarchy  # noqa: E402

__all__ = ["Error", "WriteError", "System", "scenes", "solvers", "parameters", "run", "capture", "solve", "read",
           "pack", "repair", "load_system", "AmgHierarchy", "amg_hierarchy", "export_hierarchy"]


def solvers():
    """The built-in methods (dicts: name, kind, available, reason, description), and
    py:mgpbd-gpu (xpbd_bench.gpu.MgpbdGpu): available says whether CuPy found a device (without one
    it runs on NumPy), reason which device or why none."""
    from .gpu import device_info
    found, why = device_info()
    return _core.solvers() + [{"name": "py:mgpbd-gpu", "kind": "global", "available": found, "reason": why,
                               "description": "mgpbd with its V-cycle (float) and PCG on a GPU through CuPy "
                                              "(xpbd_bench.gpu.MgpbdGpu(); NumPy without a device)"}]


def read(path):
    """Every run of a results file: dicts of name, attrs (every attribute), data (every dataset)."""
    return _core.read(os.fspath(path))


def load_system(path):
    """A System from a capture's PREFIX.h5."""
    return _core.load_system(os.fspath(path))


def _value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return repr(v)
    return str(v)


def _sets(values):
    return [a for k, v in (values or {}).items() for a in ("--set", f"{k}={_value(v)}")]


def _methods(solvers_):
    """--solver's list and the protocol objects among `solvers_` (names: str, objects: py:<name>)."""
    if solvers_ is None:
        raise Error("solvers is None: give a method name ('mgpbd'), a solver object of the protocol, or a list of them")
    if isinstance(solvers_, (str, bytes)) or not hasattr(solvers_, "__iter__"):
        solvers_ = [solvers_]
    names, objects = [], []
    for s in solvers_:
        if isinstance(s, str):
            names.append(s)
        else:
            names.append(_core.protocol_name(s))  # checks name, setup and solve
            objects.append(s)
    if not names:
        raise Error("no solver given")
    return ",".join(names), objects


def _call(name, args, objects, progress):
    if not progress:
        args = args + ["--quiet"]
    rc = _core.command(name, args, objects)
    if rc != 0:
        raise Error(f"{name} ended with exit code {rc} (see stderr)")


def run(scene, solvers, out, frames=None, set=None, form=None, profile=None, time_budget=None, reference=False,
        progress=False):
    """`xpbd-bench run --append`: each solver (a built-in name or a protocol object) on the scene,
    each run appended to `out` as it ends (an existing results file keeps its runs, the new ones
    numbered after them; the CLI's `run` without --append replaces its --out instead). `set`: any
    parameter keys ({"mesh": "bunny:12k", "linear.tol": 1e-2}); `form`: "dual", "primal" or
    "dual,primal" (--form). A failed write raises WriteError naming `out`, which keeps the runs
    finished before. Returns read(out)."""
    names, objects = _methods(solvers)
    out = os.fspath(out)
    _run(scene, names, objects, out, frames, set, form, profile, time_budget, reference, progress)
    return read(out)


def _run(scene, names, objects, out, frames, set, form, profile, time_budget, reference, progress):
    args = ["--scene", str(scene), "--solver", names, "--out", out, "--append"] + _sets(set)
    if frames is not None:
        args += ["--frames", str(frames)]
    if form is not None:
        args += ["--form", form]
    if profile is not None:
        args += ["--profile", profile]
    if time_budget is not None:
        args += ["--time-budget", _value(time_budget)]
    if reference:
        args.append("--reference")
    _call("run", args, objects, progress)


def capture(scene, frame, iteration, substep=0, set=None, solver="cholmod", out=None, time_budget=None,
            progress=False):
    """`xpbd-bench capture`: the linear step of (frame, substep, iteration) as a System. With out
    (a prefix), its files stay there (PREFIX.h5, PREFIX_A.mtx, ...); without, they go to a
    temporary folder that lives as long as the System."""
    names, objects = _methods([solver])
    keep = None
    if out is None:
        keep = tempfile.TemporaryDirectory(prefix="xpbd_bench_")
        out = os.path.join(keep.name, "system")
    prefix = os.fspath(out)
    prefix = prefix[:-3] if prefix.endswith(".h5") else prefix
    args = ["--scene", str(scene), "--frame", str(frame), "--substep", str(substep), "--iteration", str(iteration),
            "--solver", names, "--out", prefix] + _sets(set)
    if time_budget is not None:
        args += ["--time-budget", _value(time_budget)]
    _call("capture", args, objects, progress)
    system = load_system(prefix + ".h5")
    system._tmpdir = keep
    return system


def solve(system, solvers, out, form=None, tol=None, set=None, append=False, progress=False):
    """`xpbd-bench solve`: each solver on a captured system (a System or its .h5 path) from a fresh
    instance, against the direct reference; `out` is replaced, or added to with append=True
    (--append). Returns read(out)."""
    path = system.path if isinstance(system, System) else os.fspath(system)
    names, objects = _methods(solvers)
    args = ["--system", path, "--solver", names, "--out", os.fspath(out)] + _sets(set)
    if form is not None:
        args += ["--form", form]
    if tol is not None:
        args += ["--tol", _value(tol)]
    if append:
        args.append("--append")
    _call("solve", args, objects, progress)
    return read(out)


def pack(path, out):
    """`xpbd-bench pack`: every run of the results file `path` (an index and its folder PATH.runs/)
    in one self-contained file `out`, to hand to someone. Returns read(out)."""
    _call("pack", [os.fspath(path), "--out", os.fspath(out)], [], True)
    return read(out)


def repair(path):
    """`xpbd-bench repair`: rebuilds the index of the results file `path` (what h5py reads) from its
    run files (PATH.runs/), adopting a store whose index is gone, moving an older file into a
    store, removing what no reader needs. Returns what it found: a dict of runs (how many), packed
    (True: the runs are inline, nothing to do), relinked, dangling, removed and notes (lists)."""
    return _core.repair(os.fspath(path))
