"""The one table of measured quantities. For each test a measurement file names, and each of its
quantities: the SI unit, the units accepted (converted on reading), the physically possible
range, the test conditions the rig's surrogates take as inputs (None: a quantity a file may carry
that no surrogate models, such as a yield-locus output), the lab-like noise of synthetic sets, and
whether the value scales with the particles' solid density. The measurement reader, the
calibration's quantities, the synthetic sets and the reports read it; nothing else lists
quantities."""
from __future__ import annotations

import re
from dataclasses import dataclass


@dataclass(frozen=True)
class QuantitySpec:
    unit: str                                  # SI unit ('' for a coefficient)
    units: dict                                # accepted unit (lower case) -> factor to SI
    range: tuple[float, float]                 # physically possible values, SI
    conditions: tuple[str, ...] | None = None  # the surrogates' condition inputs; None: not modelled
    noise: tuple[str, float] | None = None     # synthetic sets' lab noise: ('rel', fraction) or ('abs', SI)
    scales_with_density: bool = False          # proportional to the solid density (bulk density, mass flow)
    zero_ok: bool = False                      # 0 is a possible value (else a range starting at 0 is open there)


# the rig that models each test ("poured": the bulk density of the angle-of-repose rig's filled cylinder)
RIG_OF_TEST = {"ring_shear": "ring-shear", "aor": "aor", "hopper": "hopper", "poured": "aor"}
# the test a rig's own value is written as in a measurement file (a DEM-made set)
TEST_OF_RIG = {"ring-shear": "ring_shear", "aor": "aor", "hopper": "hopper"}
# every condition a measurement row may give, with its unit
CONDITION_UNITS = {"preshear_stress": "Pa", "shear_fraction": "", "slot_width": "m", "size_cut_mm": "mm",
                   "mean_diameter_mm": "mm", "sieve_mm": "mm"}
# the conditions each rig's surrogates take as inputs (SI)
SURROGATE_CONDITIONS = {"ring-shear": ("preshear_stress", "shear_fraction"), "aor": (), "hopper": ("slot_width",)}

_COEF = dict(unit="", units={"": 1.0, "-": 1.0, "1": 1.0}, range=(0.0, 5.0))
_DENSITY = dict(unit="kg/m^3", units={"kg/m^3": 1.0, "kg/m3": 1.0, "kg m-3": 1.0, "g/cm^3": 1000.0, "g/cm3": 1000.0,
                                      "g/ml": 1000.0, "t/m^3": 1000.0, "t/m3": 1000.0}, range=(10.0, 2.5e4),
                noise=("rel", 0.01), scales_with_density=True)
_STRESS = dict(unit="Pa", units={"pa": 1.0, "kpa": 1000.0}, range=(0.0, 1e8))
_ANGLE = dict(unit="deg", units={"deg": 1.0, "°": 1.0, "degree": 1.0, "degrees": 1.0, "rad": 57.29577951308232},
              range=(0.0, 90.0))
_FRACTION = dict(unit="", units={"": 1.0, "-": 1.0, "%": 0.01}, range=(0.0, 1.0), zero_ok=True)
_FRICTION = dict(_COEF, noise=("rel", 0.02))

