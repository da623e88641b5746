"""The one vocabulary of verdicts of `pydem calibrate` and `pydem diagnose` (docs/diagnosis.md §4),
each with the sentence a report opens with. A verdict never says more than the evidence: a fit
that could not be tested is `not_testable`, not consistent; a fit held back by the campaign box
is `out_of_reach` (reach.py), not consistent either."""
from __future__ import annotations

ACCEPT = 0.001  # a fit with chi^2 p-value below this is rejected
# the diagnosis verdicts that say something is missing from the base model: on a material without
# a hidden effect each is a false alarm (`out_of_reach` says the box stops the fit, `not_testable`
# that nothing was tested: neither claims an effect)
ALARMS = ("effect", "indistinguishable", "unexplained")

TEXT = {
    # both commands
    "not_testable": "Nothing could be tested: {n} measurement(s) for {k} base parameters leave no degree of freedom "
                    "to judge the fit (or a candidate effect) with. Measure more conditions.",
    "out_of_reach": "The measurements lie out of reach of this model inside the campaign box.",
    # calibrate
    "calibrated": "The base model fits these measurements (chi^2 p = {p:.2g}); its parameters are estimated inside "
                  "the campaign box.",
    "rejected": "The base model does not fit these measurements (chi^2 p = {p:.2g} < {accept:g}): run `pydem diagnose` "
                "to find which effect is missing.",
    # diagnose
    "no_effect_needed": "The base model is consistent with the measurements: no candidate effect is needed.",
    "effect": "One missing effect explains the measurements significantly better than the base model: {effect}.",
    "effects": "Missing effects explain the measurements significantly better than the base model, each on top of "
               "the one before: {effects}.",
    "indistinguishable": "Missing effects explain the measurements significantly better than the base model, but "
                         "{effect} and {others} about equally well with these conditions.",
    "unexplained": "The base model fails, and none of the candidate effects explains the misfit.",
}


def calibration_verdict(n: int, k: int, p_value: float, reach: list) -> str:
    """A calibration's verdict: n rows, k free parameters, the fit's chi^2 p-value, reach.held_back."""
    if reach:
        return "out_of_reach"
    if n <= k:
        return "not_testable"
    return "rejected" if p_value < ACCEPT else "calibrated"
