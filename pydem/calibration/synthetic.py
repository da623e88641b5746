"""Pseudo-measurements with a hidden effect, and the validation protocol of the diagnosis
(issue protocol, docs/diagnosis.md):

- a programme of test conditions: ring shear at three pre-shear stresses with shear points at
  40/60/80 %, the angle of repose with its bulk density, the hopper at three slot widths;
- truth: base parameters drawn at random in the campaign box; one candidate effect switched on
  at a random strength (or none: a null set);
- each value = the model's value + the rig's seed-to-seed scatter (one run) + lab noise
  (2 % on friction coefficients, 1 % on bulk density, 0.5 deg on the angle of repose, 2 % on flow
  rates and discharge times); each row's uncertainty states the noise and the scatter combined.

`surrogate_set` takes the model values from the nets plus a draw of the nets' own error (what
separates the rigs' mean response from a surrogate; cheap: hundreds of sets, for the false-alarm
rate), `dem_set` from real rig runs at the campaign preset (a few sets, to check).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..quantity_table import TEST_OF_RIG, metric_spec
from .candidates import BASE_PARAMETERS, Candidate
from .calibrate import fit_base
from .confirm import rig_values
from .diagnose import diagnose
from .fit import condition_correlation, scatter_correlations
from .quantities import Observation, Quantity, test_conditions
from .verdicts import ALARMS



def programme(nets: dict, preshear=(1000.0, 2000.0, 5000.0), fractions=(0.4, 0.6, 0.8), slots=None) -> list[Observation]:
    """The conditions grid, for the quantities the nets offer (values to be filled in)."""
    out = []
    hopper = [n for q, n in nets.items() if q.rig == "hopper"]
    if hopper and slots is None:  # one grid for every hopper quantity: three runs, not one per quantity
        lo = max(n.lo[n.input_names.index("slot_width")] for n in hopper)
        hi = min(n.hi[n.input_names.index("slot_width")] for n in hopper)
        slots = tuple(float(f"{b:.3g}") for b in np.linspace(lo, hi, 5)[1:4])
    for q in sorted(nets, key=lambda q: q.key):
        if q.rig == "ring-shear":
            for s in preshear:
                if q.metric == "mu_ie_s":
                    out += [Observation(q, {"preshear_stress": s, "shear_fraction": f}, math.nan, math.nan,
                                        f"ring_shear:mu_ie_s (preshear_stress={s:g}, shear_fraction={f:g})") for f in fractions]
                else:
                    out.append(Observation(q, {"preshear_stress": s}, math.nan, math.nan,
                                           f"ring_shear:{q.metric} (preshear_stress={s:g})"))
        elif q.rig == "hopper":
            for b in slots:
                out.append(Observation(q, {"slot_width": float(b)}, math.nan, math.nan,
                                       f"hopper:{q.metric} (slot_width={b:.4g})"))
        else:
            out.append(Observation(q, {}, math.nan, math.nan, f"{q.rig}:{q.metric}"))
    return out


def noise_sd(metric: str, value: float) -> float:
    kind, v = metric_spec(metric).noise
    return v * abs(value) if kind == "rel" else v


@dataclass
class Truth:
    theta: dict[str, float]
    effect: str | None
    parameter: str | None
    strength: float | None

    def inputs(self, candidates: list[Candidate]) -> dict[str, float]:
        """Every net input except the conditions: base parameters, and each candidate at the
        truth's value (the active one) or its neutral value."""
        out = dict(self.theta)
        for c in candidates:
            out[c.parameter] = self.strength if c.parameter == self.parameter else c.neutral_value(self.theta)
        return out


def draw_truth(rng: np.random.Generator, ranges: dict, candidates: list[Candidate], effect: str | None,
               min_fraction: float = 0.2) -> Truth:
    """Base parameters uniform in the box; the effect's parameter uniform between
    `min_fraction` of the way from neutral to the range edge and that edge, so an effect is never
    drawn vanishingly small. A two-sided candidate's side is drawn in proportion to the room on
    it (size spread: 0.4 above the neutral 0.1, 0.1 below), so the strength is near-uniform over
    the campaign range, as a material's would be (an even coin gave half of the size-spread sets
    a spread of 0-0.1, below what any rig can see)."""
    theta = {n: float(rng.uniform(*ranges[n])) for n in BASE_PARAMETERS}
    if effect is None:
        return Truth(theta, None, None, None)
    c = next(c for c in candidates if c.name == effect)
    lo, hi = ranges[c.parameter]
    neutral = c.neutral_value(theta)
    neutral = min(max(neutral, lo), hi)
    side = +1
    if c.side != "+" and hi - lo > 0:  # one-sided: no draw (its truths stay as they were)
        side = +1 if rng.uniform() * (hi - lo) < hi - neutral else -1
    edge = hi if side > 0 else lo
    if abs(edge - neutral) < 1e-12 * max(1.0, abs(edge)):
        edge = lo if side > 0 else hi
    strength = float(neutral + (edge - neutral) * rng.uniform(min_fraction, 1.0))
    return Truth(theta, c.name, c.parameter, strength)


