"""One name for a calibrated quantity: (rig, metric) plus the test conditions it is measured at.

A measurement row becomes an Observation: its Quantity, the values of the conditions the
surrogate takes as inputs (pre-shear stress and shear fraction for the ring shear, slot width
for the hopper), value and standard uncertainty. A campaign store becomes one training table
per Quantity: inputs = the store's varied parameters followed by the quantity's conditions
that the store does not vary itself (the shear fraction: one run measures several)."""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np

from ..measurements import Measurement

# conditions each rig's surrogates take as inputs, in SI units, and how measurement files name them
CONDITIONS = {"ring-shear": ("preshear_stress", "shear_fraction"), "aor": (), "hopper": ("slot_width",)}
CONDITION_UNITS = {"preshear_stress": "Pa", "shear_fraction": "", "slot_width": "m"}
# quantities a measurement file may name, per rig, and the conditions each one depends on
QUANTITIES = {
    "ring-shear": {"mu_ie_ps": ("preshear_stress",), "mu_ie_s": ("preshear_stress", "shear_fraction"),
                   "bulk_density": ("preshear_stress",)},
    "aor": {"angle_of_repose": (), "bulk_density": ()},
    "hopper": {"mass_flow_rate": ("slot_width",), "discharge_time": ("slot_width",), "bulk_density": ("slot_width",)},
}
_FRACTION_METRIC = re.compile(r"^mu_ie_s_(\d+)$")
# A hopper run that did not empty (it jammed, or flowed too slowly for the time limit) measured no
# discharge time, and no flow rate either: its 20-80 % slope mixes flow with an arch's standstill
# (a run that jammed after 1.8 kg/s reports 0.3). Such runs are neither measurements (rig_values)
# nor surrogate training rows or replicates (counted_runs): with them in, the default stores' flow-rate net
# had a cross-validated R^2 of 0.965 (RMSE 0.139 kg/s) and predicted negative flows in 5 % of the
# box; without, 0.982 (0.091 kg/s).
DISCHARGE_METRICS = ("mass_flow_rate", "discharge_time")


def counted_runs(store, column: str) -> np.ndarray:
    """(runs,) bool: the store's finished runs whose value in metric column `column` counts as a
    measurement: finite, and for a hopper's discharge metrics, from a hopper that emptied."""
    j = store.metric_names.index(column)
    ok = (store.status == 1) & np.isfinite(store.values[:, j])
    if store.spec.rig == "hopper" and column in DISCHARGE_METRICS and "discharge_time" in store.metric_names:
        ok &= np.isfinite(store.values[:, store.metric_names.index("discharge_time")])
    return ok


@dataclass(frozen=True)
class Quantity:
    rig: str
    metric: str

    @property
    def key(self) -> str:
        return f"{self.rig}:{self.metric}"

    @property
    def conditions(self) -> tuple[str, ...]:
        return QUANTITIES[self.rig][self.metric]


@dataclass
class Observation:
    quantity: Quantity
    conditions: dict[str, float]  # every condition the quantity depends on, SI
    value: float
    uncertainty: float            # the measurement's own standard uncertainty
    label: str
    assumed: dict[str, float] = field(default_factory=dict)  # conditions the file did not give
    # False: the file gives no uncertainty; the likelihood's floor, the rig's seed-to-seed scatter
    # (fit.Model: max(u, scatter)), is then the row's whole measurement uncertainty
    uncertainty_given: bool = True
    ignored: dict[str, str] = field(default_factory=dict)  # the file's conditions no surrogate takes (reported)

    def condition_text(self) -> str:
        return ", ".join(f"{k}={v:g}" + (" (assumed)" if k in self.assumed else "") for k, v in self.conditions.items())


def rig_metric(o: Observation) -> str:
    """The rig result's metric that measures the observation (mu_ie_s at fraction 0.6: mu_ie_s_60)."""
    if o.quantity.metric == "mu_ie_s":
        return f"mu_ie_s_{round(100 * o.conditions['shear_fraction'])}"
    return o.quantity.metric


class ObservationError(ValueError):
    """A measurement that the surrogates cannot represent (named with its line)."""


