"""The race's one reference per size (figures/race.py computes it once, every entry reads it):
what the summary says about it."""
import math
import os

import xbruns


def passes(data_dir):
    """{(scene, size): the attributes of the size's reference pass (figures/race.py)}."""
    out = {}
    for scene in sorted(os.listdir(data_dir)) if os.path.isdir(data_dir) else []:
        for size in sorted(os.listdir(os.path.join(data_dir, scene))):
            path = os.path.join(data_dir, scene, size, "_reference", "run.h5")
            runs = xbruns.load(path, datasets=()) if os.path.isfile(path) else []
            if runs:
                out[(scene, size)] = runs[-1]["attrs"]
    return out


def note(sc, s):
    """How the size's reference was made, and how many entries read it rather than computing it."""
    a = getattr(sc, "references", {}).get(s)
    srcs = [str(e["run"].get("data", {}).get("reference/source", ["?"])[0]) for e in sc.sizes[s] if "data" in e["run"]]
    read = sum(1 for x in srcs if x == "read")
    text = f"{read} of {len(srcs)} entries read the size's stored reference"
    if a:
        verdict = "converged" if str(a.get("reference_substeps_unconverged", "1")) == "0" else "did not converge"
        text = (f"reference computed once ({float(a.get('reference_time', math.nan)):.1f} s, its process's peak "
                f"{float(a.get('peak_memory', math.nan)) / 1e9:.2f} GB; it {verdict}); " + text)
    return text + "."
