"""One name for a calibrated quantity: (rig, metric) plus the test conditions it is measured at.

A measurement row becomes an Observation: its Quantity, the values of the conditions the
surrogate takes as inputs (pre-shear stress and shear fraction for the ring shear, slot width
for the hopper), value and standard uncertainty. A campaign store becomes one training table
per Quantity: inputs = the store's varied parameters followed by the quantity's conditions
that the store does not vary itself (the shear fraction: one run measures several)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from ..measurements import Measurement
from ..quantity_table import CONDITION_UNITS, SURROGATE_CONDITIONS, TABLE, per_fraction_metric, rig_quantities

# the conditions each rig's surrogates take and the quantities they model (pydem.quantity_table)
CONDITIONS = SURROGATE_CONDITIONS
QUANTITIES = rig_quantities()
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
    # False: the file gives no uncertainty; the rig's seed-to-seed scatter then stands in for the
    # lab's repeatability (fit.row_noise)
    uncertainty_given: bool = True
    ignored: dict[str, str] = field(default_factory=dict)  # the file's conditions no surrogate takes (reported)
    # "lab": a lab's measurement, its uncertainty the lab's repeatability; "dem": one DEM run, which
    # also carries that run's seed scatter (measurements.ORIGINS; fit.row_noise)
    origin: str = "lab"
    extrapolated: dict[str, str] = field(default_factory=dict)  # conditions a little past the campaign's declared range (setup.RANGE_TOLERANCE)

    def condition_text(self) -> str:
        return ", ".join(f"{k}={v:g}" + (" (assumed)" if k in self.assumed else "") for k, v in self.conditions.items())


def rig_metric(o: Observation) -> str:
    """The rig result's metric that measures the observation (mu_ie_s at fraction 0.6: mu_ie_s_60)."""
    if o.quantity.metric == "mu_ie_s":
        return per_fraction_metric(o.conditions["shear_fraction"])
    return o.quantity.metric


class ObservationError(ValueError):
    """A measurement that the surrogates cannot represent (named with its line)."""


def observation(m: Measurement, defaults: dict[str, float]) -> Observation:
    """The Observation of a measurement row; a condition the row does not give (or gives as
    `unknown`) takes the campaign preset's value from `defaults` and is marked assumed."""
    rig = m.rig
    if rig not in QUANTITIES or m.quantity not in QUANTITIES[rig]:
        offered = "; ".join(f"{r}: {', '.join(q)}" for r, q in QUANTITIES.items())
        # the ring-shear quantities a file may carry but no surrogate models: a Schulze tester's
        # outputs of one yield locus (pydem.rigs.yield_locus) and its raw stresses
        why = (f"{m.quantity} is derived from the yield locus's points (Schulze); the diagnosis fits the points "
               f"themselves — give the row's mu_ie_ps and mu_ie_s at each shear_fraction"
               if rig == "ring-shear" and m.quantity in TABLE[m.test] else "no surrogate quantity")
        raise ObservationError(f"line {m.line}: {m.label}: {why} for test {m.test!r} quantity {m.quantity!r} (the "
                               f"diagnosis knows {offered})")
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
        return Observation(q, cond, float(m.value), 0.0, m.label, assumed, uncertainty_given=False, ignored=ignored,
                           origin=m.origin)
    return Observation(q, cond, float(m.value), float(m.uncertainty), m.label, assumed, ignored=ignored, origin=m.origin)


def test_conditions(o: Observation) -> tuple:
    """The conditions that make one test (one specimen, one run): all but the shear fraction,
    which is a point within a test."""
    return tuple(sorted((k, v) for k, v in o.conditions.items() if k != "shear_fraction"))