def with_lab_noise(obs: list[Observation], values: dict, nets: dict, rng: np.random.Generator,
                   truth_inputs: list | None = None) -> list[Observation]:
    """Pseudo-measurements from model values (observation index -> the value before noise: a
    surrogate mean with seed scatter, or one DEM run): lab noise added. Each row is one run
    (origin "dem"), its stated uncertainty the lab noise: the likelihood adds one run's seed
    scatter itself (fit.row_noise). `truth_inputs` (from row_inputs) is kept for the callers; the
    noise does not depend on it."""
    out = []
    for i, o in enumerate(obs):
        v = values[i]
        n = noise_sd(o.quantity.metric, v)
        # every quantity here is positive: a noise draw below zero (a nearly jammed hopper) is clipped
        value = max(float(v + rng.normal(0.0, n)), 1e-3 * abs(float(v)), 1e-9)
        out.append(Observation(o.quantity, dict(o.conditions), value, float(n), o.label, origin="dem"))
    return out


def seed_sd_at(net, x) -> float:
    """One run's seed scatter: the net's error model at inputs x (1, inputs), or its pooled value."""
    if x is not None and hasattr(net, "errors_at"):
        return float(net.errors_at(x)[0][0])
    return float(net.seed_sd)


def row_inputs(nets: dict, candidates: list[Candidate], truth: Truth, obs: list[Observation]) -> list[np.ndarray]:
    """Each observation's net inputs (1, inputs) at the truth: its parameters and the row's conditions."""
    inp = truth.inputs(candidates)
    return [np.array([[o.conditions.get(n, inp.get(n, math.nan)) for n in nets[o.quantity].input_names]]) for o in obs]


def surrogate_values(nets: dict, candidates: list[Candidate], truth: Truth, obs: list[Observation]) -> dict[int, float]:
    """The nets' values at the truth for every observation (no scatter, no noise)."""
    return {i: float(nets[o.quantity](x)[0]) for i, (o, x) in enumerate(zip(obs, row_inputs(nets, candidates, truth, obs)))}


def surrogate_set(nets: dict, candidates: list[Candidate], truth: Truth, rng: np.random.Generator,
                  obs: list[Observation], net_error: bool = True) -> list[Observation]:
    """Pseudo-measurements from the nets: f(truth) + the nets' own error (net_error_draw: how far
    the rigs' mean response is from the surrogate, so that a surrogate set is as far from the
    nets as a DEM-made one; False: the nets taken as exact) + one run's seed scatter + lab noise."""
    return surrogate_set_and_means(nets, candidates, truth, rng, obs, net_error)[0]


def surrogate_set_and_means(nets: dict, candidates: list[Candidate], truth: Truth, rng: np.random.Generator,
                            obs: list[Observation], net_error: bool = True) -> tuple[list[Observation], dict[int, float]]:
    """surrogate_set, and the emulated rigs' mean response at the truth for every observation
    (f(truth) + the nets' error draw: the values free of seed scatter and lab noise)."""
    values = surrogate_values(nets, candidates, truth, obs)
    xs = row_inputs(nets, candidates, truth, obs)
    scatter = seed_scatter_draw(nets, obs, rng, xs)
    if net_error:
        values = {i: v + d for (i, v), d in zip(values.items(), net_error_draw(nets, obs, rng, xs))}
    return with_lab_noise(obs, {i: values[i] + d for i, d in enumerate(scatter)}, nets, rng, xs), values