def observation(m: Measurement, defaults: dict[str, float]) -> Observation:
    """The Observation of a measurement row; a condition the row does not give (or gives as
    `unknown`) takes the campaign preset's value from `defaults` and is marked assumed."""
    rig = m.rig
    if rig not in QUANTITIES or m.quantity not in QUANTITIES[rig]:
        offered = "; ".join(f"{r}: {', '.join(q)}" for r, q in QUANTITIES.items())
        raise ObservationError(f"line {m.line}: {m.label}: no surrogate quantity for test {m.test!r} quantity "
                               f"{m.quantity!r} (the diagnosis knows {offered})")
    q = Quantity(rig, m.quantity)
    cond, assumed = {}, {}
    for name in q.conditions:
        text = m.conditions.get(name, "unknown")
        if text.lower() in ("unknown", ""):
            if name not in defaults:
                raise ObservationError(f"line {m.line}: {m.label}: condition {name} is not given and has no default")
            cond[name] = assumed[name] = float(defaults[name])
            continue
        try:
            cond[name] = float(text)
        except ValueError:
            raise ObservationError(f"line {m.line}: {m.label}: condition {name}={text!r} is not a number "
                                   f"(in {CONDITION_UNITS[name] or 'a fraction'})") from None
    ignored = {k: v for k, v in m.conditions.items() if k not in q.conditions}
    if not math.isfinite(m.uncertainty):  # not published (the JKU angles): the rig's seed scatter stands in
        return Observation(q, cond, float(m.value), 0.0, m.label, assumed, uncertainty_given=False, ignored=ignored)
    return Observation(q, cond, float(m.value), float(m.uncertainty), m.label, assumed, ignored=ignored)


def fraction_columns(metric_names: list[str]) -> list[tuple[int, float]]:
    """(column, shear fraction) of each per-shear-point metric (mu_ie_s_40 -> 0.4) of a store."""
    out = []
    for j, name in enumerate(metric_names):
        hit = _FRACTION_METRIC.match(name)
        if hit:
            out.append((j, int(hit.group(1)) / 100.0))
    return out


def test_conditions(o: Observation) -> tuple:
    """The conditions that make one test (one specimen, one run): all but the shear fraction,
    which is a point within a test."""
    return tuple(sorted((k, v) for k, v in o.conditions.items() if k != "shear_fraction"))


def training_tables(store, pooled=()) -> dict[Quantity, tuple[list[str], np.ndarray, np.ndarray]]:
    """{Quantity: (input names, inputs, values)} over the store's finished runs and those of the
    stores pooled with it (pooled_runs.py: their runs mapped into this store's parameter
    columns). Ring-shear runs give one mu_ie_s row per shear point, the fraction as an extra
    input."""
    from .pooled_runs import pooled_params
    rig = store.spec.rig
    names = list(store.spec.names)
    sources = [(store, store.params)] + [(o, pooled_params(store, o)) for o in pooled]
    out = {}
    for metric in QUANTITIES[rig]:
        q = Quantity(rig, metric)
        xs, ys, fractions = [], [], set()
        for st, params in sources:
            if metric == "mu_ie_s":
                for j, frac in fraction_columns(st.metric_names):
                    ok = counted_runs(st, st.metric_names[j])
                    xs.append(np.column_stack([params[ok], np.full(ok.sum(), frac)]))
                    ys.append(st.values[ok, j])
                    fractions.add(frac)
            elif metric in st.metric_names:
                j = st.metric_names.index(metric)
                ok = counted_runs(st, metric)
                xs.append(params[ok])
                ys.append(st.values[ok, j])
        if not xs:
            continue
        if metric != "mu_ie_s":
            out[q] = (names, np.vstack(xs), np.concatenate(ys))
        elif len(fractions) > 1:
            out[q] = (names + ["shear_fraction"], np.vstack(xs), np.concatenate(ys))
        else:  # one shear point: the fraction is a fixed condition of the store, not an input
            out[q] = (names, np.vstack(xs)[:, :-1], np.concatenate(ys))
    return out


def preset_conditions(store) -> dict[str, float]:
    """The conditions the store's runs have when they do not vary them (its preset with the
    campaign's fixed settings): the defaults for rows that do not give them."""
    cfg = store.spec.config({})
    out = {}
    for cname in CONDITIONS[store.spec.rig]:
        if cname == "shear_fraction":
            points = getattr(cfg, "shear_points", None) or []
            if len(points) == 1:  # a single shear point is the store's fixed fraction
                out[cname] = float(points[0])
            continue
        v = getattr(cfg, cname, None)
        if v is not None:
            out[cname] = float(v)
    return out
