"""DEM runs of the rigs at given parameter values, one per measured condition group
(rig_values): the confirming runs at a calibrated estimate beside the measured values (`pydem
calibrate --confirm`, `pydem diagnose --confirm`), and the DEM-made sets of the validation
(synthetic.dem_set)."""
from __future__ import annotations

import math
import time

from ..rigs import RIGS
from .fit import Fit
from .quantities import Observation, rig_metric, test_conditions
from .store_data import DISCHARGE_METRICS


def rig_values(stores: dict, inputs: dict[str, float], obs: list[Observation], seed: int, threads: int = 1,
               say=print, progress=None, extra: dict | None = None) -> dict[int, float]:
    """One rig run per condition group of `obs` at the stores' presets with the given parameter
    values (a ring-shear run measures its pre-shear and every shear point): {observation index:
    value}. An observation whose run failed is missing from the result. `extra`: settings no
    store varies, given to every run (an effect that is not a candidate)."""
    groups: dict = {}
    for i, o in enumerate(obs):
        key = (o.quantity.rig, test_conditions(o))
        groups.setdefault(key, []).append(i)
    values = {}
    for g, ((rig, cond), idx) in enumerate(groups.items()):
        store = stores[rig]
        point = {k: inputs[k] for k in store.spec.names if k in inputs}
        point.update({k: v for k, v in cond})
        point.update(extra or {})
        cfg = store.spec.config(point)
        fractions = sorted({obs[i].conditions["shear_fraction"] for i in idx if "shear_fraction" in obs[i].conditions})
        if fractions:
            cfg.shear_points = list(fractions)
        cfg.num_threads = threads
        t0 = time.perf_counter()
        try:
            res = RIGS[rig][0](cfg).run(seed=seed, progress=progress)
        except Exception as exc:  # a run that fails is reported, the others go on
            say(f"    [{g + 1}/{len(groups)}] DEM {rig} {dict(cond)} failed: {exc}")
            continue
        if progress is not None:
            progress.done()
        say(f"    [{g + 1}/{len(groups)}] DEM {rig} {dict(cond)}: {time.perf_counter() - t0:.0f} s")
        dt = res.metrics.get("discharge_time")
        jammed = rig == "hopper" and not (dt is not None and math.isfinite(dt.value))
        for i in idx:
            o = obs[i]
            metric = rig_metric(o)
            if jammed and metric in DISCHARGE_METRICS:
                continue  # a hopper that did not empty measured neither a flow rate nor a discharge time
            v = res.metrics[metric].value if metric in res.metrics else None
            if isinstance(v, float) and math.isfinite(v) and v > 0:
                values[i] = v
    return values


def confirm(setup, fit: Fit, observations: list[Observation], threads: int = 1, say=print, progress=None) -> list[dict]:
    """One DEM run per rig and condition group at the fit's estimate (candidates not freed at
    their neutral values); per observation: measured, DEM and the relative difference."""
    inputs = {c.parameter: c.neutral_value(fit.as_dict()) for c in setup.candidates}
    inputs.update(fit.as_dict())
    groups = len({(o.quantity.rig, str(o.conditions)) for o in observations})
    say(f"confirming DEM runs at the estimate ({groups} condition groups at most)")
    values = rig_values(setup.stores, inputs, observations, seed=12345, threads=threads, say=say, progress=progress)
    rows = [{"label": observations[i].label, "measured": observations[i].value, "dem": v,
             "relative": (observations[i].value - v) / observations[i].value} for i, v in sorted(values.items())]
    for row in rows:
        say(f"  {row['label']:60s} measured {row['measured']:.4g}  DEM {row['dem']:.4g}  ({100 * row['relative']:+.1f} %)")
    return rows
