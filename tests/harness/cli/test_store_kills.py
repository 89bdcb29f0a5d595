#!/usr/bin/env python3
"""Writers of a results file killed (XB_FAULT_SIGNAL=N:SIGKILL) before each of their durable steps
— an fsync of a file or a folder, a rename, a link — N = 1, 2, ... until the command ends by itself,
for run --append (into a new file and into one of two runs), sweep, run --out, the first append to a packed file and to a file of the earlier
layout, and repair (with and without an index): over 100 kills (results/README.md,
docs/failures.md). After each kill every run finished before it reads (a replaced file: the old
runs, or the first of the new); after the next writer or repair the index links exactly the
store's run files, h5py reads each through it, no temporary file, other store or older file is
left, and every run finished before the kill is still there.

    python3 tests/harness/cli/test_store_kills.py --binary build/xpbd-bench
"""
import concurrent.futures
import os
import shutil
import signal
import sys

import h5py

from store_support import TINY, fail, read_names, run_tests, spec, whole, xb


def base_files(binary, work):
    """Files each killed command starts from, each in a folder of its own: name -> (folder, file)."""
    bases = {}

    def make(name, *commands):
        folder = os.path.join(work, "base_" + name)
        os.makedirs(folder)
        out = os.path.join(folder, "r.h5")
        for c in commands:
            rc, _, err = xb(binary, [a.replace("{OUT}", out).replace("{DIR}", folder) for a in c])
            assert rc == 0, f"{name}: {c}: {err}"
        bases[name] = (folder, out)

    s = spec(work, "kill.toml", [1e-8, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2])
    make("two", ["run"] + TINY + ["--solver", "xpbd-gs,cholmod", "--out", "{OUT}"])
    make("sweep", ["sweep", s, "--out", "{OUT}", "--part", "0/7"])
    make("packed", ["run"] + TINY + ["--solver", "xpbd-gs,cholmod", "--out", "{DIR}/src.h5"],
         ["pack", "{DIR}/src.h5", "--out", "{OUT}"])
    make("older", ["run"] + TINY + ["--solver", "xpbd-gs", "--out", "{OUT}"])
    older_layout(bases["older"][1])
    make("none")  # no file yet
    make("no_index", ["run"] + TINY + ["--solver", "xpbd-gs,cholmod,xpbd-jacobi", "--out", "{OUT}"])
    os.remove(bases["no_index"][1])
    return bases, s


def older_layout(out):
    """Rewrites a one-run file as the layout before stores wrote it: an index of links to
    OUT.runs/<name>.<8 hex>.h5, plus a run file no link names (a writer killed between its files)."""
    with h5py.File(out, "r") as f:
        store = f.attrs["store"]
        (name,) = list(f["runs"])
    folder = out + ".runs"
    os.rename(os.path.join(folder, store, name + ".h5"), os.path.join(folder, name + ".0badf00d.h5"))
    shutil.copy(os.path.join(folder, name + ".0badf00d.h5"), os.path.join(folder, "orphan.h5.tmpcopy"))
    with h5py.File(os.path.join(folder, "orphan.h5.tmpcopy"), "a") as f:
        f.move(f"runs/{name}", "runs/0002_orphan")
    os.rename(os.path.join(folder, "orphan.h5.tmpcopy"), os.path.join(folder, "0002_orphan.cafe1234.h5"))
    os.rmdir(os.path.join(folder, store))
    os.remove(out)
    with h5py.File(out, "w") as f:
        f.attrs["schema_version"] = 1
        f.create_group("runs")[name] = h5py.ExternalLink(f"r.h5.runs/{name}.0badf00d.h5", f"/runs/{name}")


def stored_names(out):
    """The runs of every store of OUT, from their file names (the index may be gone)."""
    names = []
    for d, _, files in os.walk(out + ".runs"):
        names += [n[:-3].split(".")[0] for n in files if n.endswith(".h5") and d != out + ".runs"]
    return sorted(names)


def kill_case(binary, work, bases, case, base, command, nxt, replaced=None):
    """`command` killed before each of its durable steps in turn; returns the kills. `replaced`: the
    names a run --out writes (after a kill the file holds the old runs or the first of these)."""
    kills = 0
    for n in range(1, 200):
        folder = os.path.join(work, f"k_{case.replace(' ', '_')}_{n}")
        shutil.copytree(bases[base][0], folder, symlinks=True)
        out = os.path.join(folder, "r.h5")
        before = read_names(out)[0] if os.path.exists(out) else stored_names(out)
        rc, _, err = xb(binary, [a.replace("{OUT}", out) for a in command], {"XB_FAULT_SIGNAL": f"{n}:SIGKILL"})
        if rc == 0:
            shutil.rmtree(folder)
            return kills
        step = f"{case} killed at step {n}"
        if rc != -signal.SIGKILL:
            fail(step, f"exit {rc}: {err[-500:]}")
            return kills
        kills += 1
        after, skipped = read_names(out) if os.path.exists(out) else (stored_names(out), [])
        if skipped:
            fail(step, f"unreadable after the kill: {skipped}")
        if replaced is not None:
            if after != before and after != replaced[:len(after)]:
                fail(step, f"neither the old file nor the new one: {before} -> {after}")
        elif not set(before) <= set(after):
            fail(step, f"runs lost: {sorted(set(before) - set(after))}")
        rc, out_text, err = xb(binary, [a.replace("{OUT}", out) for a in nxt])
        if rc != 0:
            fail(f"{case} killed at step {n}", f"the next {nxt[0]} exited {rc}: {err[-500:]}{out_text[-300:]}")
        whole(f"{case} killed at step {n}, then {nxt[0]}", out, after)
        shutil.rmtree(folder)
    fail(case, "never ended by itself in 200 steps")
    return kills


def killed_at_every_step(binary, work):
    bases, s = base_files(binary, work)
    append = ["run"] + TINY + ["--solver", "xpbd-gs", "--out", "{OUT}", "--append"]
    repair = ["repair", "{OUT}"]
    cases = [("run --append into a new file", "none", ["run"] + TINY + ["--solver", "xpbd-gs,cholmod", "--out", "{OUT}", "--append"],
              repair),
             ("run --append", "two", ["run"] + TINY + ["--solver", "xpbd-gs,cholmod,xpbd-jacobi,cg", "--out", "{OUT}", "--append"], repair),
             ("sweep", "sweep", ["sweep", s, "--out", "{OUT}"], append),
             ("run --out", "two", ["run"] + TINY + ["--solver", "cholmod,xpbd-jacobi,xpbd-gs", "--out", "{OUT}"], repair,
              ["0001_cloth_hang_cholmod", "0002_cloth_hang_xpbd-jacobi", "0003_cloth_hang_xpbd-gs"]),
             ("a packed file's first append", "packed", append, repair),
             ("an older layout's first append", "older", append, append),
             ("repair of an older layout", "older", repair, append),
             ("repair without an index", "no_index", repair, append)]
    with concurrent.futures.ThreadPoolExecutor(2) as pool:
        done = list(pool.map(lambda c: (c[0], kill_case(binary, work, bases, *c)), cases))
    total = sum(k for _, k in done)
    print("killed at every step: " + ", ".join(f"{c}: {k}" for c, k in done) + f"; {total} kills", flush=True)
    if total < 100:
        fail("killed at every step", f"only {total} kills")



if __name__ == "__main__":
    sys.exit(run_tests([killed_at_every_step], __doc__))