TABLE: dict[str, dict[str, QuantitySpec]] = {
    # the material itself, said once (calibration/similarity.py): not compared, used to compare
    "material": {
        "particle_density": QuantitySpec(unit="kg/m^3", units=_DENSITY["units"], range=(100.0, 2.5e4)),
        "particle_diameter": QuantitySpec(unit="m", units={"m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6},
                                          range=(1e-7, 1.0)),
        "youngs_modulus": QuantitySpec(unit="Pa", units={"pa": 1.0, "kpa": 1e3, "mpa": 1e6, "gpa": 1e9}, range=(1e3, 1e13)),
        "poisson_ratio": QuantitySpec(unit="", units={"": 1.0, "-": 1.0}, range=(0.0, 0.5)),
        # diameters uniform in d (1 +- spread), the rigs' own description of a size distribution
        "size_spread": QuantitySpec(**dict(_FRACTION, units={"": 1.0, "-": 1.0})),
        # a sieve table: the mass fraction retained on each class, named by its lower sieve size
        # (condition sieve_mm=<mm>, or sieve_mm=pan), as ../shared/data/jku_psd.csv gives them
        "sieve_retained": QuantitySpec(**_FRACTION),
    },
    "ring_shear": {
        "mu_ie_ps": QuantitySpec(**_FRICTION, conditions=("preshear_stress",)),
        "mu_ie_s": QuantitySpec(**_FRICTION, conditions=("preshear_stress", "shear_fraction")),
        "bulk_density": QuantitySpec(**_DENSITY, conditions=("preshear_stress",)),
        "tau_shear": QuantitySpec(**_STRESS), "tau_preshear": QuantitySpec(**_STRESS),
        "phi_e": QuantitySpec(**_ANGLE), "phi_lin": QuantitySpec(**_ANGLE), "phi_sf": QuantitySpec(**_ANGLE),
        "sigma_1": QuantitySpec(**_STRESS), "sigma_c": QuantitySpec(**_STRESS),
        "yield_locus_intercept": QuantitySpec(**_STRESS),
        "ffc": QuantitySpec(unit="", units={"": 1.0, "-": 1.0}, range=(0.0, 1e6)),
    },
    "aor": {
        "angle_of_repose": QuantitySpec(**_ANGLE, conditions=(), noise=("abs", 0.5), zero_ok=True),
        "bulk_density": QuantitySpec(**_DENSITY, conditions=()),
    },
    "poured": {"bulk_density": QuantitySpec(**_DENSITY, conditions=())},
    "hopper": {
        "mass_flow_rate": QuantitySpec(unit="kg/s", units={"kg/s": 1.0, "g/s": 1e-3, "t/h": 1.0 / 3.6}, range=(0.0, 1e6),
                                       conditions=("slot_width",), noise=("rel", 0.02), scales_with_density=True),
        "discharge_time": QuantitySpec(unit="s", units={"s": 1.0, "min": 60.0}, range=(0.0, 1e7),
                                       conditions=("slot_width",), noise=("rel", 0.02)),
        "bulk_density": QuantitySpec(**_DENSITY, conditions=("slot_width",)),
    },
}


def rig_quantities() -> dict[str, dict[str, tuple[str, ...]]]:
    """{rig: {metric: its conditions}} for every quantity a rig's surrogates model, in the table's order."""
    out: dict[str, dict[str, tuple[str, ...]]] = {}
    for test, quantities in TABLE.items():
        for name, spec in quantities.items():
            if spec.conditions is not None:
                known = out.setdefault(RIG_OF_TEST[test], {}).setdefault(name, spec.conditions)
                assert known == spec.conditions, f"{name}: two tests of one rig with other conditions"
    return out


def metric_spec(metric: str) -> QuantitySpec:
    """The table's row for a rig metric (the first test that names it; the rows agree on units,
    noise and density scaling)."""
    for quantities in TABLE.values():
        if metric in quantities:
            return quantities[metric]
    raise KeyError(metric)


# A ring-shear run measures mu_ie_s at each shear point: the rig's metric is named by the point's
# shear fraction in per cent (mu_ie_s at 0.6 of the pre-shear stress: mu_ie_s_60).
_PER_FRACTION = re.compile(r"^mu_ie_s_(\d+)$")


def per_fraction_metric(fraction: float) -> str:
    return f"mu_ie_s_{round(100 * fraction)}"


def fraction_of_metric(name: str) -> float | None:
    """The shear fraction of a per-shear-point metric name (mu_ie_s_40 -> 0.4), else None."""
    hit = _PER_FRACTION.match(name)
    return int(hit.group(1)) / 100.0 if hit else None
