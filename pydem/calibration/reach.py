"""Is a best fit held back by the campaign box? A parameter whose estimate sits at an edge of its
range, where χ² still falls outward, marks measurements the model cannot reach inside the box:
the verdict is then `out_of_reach` (docs/diagnosis.md §4), not "consistent" — a model that fits
only because the row's σ is wide, or that would fit better past the box, is not confirmed by it.

The test is linear at the best fit, in whitened units (fit.Model): the chi^2 drop when parameter j
may step outward past its edge and the others re-adjust inside the box (one at an edge only
inward), each of them at a cost of chi^2 1 per box width moved — a bounded linear least-squares
problem. An edge counts when that gain is at least REACH_CHI2 (one σ's worth): a gain below it is
within what the noise moves."""
from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy import optimize

from ..quantity_table import metric_spec
from .fit import Fit, Model

EDGE = 0.01        # an estimate within this fraction of its range's width of an edge sits at it
REACH_CHI2 = 1.0   # the linearised chi^2 gain past the edge that makes it "out of reach"


def held_back(model: Model, fit: Fit) -> list[dict]:
    """Per parameter at an edge with chi^2 falling outward by at least REACH_CHI2: its name, the
    edge ('lower'/'upper') and its value, the gain, and the row the model misses most (label,
    measured, model, residual in the quantity's unit and in sigma)."""
    p = fit.best
    width = model.hi - model.lo
    at_lo = p - model.lo <= EDGE * width
    at_hi = model.hi - p <= EDGE * width
    if not (at_lo.any() or at_hi.any()):
        return []
    pred = model.predict(p)
    r = model.white(model.y - pred)
    J = model.white(model.jacobian(p))
    k = len(model.free)
    # the other parameters re-adjust, inside the box: one at an edge only inward (freeing j can let it
    # back in, never past its own edge); each costs chi^2 1 per box width moved (as the posterior's
    # proposal), so a parameter with no local slope (friction at the angle of repose's maximum)
    # does not absorb a whole row by a huge linearised step
    inward_lo = np.where(at_lo, 0.0, -np.inf)
    inward_hi = np.where(at_hi, 0.0, np.inf)
    A = np.vstack([J, np.diag(1.0 / width)])
    b = np.concatenate([r, np.zeros(k)])
    out = []
    for j, name in enumerate(model.free):
        if not (at_lo[j] or at_hi[j]):
            continue
        lo, hi = inward_lo.copy(), inward_hi.copy()
        lo[j], hi[j] = (0.0, np.inf) if at_hi[j] else (-np.inf, 0.0)  # j: outward only, and free of cost
        Aj = A.copy()
        Aj[len(r) + j] = 0.0
        step = optimize.lsq_linear(Aj, b, bounds=(lo, hi)).x
        gain = float(r @ r - np.sum((b - Aj @ step) ** 2))
        if abs(step[j]) <= 0 or gain < REACH_CHI2:
            continue
        z = (model.y - pred) / model.sigma
        worst = int(np.argmax(np.abs(z)))
        out.append({"parameter": name, "edge": "upper" if at_hi[j] else "lower",
                    "value": float(model.hi[j] if at_hi[j] else model.lo[j]), "gain": gain,
                    "row": {"label": model.obs[worst].label, "measured": float(model.y[worst]),
                            "model": float(pred[worst]), "residual": float(model.y[worst] - pred[worst]),
                            "z": float(z[worst]), "unit": metric_spec(model.obs[worst].quantity.metric).unit}})
    return out


def name_campaigns(reach: list[dict], stores: dict, rigs: set) -> list[str]:
    """Adds to each held-back parameter the campaigns (their TOML files) whose range for it would have
    to go past the edge: the main store of each rig the measurements use; returns one line per parameter."""
    def shown(path: Path) -> str:
        try:
            return str(path.resolve().relative_to(Path.cwd()))
        except ValueError:
            return str(path)
    lines = []
    for r in reach:
        r["campaigns"] = [shown(st.path.with_suffix(".toml")) for rig, st in sorted(stores.items())
                          if rig in rigs and r["parameter"] in st.spec.ranges]
        if r["campaigns"]:
            way = "above" if r["edge"] == "upper" else "below"
            lines.append(f"{r['parameter']} stops at its {r['edge']} edge {r['value']:g}: extend {', '.join(r['campaigns'])} "
                         f"{way} it (a campaign over the wider box, this store pooled into it: docs/diagnosis.md §2)")
    return lines


def sentence(reach: list[dict]) -> str:
    """The plain-words account of held_back's list: how far, and what could reach it."""
    if not reach:
        return ""
    row = reach[0]["row"]
    unit = row["unit"]
    edges = ", ".join(f"{r['parameter'].split('.')[-1]} at its {r['edge']} edge {r['value']:g}" for r in reach)
    past = " or ".join(f"{'above' if r['edge'] == 'upper' else 'below'} {r['value']:g} for "
                       f"{r['parameter'].split('.')[-1]}" for r in reach)
    return (f"The best fit inside the campaign box stops at {edges}, and the misfit falls past it (χ² by "
            f"{max(r['gain'] for r in reach):.1f} to first order): {row['label']} measured {row['measured']:.4g}, "
            f"the model reaches {row['model']:.4g} ({row['residual']:+.3g}{(' ' + unit) if unit else ''}, "
            f"{row['z']:+.1f} σ). A campaign whose range goes {past}, or an effect that moves this quantity, could "
            f"reach it; within this box the parameters are bounds, not estimates." + "".join(
                f" Campaigns to extend for {r['parameter'].split('.')[-1]}: {', '.join(r['campaigns'])}."
                for r in reach if r.get("campaigns")))