def net_error_draw(nets: dict, obs: list[Observation], rng: np.random.Generator, truth_inputs: list) -> np.ndarray:
    """One draw of the nets' own error over a programme: per quantity, Gaussian with the net
    error of the error model at the truth's inputs (errors_at) and the likelihood's correlation
    over the conditions (fit.condition_correlation), so the likelihood's noise model is the one
    that made the set. The rows' stated uncertainty does not include it (a lab does not know
    our nets); the diagnosis adds it to every row, as it does for measured data."""
    out = np.zeros(len(obs))
    by: dict = {}
    for i, o in enumerate(obs):
        by.setdefault(o.quantity, []).append(i)
    for q, rows in by.items():
        net = nets[q]
        e = np.array([float(net.errors_at(truth_inputs[i])[1][0]) if hasattr(net, "errors_at")
                      else float(getattr(net, "net_error", 0.0)) for i in rows])
        c = np.array([[condition_correlation(net, obs[i], obs[j]) for j in rows] for i in rows])
        k = e[:, None] * e[None, :] * c + 1e-12 * np.diag(e * e + 1e-30)
        out[rows] = np.linalg.cholesky(k) @ rng.normal(size=len(rows))
    return out


def seed_scatter_draw(nets: dict, obs: list[Observation], rng: np.random.Generator,
                      truth_inputs: list | None = None) -> np.ndarray:
    """One draw of the rigs' seed scatter over a programme, as DEM runs make it: one run per test
    (a rig and its conditions but the shear fraction), whose rows share it as the likelihood says
    (fit.scatter_correlations: the shear points of one test, the quantities of one run), and
    different tests are independent. Its size: the nets' error models at the truth's inputs
    where given."""
    out = np.zeros(len(obs))
    rho = scatter_correlations(obs, [nets[o.quantity] for o in obs])
    tests: dict = {}
    for i, o in enumerate(obs):
        tests.setdefault((o.quantity.rig, test_conditions(o)), []).append(i)
    for rows in tests.values():
        sd = np.array([seed_sd_at(nets[obs[i].quantity], None if truth_inputs is None else truth_inputs[i]) for i in rows])
        c = rho[np.ix_(rows, rows)]
        w, v = np.linalg.eigh(c)  # a square root that tolerates a semi-definite c
        out[rows] = sd * (v @ (np.sqrt(np.clip(w, 0.0, None)) * rng.normal(size=len(rows))))
    return out


def signal(setup, truth: Truth, obs: list[Observation]) -> float:
    """How visible the hidden effect is in a set, whatever the method: chi^2 of the base model's
    best fit to the set's noise-free values (the truth's net values, each row with the set's
    uncertainty). It is the noncentrality of the likelihood-ratio test of the true effect: the
    statistic scatters about it by the noise (noncentral chi^2_1), so an effect whose signal is
    below the test's critical value (6.6 at p = 0.01) is missed as often as it is found by any
    method on these measurements; 0 for a null set."""
    if truth.effect is None:
        return 0.0
    values = surrogate_values(setup.nets, setup.candidates, truth, obs)
    clean = [replace(o, value=values[i]) for i, o in enumerate(obs)]
    _, fit = fit_base(clean, setup.nets, setup.ranges, setup.candidates)
    return float(fit.chi2)


def dem_set(stores: dict, nets: dict, candidates: list[Candidate], truth: Truth, rng: np.random.Generator,
            obs: list[Observation], seed: int, threads: int = 1, say=print) -> list[Observation]:
    """Pseudo-measurements from rig runs at the stores' presets, then lab noise; rows whose run
    failed are left out."""
    values = rig_values(stores, truth.inputs(candidates), obs, seed, threads, say)
    keep = sorted(values)
    kept = [obs[i] for i in keep]
    return with_lab_noise(kept, {k: values[i] for k, i in enumerate(keep)}, nets, rng,
                          row_inputs(nets, candidates, truth, kept))


def journal_set(row: dict, nets: dict, candidates: list[Candidate], rng: np.random.Generator,
                keep=None) -> tuple[Truth, list[Observation]]:
    """A set from a studies/diagnosis_dem_sets.py journal line (the rigs' raw values and the truth):
    its truth and its rows with lab noise drawn now (rows whose run failed, or that `keep`
    rejects, left out)."""
    t = row["truth"]
    truth = Truth(t["theta"], t["effect"], t["parameter"], t["strength"])
    kept = [r for r in row["rows"] if r["value"] is not None and (keep is None or keep(r))]
    obs = [Observation(Quantity(r["rig"], r["metric"]), r["conditions"], math.nan, math.nan, r["label"]) for r in kept]
    return truth, with_lab_noise(obs, {i: r["value"] for i, r in enumerate(kept)}, nets, rng,
                                 row_inputs(nets, candidates, truth, obs))


