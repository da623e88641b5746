"""Confirming DEM runs: the rigs at a calibrated estimate, for every measured condition, beside
the measured values (`pydem calibrate --confirm`, `pydem diagnose --confirm`)."""
from __future__ import annotations

from .fit import Fit
from .quantities import Observation


def confirm(setup, fit: Fit, observations: list[Observation], threads: int = 1, say=print, progress=None) -> list[dict]:
    """One DEM run per rig and condition group at the fit's estimate (candidates not freed at
    their neutral values); per observation: measured, DEM and the relative difference."""
    from .synthetic import rig_values
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
