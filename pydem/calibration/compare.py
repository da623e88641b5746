"""A given model against a measurement file (`pydem compare`): the surrogates at a parameter set,
or DEM rig results; per row measured, model, sigma and z, and the overall error. Rows are
matched by quantity *and* condition; a row no model value represents is listed, never matched
to another condition."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from .calibrate import residual_table
from .fit import Fit, Model
from .quantities import Observation, rig_metric


def surrogate_model(observations: list[Observation], setup, params: dict[str, float]) -> tuple[Model, Fit]:
    """The surrogates at `params` (the base parameters required; a candidate's parameter, when
    given, replaces its neutral value) as a Model and a Fit at that point."""
    missing = [n for n in ("friction", "rolling_friction", "restitution") if n not in params]
    if missing:
        raise ValueError(f"--params needs {', '.join(missing)}")
    unknown = [k for k in params if k not in setup.ranges]
    if unknown:
        raise ValueError(f"--params: {', '.join(unknown)} not varied by the stores (they vary {', '.join(setup.ranges)})")
    given = [c for c in setup.candidates if c.parameter in params]
    if len(given) > 1:
        raise ValueError(f"--params: at most one candidate effect's parameter at a time (got {[c.name for c in given]})")
    model = Model(observations, setup.nets, setup.ranges, setup.candidates, given[0] if given else None)
    p = np.array([params[n] for n in model.free])
    return model, Fit(list(model.free), p, float(model.chi2(p)[0]), len(observations), model.lo, model.hi)


def surrogate_rows(observations, setup, params) -> list[dict]:
    model, fit = surrogate_model(observations, setup, params)
    return residual_table(observations, model, fit)


def dem_rows(observations: list[Observation], result_files: list[str | Path]) -> tuple[list[dict], list[str]]:
    """Rows matched with rig results (`pydem rig ... --out r.json`): same rig, and the run's
    conditions (from its recorded configuration) equal to the row's. The row's sigma is its own
    uncertainty (one DEM run: no surrogate error; its seed scatter is not known here)."""
    results = []
    for f in result_files:
        d = json.loads(Path(f).read_text())
        results.append((f, d["rig"], d.get("provenance", {}).get("config", {}), d["metrics"]))
    rows, unmatched = [], []
    for o in observations:
        hit = None
        for f, rig, cfg, metrics in results:
            if rig != o.quantity.rig or rig_metric(o) not in metrics:
                continue
            same = all(k == "shear_fraction" or (k in cfg and math.isclose(float(cfg[k]), v, rel_tol=1e-6))
                       for k, v in o.conditions.items())
            if same:
                hit = (f, metrics[rig_metric(o)]["value"])
                break
        if hit is None or hit[1] is None:
            unmatched.append(f"{o.label} ({o.condition_text() or 'no condition'}): no result at this condition")
            continue
        v = float(hit[1])
        s = o.uncertainty
        rows.append({"quantity": o.quantity.key, "conditions": o.conditions, "label": o.label, "measured": o.value,
                     "u_measured": o.uncertainty, "model": v, "u_model": 0.0, "scatter": math.nan, "sigma": s,
                     "z": (o.value - v) / s if s > 0 else math.nan, "relative": (o.value - v) / o.value,
                     "source": str(hit[0])})
    return rows, unmatched


def overall(rows: list[dict]) -> dict:
    rel = np.array([r["relative"] for r in rows])
    z = np.array([r["z"] for r in rows if math.isfinite(r["z"])])
    return {"n": len(rows), "rmse_relative": float(np.sqrt(np.mean(rel ** 2))) if len(rel) else math.nan,
            "chi2_per_value": float(np.mean(z ** 2)) if len(z) else math.nan}
