"""The smallest effect these measurements would detect: for each candidate, how far from its
neutral value the effect must be before the diagnosis's test finds it with 90 % probability.

Why: a verdict `no_effect_needed` says the base model is consistent with the data, not that the
material lacks the effect. How much effect could hide depends on the conditions measured, the
rows' uncertainties and the rig's seed scatter — on the hidden-effect protocol most size spreads
and many wall frictions hide (docs/diagnosis.md §7: no method can name them). This tells a user,
for their own measurements, what a clean verdict rules out and what it does not.

How: at the base fit theta (its noise model fixed, as in the likelihood-ratio tests), the rows
the surrogates predict with the candidate at eta, y(eta) = f(theta, eta), are fitted by the base
model; the chi^2 left is the noncentrality of the likelihood-ratio test for an effect of that
size (diagnose.py, the same quadratic form), its `signal`. The test at ALPHA (one-sided for a
candidate whose neutral value is the edge of its range) detects an effect with probability
POWER once the signal reaches the noncentral chi^2_1 value that puts POWER of its mass above
the critical value. The smallest |eta - neutral| with that signal is found on each allowed side
by a scan from the neutral value to the campaign range's edge and a root search in the first
bracket; none: not detectable anywhere in the range with these measurements. In a linear model
this is sqrt(lambda / |M^1/2 J_E|^2), the score test's information (a test checks it)."""
from __future__ import annotations

import copy

import numpy as np
from scipy import optimize, stats

from .candidates import Candidate
from .fit import Fit, Model, minimise
from .quantities import CONDITION_UNITS, CONDITIONS, Observation

POWER = 0.9
SCAN = 8  # scan points per side, from the neutral value to the range's edge


def noncentrality_for_power(alpha: float, one_sided: bool, power: float = POWER) -> float:
    """lambda such that P(noncentral chi^2_1(lambda) > the test's critical value) = power."""
    crit = stats.chi2.isf(2 * alpha if one_sided else alpha, 1)
    return float(optimize.brentq(lambda lam: stats.ncx2.sf(crit, 1, lam) - power, 1e-6, 1e4))


def effect_signal(ref_model: Model, base: Fit, effect_model: Model, eta: float) -> float:
    """chi^2 of the base model's best fit to the rows the surrogates predict at the base fit with
    the candidate at eta (ref_model's noise model: the tests' quadratic form)."""
    m = copy.copy(ref_model)  # the same whitener; only the values it fits differ
    m.y = effect_model.predict(np.append(base.best, eta))
    return float(minimise(m, starts=64, keep=1, start=base.best).chi2)


def smallest_detectable(ref_model: Model, base: Fit, candidate: Candidate, nets: dict, ranges: dict,
                        covered: list[Candidate], alpha: float) -> dict:
    """{"neutral", "below", "above", "signal_at_edge": {"below", "above"}, "power", "alpha"} for one
    candidate: the smallest effect on each allowed side that the test finds with probability
    POWER (None where even the range's edge is not enough; a side the candidate does not have is
    left out)."""
    neutral = float(candidate.neutral_value(base.as_dict()))
    lo, hi = ranges[candidate.parameter]
    one_sided = candidate.side == "+"
    target = noncentrality_for_power(alpha, one_sided)
    effect_model = Model(ref_model.obs, nets, ranges, covered, candidate, at=np.append(base.best, neutral))
    effect_model.y = ref_model.y  # predictions only; its noise model is never used
    out = {"neutral": neutral, "range": [float(lo), float(hi)], "power": POWER, "alpha": alpha, "signal_needed": target,
           "signal_at_edge": {}}
    sides = [("above", hi)] + ([] if one_sided else [("below", lo)])
    for side, edge in sides:
        if abs(edge - neutral) < 1e-12 * max(1.0, abs(edge)):
            out[side] = None
            continue
        signal = lambda eta: effect_signal(ref_model, base, effect_model, eta) - target  # noqa: E731
        prev, found = neutral, None
        for t in np.linspace(1.0 / SCAN, 1.0, SCAN):
            eta = neutral + t * (edge - neutral)
            s = signal(eta)
            if s >= 0.0:
                # signal(prev) < 0: at the neutral value the base model fits exactly (signal 0)
                found = eta if s == 0.0 else optimize.brentq(signal, prev, eta, xtol=1e-6 * abs(edge - neutral))
                break
            prev = eta
        out["signal_at_edge"][side] = float(s + target)
        out[side] = None if found is None else float(found)
    return out