def to_csv(path, material: str, obs: list[Observation], truth: Truth, note: str, material_rows: list[str] = ()):
    """A measurement file (docs/measurements.md) of a pseudo-measurement set, its truth in comments;
    material_rows: rows of test `material` (quantity,value,unit,conditions) that describe it."""
    lines = [f"# {note}", f"# truth: {truth.theta}; effect {truth.effect} {truth.parameter} = {truth.strength}",
             "material,test,quantity,value,uncertainty,unit,conditions,use,source,origin"]
    for o in obs:
        cond = ";".join(f"{k}={v:.6g}" for k, v in o.conditions.items())
        lines.append(f"{material},{TEST_OF_RIG[o.quantity.rig]},{o.quantity.metric},{o.value:.8g},{o.uncertainty:.6g},,"
                     f"{cond},calibrate,synthetic,{o.origin}")
    for row in material_rows:
        q, v, unit, cond = row.split(",")
        lines.append(f"{material},material,{q},{v},,{unit},{cond},,synthetic,")
    from pathlib import Path
    Path(path).write_text("\n".join(lines) + "\n")




def density_mismatch(obs: list[Observation], factor: float) -> list[Observation]:
    """A discrepancy that no candidate represents: the solid density is `factor` times what the
    model assumes, which scales every bulk density and mass flow rate and nothing else."""
    out = []
    for o in obs:
        k = factor if metric_spec(o.quantity.metric).scales_with_density else 1.0
        out.append(replace(o, value=o.value * k, uncertainty=o.uncertainty * k))
    return out


def model_error(model, fit, clean: dict[int, float]) -> float | None:
    """RMSE of the fitted model's relative errors against the set's noise-free values (the
    emulated rigs' mean response at the truth: no seed scatter, no lab noise): what the model gets
    wrong about the material, which a measured set's residuals show only mixed with the noise
    (None without a fit)."""
    if fit is None or len(model.y) != len(clean):
        return None
    v = np.array([clean[i] for i in range(len(clean))])
    return float(np.sqrt(np.mean(((v - model.predict(fit.best)) / v) ** 2)))


SIGNAL_VISIBLE = 15.0  # the noncentrality at which the one-sided LR test at p = 0.01 has 94 % power
SIGNAL_BINS = ((0.0, 5.0), (5.0, 15.0), (15.0, 50.0), (50.0, math.inf))


def score_sets(results: list[dict]) -> dict:
    """Accuracy, false alarms and error fall over validation results (rows of `validate`)."""
    by = {}
    for r in results:
        by.setdefault(r["kind"], []).append(r)
    out = {}
    for kind, rows in sorted(by.items()):
        n = len(rows)
        if kind == "null":
            alarms = sum(r["verdict"] in ALARMS for r in rows)
            out[kind] = {"sets": n, "false_alarms": alarms, "false_alarm_rate": alarms / n,
                         "out_of_reach": sum(r["verdict"] == "out_of_reach" for r in rows)}
        elif kind == "unexplained":
            out[kind] = {"sets": n, "verdicts": {v: sum(r["verdict"] == v for r in rows) for v in sorted({r["verdict"] for r in rows})}}
        else:
            hit = [r for r in rows if r["effect"] == kind]
            falls = [r["rmse_after"] / r["rmse_before"] for r in hit if r["rmse_after"] is not None and r["rmse_before"] > 0]
            truth_falls = [r["truth_error_after"] / r["truth_error_before"] for r in hit
                           if r.get("truth_error_after") is not None and r["truth_error_before"] > 0]
            seen = [r for r in rows if (r.get("signal") or 0.0) >= SIGNAL_VISIBLE]
            # forward selection's extra effects on a one-effect set are false alarms of their own
            extra = sum(len(r.get("effects") or []) > 1 for r in rows)
            out[kind] = {"sets": n, "top1": len(hit), "top1_rate": len(hit) / n, "extra_effect_named": extra,
                         "visible_sets": len(seen), "top1_visible": sum(r["effect"] == kind for r in seen),
                         "top1_rate_visible": sum(r["effect"] == kind for r in seen) / len(seen) if seen else None,
                         "by_signal": {f"{lo:g}-{hi:g}": [sum(r["effect"] == kind for r in b), len(b)]
                                       for lo, hi in SIGNAL_BINS
                                       for b in [[r for r in rows if r.get("signal") is not None and lo <= r["signal"] < hi]]},
                         "verdicts": {v: sum(r["verdict"] == v for r in rows) for v in sorted({r["verdict"] for r in rows})},
                         "error_after_over_before_median": float(np.median(falls)) if falls else None,
                         "truth_error_after_over_before_median": float(np.median(truth_falls)) if truth_falls else None,
                         "chi2_per_dof_after_median": float(np.median([r["chi2_after"] for r in hit])) if hit else None}
    return out


