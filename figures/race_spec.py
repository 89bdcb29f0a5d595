"""The race's spec (figures/race/race.toml) as figures/race.py reads it: its entries, the --set keys
of each, and the check that every name in it is known to the binary."""
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(ROOT, "plots"))
import race as race_plots  # noqa: E402
import race_rules as rules  # noqa: E402

LOCAL_MAX_ITERATIONS = 100000  # a sweep method stops on its time budget, not on a count
STOP_KEYS = ("rtol", "atol", "max_iterations")  # an own_stop outer method keeps its profile's


def sets_of(*tables):
    out = {}
    for t in tables:
        out.update(t or {})
    return out


def set_args(sets):
    args = []
    for k, v in sets.items():
        args += ["--set", f"{k}={race_plots.toml_text(v)}"]
    return args


def frame_iterations(scene, size):
    return int(sets_of(scene.get("set"), size.get("set")).get("max_iterations", 100))


def entry_sets(spec, scene, size, outer, linear, forcing):
    """The --set keys of one entry: the scene's, the size's, the outer method's, the linear
    method's and the scene's own for that linear method (`linear_set`). XPBD's outer methods run
    `overrun` times the frame's outer iterations; an own_stop one (Newton) keeps its profile's stop
    test; a sweep runs until its time budget."""
    o, m = spec["outer"][outer], spec["linear"][linear]
    sets = sets_of(scene.get("set"), size.get("set"), o.get("set"), m.get("set"), scene.get("linear_set", {}).get(linear))
    if forcing not in ("none",):
        sets["linear.forcing"] = forcing
    if o.get("own_stop"):
        sets = {k: v for k, v in sets.items() if k not in STOP_KEYS}
    elif m.get("local"):
        sets["max_iterations"] = LOCAL_MAX_ITERATIONS
    else:
        sets["max_iterations"] = int(spec.get("overrun", 3) * frame_iterations(scene, size))
    if scene.get("state"):
        sets["frames"] = 1
    return sets


def reference_sets(scene, size):
    """The --set keys of a size's reference pass: the scene's and the size's (the problem), one
    outer iteration of a sweep (the reference is what it is for)."""
    sets = sets_of(scene.get("set"), size.get("set"))
    sets["max_iterations"] = 1
    if scene.get("state"):
        sets["frames"] = 1
    return sets


def entries(spec, forcing_rules, outers=None, linears=None):
    """(outer, linear, forcing) of every entry, the anchor first (always: it bounds the others)."""
    out = []
    for o, table in spec["outer"].items():
        for name, m in spec["linear"].items():
            if ((outers and o not in outers) or (linears and name not in linears)) and (o, name) != rules.ANCHOR:
                continue
            if table.get("local_only") and not m.get("local"):
                continue  # block descent: no linear step to take
            if m.get("local"):
                if o in m.get("outer", ["xpbd"]):
                    out.append((o, name, "none"))
            else:
                out += [(o, name, f) for f in (["fixed"] if m.get("forcing", True) is False else forcing_rules)]
    return sorted(out, key=lambda e: (e[0], e[1]) != rules.ANCHOR)


def size_indices(args, scene):
    """The sizes to run: --sizes, or with --quick the scene's quick_size (default its first)."""
    sizes = scene["sizes"]
    if args.quick:
        labels = [z["label"] for z in sizes]
        quick = scene.get("quick_size", labels[0])
        if quick not in labels:
            sys.exit(f"race spec: quick_size {quick!r} is not one of the scene's sizes ({', '.join(labels)})")
        return [labels.index(quick)]
    chosen = [int(i) for i in args.sizes.split(",")] if args.sizes else list(range(len(sizes)))
    bad = [i for i in chosen if not 0 <= i < len(sizes)]
    if bad:
        sys.exit(f"--sizes: no size {bad[0]} (the scene has {len(sizes)})")
    return chosen


def binary_names(bench):
    out = subprocess.run([bench, "list"], capture_output=True, text=True, check=True).stdout
    part, names = None, {"scenes": set(), "solvers": set(), "keys": set()}
    for line in out.splitlines():
        if line.endswith(":") and not line.startswith(" "):
            part = {"scenes:": "scenes", "solvers:": "solvers"}.get(line, "keys" if line.startswith("param") else None)
        elif line.startswith("  ") and part:
            names[part].add(line.split()[0])
    return names


def check_spec(bench, spec):
    """Every scene, solver, profile and --set key of the spec is known to the binary (`xpbd-bench list`)."""
    names = binary_names(bench)
    bad = [f"{k}: missing" for k in ("outer", "linear", "scenes", "thresholds", "time_budget") if k not in spec]
    if bad:
        sys.exit("race spec: " + "; ".join(bad))
    if rules.ANCHOR[0] not in spec["outer"] or rules.ANCHOR[1] not in spec["linear"]:
        bad.append(f"the anchor (outer {rules.ANCHOR[0]!r}, linear {rules.ANCHOR[1]!r}) must be in the spec")
    for name, o in spec["outer"].items():
        bad += [f"outer.{name}: unknown key {k!r}" for k in o.get("set", {}) if k not in names["keys"]]
        prof = o.get("profile")
        if prof and not os.path.exists(os.path.join(ROOT, "problems", "profiles", f"{prof}.toml")) and not os.path.exists(prof):
            bad.append(f"outer.{name}: unknown profile {prof!r}")
    for name, m in spec["linear"].items():
        if m.get("solver") not in names["solvers"]:
            bad.append(f"linear.{name}: unknown solver {m.get('solver')!r}")
        bad += [f"linear.{name}: unknown key {k!r}" for k in m.get("set", {}) if k not in names["keys"]]
        bad += [f"linear.{name}: unknown outer method {k!r}" for k in m.get("outer", []) if k not in spec["outer"]]
    for p in spec.get("pick", {}).get("entries", []):
        if p.get("outer") not in spec["outer"] or p.get("linear") not in spec["linear"]:
            bad.append(f"pick: entry {p.get('outer')!r} + {p.get('linear')!r} is not an outer and a linear method of the spec")
    for name, sc in spec["scenes"].items():
        if sc.get("scene") not in names["scenes"]:
            bad.append(f"scenes.{name}: unknown scene {sc.get('scene')!r}")
        for t in [sc.get("set", {})] + [z.get("set", {}) for z in sc.get("sizes", [])] + list(sc.get("linear_set", {}).values()):
            bad += [f"scenes.{name}: unknown key {k!r}" for k in t if k not in names["keys"]]
        bad += [f"scenes.{name}.linear_set: unknown linear method {k!r}" for k in sc.get("linear_set", {})
                if k not in spec["linear"]]
    if bad:
        sys.exit("race spec: " + "; ".join(bad))