def information(model: Model, p: np.ndarray, parameter: str) -> float:
    """|M^1/2 J_E|^2 at the base parameters p: how strongly the rows tell a small step of the
    candidate's input from what the base parameters can re-adjust (the score test's information;
    the signal of a small effect eta is (eta - neutral)^2 times this)."""
    mje = model.projected_signature(p, parameter)
    return float(mje @ mje)


def candidate_tests(observations: list, nets: dict, points: int = 4) -> list[tuple[str, list]]:
    """Tests a user could add: for every rig with surrogates, one run at each of `points` values of
    its test condition over the campaign range (log-spaced for the pre-shear stress), giving every
    quantity the rig measures (the shear points at the fractions observed, else 40/60/80 %).
    [(label, rows)]."""
    fractions = sorted({o.conditions["shear_fraction"] for o in observations if "shear_fraction" in o.conditions}) \
        or [0.4, 0.6, 0.8]
    tests = []
    for rig in sorted({q.rig for q in nets}):
        quantities = [q for q in nets if q.rig == rig]
        net = nets[quantities[0]]
        cond = [c for c in CONDITIONS.get(rig, ()) if c != "shear_fraction" and c in net.input_names]
        values = [None]
        if cond:
            j = net.input_names.index(cond[0])
            lo, hi = float(net.lo[j]), float(net.hi[j])
            values = np.geomspace(lo, hi, points) if cond[0] == "preshear_stress" else np.linspace(lo, hi, points)
        for v in values:
            at = {} if v is None else {cond[0]: float(v)}
            rows = []
            for q in quantities:
                for f in (fractions if "shear_fraction" in nets[q].input_names else [None]):
                    c = dict(at) if f is None else dict(at, shear_fraction=f)
                    rows.append(Observation(q, c, 1.0, 0.0, f"{q.key} {c}", origin="dem"))  # a new run's noise
            tests.append((f"{rig}" + (f" at {cond[0]} = {v:.4g} {CONDITION_UNITS.get(cond[0], '')}".rstrip()
                                      if v is not None else ""), rows))
    return tests


def best_next_measurement(ref_model: Model, base: Fit, candidate: Candidate, tests: list, nets: dict, ranges: dict,
                          covered: list[Candidate]) -> dict | None:
    """The one extra test (of `tests`: candidate_tests) that would lower the candidate's detection
    limit most, in the linearised view: the information with that test's rows added (their
    uncertainty the rig's seed scatter and the net's error there, their correlations as the
    likelihood has them), the limit scaling as information^-1/2. {"test", "limit_ratio"} (new
    limit / now, < 1), or None without a gain."""
    now = information(ref_model, base.best, candidate.parameter)
    best = None
    for label, rows in tests:
        try:
            m = Model(ref_model.obs + rows, nets, ranges, covered, at=base.best)
        except ValueError:  # a test whose rows these surrogates cannot evaluate (an input they lack)
            continue
        gain = information(m, base.best, candidate.parameter)
        if gain > now * (1 + 1e-9) and (best is None or gain > best[0]):
            best = (gain, label)
    if best is None or now <= 0:
        return None
    return {"test": best[1], "limit_ratio": float(np.sqrt(now / best[0]))}


def detectable_effects(ref_model: Model, base: Fit, candidates: list[Candidate], nets: dict, ranges: dict,
                       covered: list[Candidate], alpha: float) -> dict:
    """{candidate name: smallest_detectable(...)} for every candidate tested."""
    return {c.name: smallest_detectable(ref_model, base, c, nets, ranges, covered, alpha) for c in candidates}