def set_rng(seed: int, kind: str, k: int) -> np.random.Generator:
    """The generator of set k of a kind: each set its own, so a resumed or partial run, and every
    tool that revisits the validation's sets, draws the same ones."""
    return np.random.default_rng([seed, sum(map(ord, kind)), k])


def effect_sets(setup, n: int, seed: int = 0, net_error: bool = True, min_fraction: float = 0.2):
    """(candidate, k, truth, observations) for n surrogate-made sets per candidate effect, drawn as
    validate() draws them (the same seed gives the same sets)."""
    base_obs = programme(setup.nets)
    for c in setup.candidates:
        for k in range(n):
            rng = set_rng(seed, c.name, k)
            truth = draw_truth(rng, setup.ranges, setup.candidates, c.name, min_fraction)
            obs, _ = surrogate_set_and_means(setup.nets, setup.candidates, truth, rng, base_obs, net_error)
            yield c, k, truth, obs


def validate(setup, kinds: dict[str, int], seed: int = 0, source: str = "surrogate", threads: int = 1,
             say=print, journal=None, net_error: bool = True, base_obs: list[Observation] | None = None) -> list[dict]:
    """Runs the protocol: kinds = {"null": n, <candidate name>: n, "unexplained": n}; source
    "surrogate" or "dem" (net_error: surrogate sets carry a draw of the nets' own error, as
    DEM-made ones do); base_obs: the conditions (default: programme's grid). One row per set:
    truth, verdict, chosen effect, errors before/after."""
    import json
    from pathlib import Path
    base_obs = programme(setup.nets) if base_obs is None else base_obs
    rows = []
    done = {}
    if journal is not None and Path(journal).exists():  # resumable: finished sets are kept, not redone
        for line in Path(journal).read_text().splitlines():
            r = json.loads(line)
            done[(r["kind"], r["set"])] = r
    for kind, n in kinds.items():
        for k in range(n):
            # each set its own seeded generator, so a resumed run draws the same sets
            rng = set_rng(seed, kind, k)
            if (kind, k) in done:
                rows.append(done[(kind, k)])
                continue
            effect = None if kind in ("null", "unexplained") else kind
            truth = draw_truth(rng, setup.ranges, setup.candidates, effect)
            if source == "dem":
                obs = dem_set(setup.stores, setup.nets, setup.candidates, truth, rng, base_obs,
                              seed=int(rng.integers(1 << 30)), threads=threads, say=say)
            else:
                obs, means = surrogate_set_and_means(setup.nets, setup.candidates, truth, rng, base_obs, net_error)
            if kind == "unexplained":
                obs = density_mismatch(obs, 1.25)
            visible = signal(setup, truth, obs) if source == "surrogate" else None
            d = diagnose(f"{kind}-{k}", obs, setup.nets, setup.ranges, setup.candidates, say=lambda *a: None,
                         detection_limits=False)
            s_before, s_after = d.summary_of(d.base, d.base_model), d.summary_of(d.after, d.after_model)
            truth_error = {"before": None, "after": None}
            if source == "surrogate" and kind != "unexplained":
                truth_error = {"before": model_error(d.base_model, d.base, means),
                               "after": model_error(d.after_model, d.after, means)}
            row = {"kind": kind, "set": k, "source": source, "truth": truth.theta, "effect_truth": truth.effect,
                   "strength": truth.strength, "signal": visible, "verdict": d.verdict, "effect": d.effect,
                   "effects": d.effects,
                   "best_candidate": d.candidates[0].effect if d.candidates else None,
                   "p_best": d.candidates[0].p_value if d.candidates else None,
                   "chi2_before": s_before["chi2_per_dof"], "rmse_before": s_before["rmse_relative"],
                   "chi2_after": s_after["chi2_per_dof"] if s_after else None,
                   "rmse_after": s_after["rmse_relative"] if s_after else None,
                   "loco_before": d.loco.get("before"), "loco_after": d.loco.get("after"),
                   "truth_error_before": truth_error["before"], "truth_error_after": truth_error["after"]}
            rows.append(row)
            if journal is not None:
                with open(journal, "a") as fh:
                    fh.write(json.dumps(row, default=float) + "\n")
            say(f"  {source} {kind:14s} #{k}: {d.verdict:18s} {d.effect or '-':14s} chi2/dof {row['chi2_before']:.2f}"
                + (f" -> {row['chi2_after']:.2f}" if row["chi2_after"] is not None else ""))
    return rows
