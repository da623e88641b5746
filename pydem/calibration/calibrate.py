"""Calibration of the base model (`pydem calibrate`): the micro parameters from measurements over
test conditions, with honest uncertainty.

- the posterior over the base parameters (uniform prior on the campaign box; likelihood from each
  row's uncertainty, the rig's seed-to-seed scatter and the net's error: fit.Model) with credible
  intervals, correlations and a flag for an estimate at a range edge;
- seed 000's view of the same data: the ±window admissible set, screened natively in libdem over
  2^20 scrambled Sobol combinations (each observation's net evaluated at its own conditions);
- the candidate effects' parameters, where a store varies them, sit at their neutral values
  (`pydem diagnose` is the step that frees them).

Returns a Calibration that the report renders; nothing is written here."""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from nn.export import weights_text

from ..campaign.design import design_points
from ..mlp import NativeMLP
from .candidates import Candidate
from .fit import Fit, Model, fit_own_noise, posterior
from .quantities import Observation
from .reach import held_back
from .verdicts import calibration_verdict


@dataclass
class Calibration:
    material: str
    observations: list[Observation]
    model: Model
    fit: Fit                       # best fit, with its posterior
    screening: dict                # seed 000's admissible set: window, samples, admissible, ranges, seconds
    notes: list[str] = field(default_factory=list)
    reach: list[dict] = field(default_factory=list)  # parameters held back by the campaign box (reach.py)

    @property
    def verdict(self) -> str:
        return calibration_verdict(self.fit.n, len(self.fit.names), self.fit.p_value, self.reach)

    def residual_table(self) -> list[dict]:
        return residual_table(self.observations, self.model, self.fit)

    def summary(self) -> dict:
        return fit_summary(self.model, self.fit)

    def as_dict(self) -> dict:
        post = self.fit.posterior
        return {"material": self.material, "verdict": self.verdict, "reach": self.reach, "fit": self.summary(),
                "parameters": {n: dict(p) for n, p in post.get("parameters", {}).items()},
                "correlation": {"names": post.get("names"), "matrix": post.get("correlation")},
                "posterior_samples": post.get("samples"), "posterior_ess": post.get("ess"),
                "admissible_window": {k: v for k, v in self.screening.items() if k != "points"},
                "residuals": self.residual_table(), "notes": self.notes}


def residual_table(observations: list[Observation], model: Model, fit: Fit) -> list[dict]:
    """Per row: measured ± u, model, the row's sigma (u or the seed scatter, and the net's error), z."""
    pred = model.predict(fit.best)
    rows = []
    for o, f, s, net in zip(observations, pred, model.sigma, model.nets):
        rows.append({"quantity": o.quantity.key, "conditions": o.conditions, "label": o.label,
                     "measured": o.value, "u_measured": o.uncertainty, "model": float(f), "u_model": net.net_error,
                     "scatter": net.seed_sd, "sigma": float(s), "z": float((o.value - f) / s),
                     "relative": float((o.value - f) / o.value)})
    return rows


WEAK_R2 = 0.3  # below: a surrogate says little about its parameters, and the report says so


def weak_surrogates(observations: list[Observation], nets: dict) -> list[str]:
    """Notes for the measured quantities whose surrogate explains little of its runs' variance."""
    out = []
    for q in dict.fromkeys(o.quantity for o in observations):
        n = nets[q]
        r2 = getattr(n, "r2", 1.0)
        if r2 < WEAK_R2:
            out.append(f"the surrogate of {q.key} explains little of its {getattr(n, 'runs', '?')} runs (cross-validated R² "
                       f"{r2:.2f}, RMSE {n.rmse:.3g}): what this quantity says about the parameters is mostly lost in "
                       f"its uncertainty, and the posterior stays near the prior; more runs in its store are needed")
    return out


def row_notes(observations: list[Observation]) -> list[str]:
    """Notes on what the rows do not say or say beyond the surrogates: no uncertainty given,
    conditions not given (assumed at the preset's value), and conditions that no surrogate takes."""
    notes = []
    unstated = [o.label for o in observations if not o.uncertainty_given]
    if unstated:
        notes.append("no uncertainty given for " + ", ".join(unstated) + ": the rig's seed-to-seed scatter stands in "
                     "for the lab's repeat scatter (the likelihood's floor in any case)")
    for o in observations:
        if o.assumed:
            notes.append(f"{o.label}: condition(s) not given, assumed " + ", ".join(f"{k}={v:g}" for k, v in o.assumed.items()))
        for text in o.extrapolated.values():
            notes.append(f"{o.label}: compared a little past the campaign's declared range: {text} (the surrogate extrapolates)")
        if o.ignored:
            notes.append(f"{o.label}: condition(s) " + ", ".join(f"{k}={v}" for k, v in o.ignored.items())
                         + " not taken by the surrogate: compared with the campaign preset as it is")
    return notes


