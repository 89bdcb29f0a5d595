"""How far a run's reference may be trusted (plots/xbruns.py re-exports these): the one place the
plots and scripts judge a reference's verdict and certificate (results/README.md, run --reference).
"""
import math

# The reference's records (results/README.md, run --reference): what a plot needs to judge it.
REFERENCE_DATASETS = ("reference/status", "reference/success", "reference/relative_energy_gradient",
                      "reference/relative_dual_residual", "reference/error_estimate", "reference/certified",
                      "reference/certified_threshold", "reference/certificate_note")
NOT_FINE = "reference not fine enough"


def reference_verdict(run, index=0):
    """Whether the run's reference converged in substep `index` of the run (0: its first), the
    one place the plots read that: (True, "") or (False, why), e.g. "stagnated at ‖∇E‖ 0.00025 of
    its start". It reads the success predicate the harness wrote (reference/success), never the
    status names. Needs REFERENCE_DATASETS loaded; a run without them has no verdict (False)."""
    d = run.get("data", {}) if run else {}
    st, ok = d.get("reference/status"), d.get("reference/success")
    if st is None or len(st) <= index:
        return False, "no reference recorded"
    if ok is None or len(ok) <= index:
        return False, "no reference/success recorded (a file from before it)"
    if int(ok[index]):
        return True, ""
    why = str(st[index])
    g = d.get("reference/relative_energy_gradient")
    if g is not None and len(g) > index:
        why += f" at ‖∇E‖ {float(g[index]):.2g} of its start"
    return False, why


def reference_trusted(run, threshold, index=0):
    """Whether the run's reference in substep `index` may judge a position error of `threshold`:
    (True, "") where it is certified and its error estimate is at most threshold/100 (the harness
    records that bound as reference/certified_threshold, harness/sim/reference.hpp), else (False,
    why): why starts with NOT_FINE where the reference is certified but not to that threshold.
    Every script that prints a position error against a threshold asks this first."""
    ok, why = reference_verdict(run, index)
    if not ok:
        return False, "reference unconverged: " + why if why != "no reference recorded" else why
    d = run.get("data", {})
    th, cert = d.get("reference/certified_threshold"), d.get("reference/certified")
    if th is None or cert is None or len(th) <= index:
        return False, "reference not certified (a file from before the certificate)"
    if not int(cert[index]):
        note = d.get("reference/certificate_note")
        return False, "reference not certified" + (f": {note[index]}" if note is not None and len(note) > index and
                                                   str(note[index]) else "")
    if float(th[index]) <= threshold:
        return True, ""
    est = d.get("reference/error_estimate")
    return False, NOT_FINE + (f" (its error estimate {float(est[index]):.2g} > {threshold:g}/100)" if est is not None else "")


def error_text(value, attrs, digits=3):
    """A run's position error as its references allow it to be printed (the run's attributes, whose
    reference_certified_threshold is the finest error every substep's reference can judge, 100
    times its worst error estimate): the value where the references vouch for it, else NOT_FINE
    (or why there is no reference to judge by). For scripts that print a run's error."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "—"
    if "reference_substeps_unconverged" not in attrs:
        return f"{value:.{digits}g} (no reference)"
    if int(attrs["reference_substeps_unconverged"]):
        return f"{value:.{digits}g} (reference unconverged)"
    th = float(attrs.get("reference_certified_threshold", math.inf))
    if not th <= value:
        return f"{NOT_FINE} (it judges ≥ {th:.2g})" if math.isfinite(th) else "reference not certified"
    return f"{value:.{digits}g}"