def fit_summary(model: Model, fit: Fit) -> dict:
    rel = (model.y - model.predict(fit.best)) / model.y
    return {"chi2": fit.chi2, "chi2_per_dof": fit.chi2_per_dof, "dof": fit.dof, "p_value": fit.p_value,
            "rmse_relative": float(np.sqrt(np.mean(rel ** 2))), "n": fit.n, "bic": fit.bic}


def fit_base(observations: list[Observation], nets: dict, ranges: dict, candidates: list[Candidate]) -> tuple[Model, Fit]:
    """The base model (candidates at their neutral values) fitted with the noise model at its own
    optimum (fit.fit_own_noise), with its posterior."""
    model, fit = fit_own_noise(observations, nets, ranges, candidates)
    fit.posterior = posterior(model, fit)
    return model, fit


def window_screen(model: Model, window: float = 0.05, samples: int = 2 ** 20, threads: int = 2, seed: int = 7,
                  keep_points: bool = True) -> dict:
    """Seed 000's admissible set, natively: `samples` scrambled Sobol points of the free
    parameters' box; a point is admissible when every observation's net, at that point and the
    observation's conditions, predicts the measured value within ±window (relative). Each net
    is libdem's MLP (dem_mlp_eval_many, `threads` threads) built in memory from the surrogate."""
    ranges = {n: (lo, hi) for n, lo, hi in zip(model.free, model.lo, model.hi)}
    pts = design_points("sobol", ranges, 0, samples, seed)
    t0 = time.perf_counter()
    keep = np.ones(len(pts), bool)
    resid = np.empty((len(model.y), len(pts)))
    natives = {}
    for k, net in enumerate(model.nets):
        if id(net) not in natives:  # a net that cannot be exported (a test's closed form) runs in numpy
            natives[id(net)] = (NativeMLP(text=weights_text(net.mlp)) if hasattr(net, "mlp")
                                else lambda x, _threads, net=net: net(x))
        pred = natives[id(net)](model.row_inputs(k, pts), threads)
        keep &= np.abs(pred - model.y[k]) <= window * abs(model.y[k])
        resid[k] = model.y[k] - pred
    seconds = time.perf_counter() - t0
    misfit = np.sum(model.white(resid) ** 2, axis=0)  # chi^2 with the rows' covariance (fit.Model)
    idx = np.flatnonzero(keep)
    pool = idx if len(idx) else np.arange(len(pts))
    best = pts[pool[int(np.argmin(misfit[pool]))]]
    out = {"window": window, "samples": int(len(pts)), "admissible": int(len(idx)), "seconds": seconds,
           "rows": len(model.y), "names": list(model.free),
           "ranges": {n: [float(pts[idx, j].min()), float(pts[idx, j].max())] for j, n in enumerate(model.free)}
           if len(idx) else {},
           "least_misfit": dict(zip(model.free, map(float, best))), "least_misfit_admissible": bool(len(idx))}
    if keep_points:
        out["points"] = pts[idx]
    return out


def calibrate(material: str, observations: list[Observation], nets: dict, ranges: dict, candidates: list[Candidate],
              window: float = 0.05, samples: int = 2 ** 20, threads: int = 2, say=print) -> Calibration:
    used = {o.quantity for o in observations}
    inputs = set().union(*(set(nets[q].input_names) for q in used))
    covered = [c for c in candidates if c.parameter in inputs and c.parameter in ranges]
    model, fit = fit_base(observations, nets, ranges, covered)
    say(f"  posterior: chi^2/dof {fit.chi2_per_dof:.2f} (p = {fit.p_value:.2g}, {fit.n} rows, {len(fit.names)} "
        f"parameters; effective sample size {fit.posterior['ess']:.0f} of {fit.posterior['samples']})")
    for name, p in fit.posterior["parameters"].items():
        say(f"    {name:20s} {p['estimate']:10.4g}   95 % {p['lo']:.4g} - {p['hi']:.4g}" + ("   AT RANGE EDGE" if p["at_edge"] else ""))
    screening = window_screen(model, window, samples, threads)
    say(f"  seed 000's view: {screening['admissible']:,} of {screening['samples']:,} combinations within "
        f"±{100 * window:g} % of every measured value ({screening['seconds']:.2f} s natively, {threads} threads)")
    notes = []
    for name, p in fit.posterior["parameters"].items():
        if p["at_edge"]:
            notes.append(f"{name} sits at the edge of its campaign range [{p['range'][0]:g}, {p['range'][1]:g}] "
                         f"(estimate {p['estimate']:.4g}, 95 % interval {p['lo']:.4g}-{p['hi']:.4g}): the campaign "
                         f"box may be too small, or the model misses an effect (`pydem diagnose`)")
    if covered:
        notes.append("held at their neutral values: " + ", ".join(f"{c.name} ({c.parameter})" for c in covered))
    notes += row_notes(observations) + weak_surrogates(observations, nets)
    return Calibration(material, observations, model, fit, screening, notes, held_back(model, fit))
