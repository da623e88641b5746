"""A material's own particle density, size and stiffness, served by stores made for another
material (docs/diagnosis.md §1, "The material, said once").

Density, by similarity: a DEM model whose particle density, Young's modulus, cohesion energy
density and applied stresses are all multiplied by one factor k, with sizes, friction,
restitution, gravity and wall speeds unchanged, moves exactly as before. Every force scales by k —
weight and inertia (mass), Hertz contact (E), cohesion (energy density), the damping of a
restitution-based dashpot (sqrt(m k_n)), friction and rolling resistance (normal force), loads
(stress x area) — so the accelerations, overlaps and trajectories do not change. What a rig
measures then scales as: bulk densities and mass flow rates by k (the solid fraction
phi = rho_b / rho_p and a time do not), friction coefficients and angles not at all, stresses by k.
So a material of particle density rho_p is compared with stores made at rho_s through
s = rho_s / rho_p: its bulk densities and flow rates (and their uncertainties) times s, its
pre-shear stresses times s; back in the material's terms the cohesion energy density is divided
by s and the model's Young's modulus is the stores' divided by s — the same stiffness number
rho g d / E as the stores, the rule the tool applies. A modulus the user gives that differs from
that rule is reported (the stores do not vary the stiffness number), not used.

Size, by coarse-graining: the model's spheres are the stores' (3 mm in the ring shear and
angle-of-repose rigs; the hopper's 6/9 mm pair, mass-mean 8.1 mm), whatever the material's own
size — DEM calibrations are made on coarse-grained spheres, as seed 000's were. Friction
coefficients and angles are compared as they are (bench/similarity_default.py: they move by less
than the seed scatter for spheres 0.8 and 1.25 times the stores'). Solid fractions do depend on
the size in cells 5-10 spheres wide (~11 % per unit ln d): a bulk density is compared only when
the material's mean diameter is within 5 % of the rig store's, else left out with the reason. The one condition measured in sphere sizes is
the hopper's slot: a slot b of a material of mean size d is the stores' slot b d_s / d (the same
b/d), and its mass flow rate, by Beverloo's law for a slot of fixed length (W ~ rho_b sqrt(g)
(b - k d)^(3/2) L), is the stores' times (d / d_s)^(3/2). A discharge time also depends on the
fill's mass, which does not follow the size: such a row is left out, with the reason, when the
size differs. A slot that scales past the stores' range is left out as any condition is.

The size spread of a sieve table (or one given) becomes the base model's: the size-spread
candidate's neutral value, so the base model has the material's spread and the candidate asks
whether another fits better. A cohesion energy density is also given as a Bond number
Bo = k_c / (rho_p g d), cohesion over the particle's own weight stress, which the similarity
leaves unchanged."""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

from ..measurements import MeasurementError
from ..quantity_table import metric_spec
from .candidates import Candidate
from .quantities import Observation, ObservationError

MATERIAL_TEST = "material"  # the measurement file's test of the rows that describe the material
STIFFNESS_TOLERANCE = 0.1   # a given modulus this far (relative) from the similarity rule is reported
SIZE_TOLERANCE = 0.02       # a mean diameter this close (relative) to the stores' is their size
# a bulk density is compared only for a mean diameter this close to the rig store's: the cells are
# 5-10 spheres wide, and their solid fraction falls ~0.11 per unit ln(d) (ring shear -2.2 % / +2.6 %,
# hopper -2.0 % / +2.8 % for spheres 1.25x / 0.8x the stores', bench/results/similarity_default.md):
# within 5 % that is <= 0.6 %, below a lab's 1 %
SOLID_FRACTION_SIZE_TOLERANCE = 0.05
SIEVE_SUM_TOLERANCE = 0.02  # a sieve table's fractions must sum to 1 within this
SIEVE_DIAMETER_TOLERANCE = 0.1  # a diameter given beside a sieve table must agree with its mean within this
BEVERLOO_SLOT_EXPONENT = 1.5    # W ~ (b - k d)^(3/2) at a fixed slot length: the flow at the same b/d ~ d^(3/2)
SPREAD_PARAMETER = "size_spread"
G = 9.81


@dataclass
class MaterialProperties:
    """What the measurement file says of the material itself (None: not given). sieve: ((the
    class's lower sieve size in m, 0 for the pan; the mass fraction retained; the file's line), ...)."""
    particle_density: float | None = None
    particle_diameter: float | None = None
    youngs_modulus: float | None = None
    poisson_ratio: float | None = None
    size_spread: float | None = None
    sieve: tuple = field(default_factory=tuple)

    @classmethod
    def from_rows(cls, rows) -> "MaterialProperties":
        rows = [m for m in rows if m.test == MATERIAL_TEST]
        sieve = tuple(sorted((_sieve_size(m), float(m.value), m.line) for m in rows if m.quantity == "sieve_retained"))
        out = cls(**{m.quantity: float(m.value) for m in rows if m.quantity != "sieve_retained"}, sieve=sieve)
        if sieve:
            total = sum(w for _, w, _ in sieve)
            first, last = min(x[2] for x in sieve), max(x[2] for x in sieve)
            lines = f"lines {first}-{last}" if last > first else f"line {first}"
            if abs(total - 1.0) > SIEVE_SUM_TOLERANCE:
                raise MeasurementError(f"the sieve table ({lines}) sums to {total:.4g}, not 1 (mass fractions "
                                       f"retained on each sieve class, the pan included)")
            if out.particle_diameter is not None and \
                    abs(out.particle_diameter / out.sieve_mean - 1.0) > SIEVE_DIAMETER_TOLERANCE:
                raise MeasurementError(f"particle_diameter {out.particle_diameter * 1e3:.4g} mm disagrees with the sieve "
                                       f"table's mean {out.sieve_mean * 1e3:.4g} mm ({lines}); give one of them")
        return out

    @property
    def sieve_mean(self) -> float | None:
        """The sieve table's mass-mean diameter, each class at its lower sieve size (seed 000's reduction,
        particleDistroFun.m, which the JKU mean diameters are)."""
        if not self.sieve:
            return None
        return sum(d * w for d, w, _ in self.sieve) / sum(w for _, w, _ in self.sieve)

    @property
    def mean_diameter(self) -> float | None:
        return self.particle_diameter if self.particle_diameter is not None else self.sieve_mean

    @property
    def spread(self) -> float | None:
        """The size spread in the rigs' terms (diameters uniform in d (1 +- spread)): the one given, or
        the sieve table's, the uniform distribution of the same relative standard deviation
        (sqrt(3) sd / mean)."""
        if self.size_spread is not None or not self.sieve:
            return self.size_spread
        mean, total = self.sieve_mean, sum(w for _, w, _ in self.sieve)
        sd = math.sqrt(sum(w * (d - mean) ** 2 for d, w, _ in self.sieve) / total)
        return math.sqrt(3.0) * sd / mean


def _sieve_size(m) -> float:
    text = m.conditions.get("sieve_mm", "")
    if text == "pan":
        return 0.0
    try:
        v = float(text) * 1e-3
    except ValueError:
        raise MeasurementError(f"line {m.line}: sieve_retained needs the class's lower sieve size, sieve_mm=<mm> or "
                               f"sieve_mm=pan, got {text!r}") from None
    if not 0.0 < v < 1.0:
        raise MeasurementError(f"line {m.line}: sieve_mm={text} is not a sieve size in mm")
    return v


@dataclass
class Scaling:
    """How one material's rows are compared with stores made at `store_density`, `store_modulus`
    and, per rig, the mass-mean sphere diameter `store_diameters`."""
    material: MaterialProperties
    store_density: float
    store_modulus: float
    store_diameters: dict = field(default_factory=dict)  # rig -> m

    @property
    def factor(self) -> float:
        """s = rho_store / rho_material (1 when the file gives no particle density)."""
        rho = self.material.particle_density
        return 1.0 if rho is None else self.store_density / rho

    def size_ratio(self, rig: str) -> float:
        """d_store / d_material for the rig's store (1 when the file gives no size or it is the store's)."""
        d, ds = self.material.mean_diameter, self.store_diameters.get(rig)
        if d is None or ds is None or abs(ds / d - 1.0) <= SIZE_TOLERANCE:
            return 1.0
        return ds / d

    def observation(self, o: Observation) -> Observation:
        """The row in the stores' terms: a density-like value and its uncertainty times s, a pre-shear
        stress times s; on a hopper of another sphere size, the slot at the same b/d and the flow
        rate by Beverloo's law (ObservationError: a row that cannot be carried over)."""
        s, r = self.factor, self.size_ratio(o.quantity.rig)
        if s == 1.0 and r == 1.0:
            return o
        if o.quantity.metric == "bulk_density" and abs(math.log(r)) > math.log1p(SOLID_FRACTION_SIZE_TOLERANCE):
            raise ObservationError(f"{o.label}: the material's mean diameter {self.material.mean_diameter * 1e3:.4g} mm is "
                                   f"not the {o.quantity.rig} store's {self.store_diameters[o.quantity.rig] * 1e3:.3g} mm "
                                   f"(within {100 * SOLID_FRACTION_SIZE_TOLERANCE:g} %), and a cell a few spheres wide "
                                   f"packs to a solid fraction that depends on the size (~11 % per unit ln d: "
                                   f"bench/results/similarity_default.md)")
        k = s if metric_spec(o.quantity.metric).scales_with_density else 1.0
        cond = {c: v * s if c == "preshear_stress" else v for c, v in o.conditions.items()}
        if r != 1.0 and "slot_width" in cond:
            if o.quantity.metric == "discharge_time":
                raise ObservationError(f"{o.label}: a discharge time depends on the fill's mass, which does not follow "
                                       f"the particle size ({self.material.mean_diameter * 1e3:.4g} mm, the hopper "
                                       f"store's {self.store_diameters[o.quantity.rig] * 1e3:.4g} mm); give the mass "
                                       f"flow rate")
            cond["slot_width"] *= r
            if o.quantity.metric == "mass_flow_rate":
                k *= r ** BEVERLOO_SLOT_EXPONENT
        return dataclasses.replace(o, value=o.value * k, uncertainty=o.uncertainty * k, conditions=cond)

    def condition_note(self, o: Observation) -> str:
        """How the row's conditions were carried over to the stores (empty: as given)."""
        said = []
        if self.factor != 1.0 and "preshear_stress" in o.conditions:
            said.append(f"the pre-shear stress x{self.factor:.4g}, the stores' particle density")
        r = self.size_ratio(o.quantity.rig)
        if r != 1.0 and "slot_width" in o.conditions:
            said.append(f"the slot x{r:.4g}, the same slot width over size for the stores' "
                        f"{1e3 * self.store_diameters[o.quantity.rig]:.3g} mm spheres")
        return f" ({'; '.join(said)})" if said else ""

    def cohesion_to_material(self, value: float) -> float:
        return value / self.factor

    def bond_number(self, cohesion_energy_density: float, rig: str = "ring-shear") -> float:
        """Bo = k_c / (rho_p g d) of the stores' model (unchanged by the density similarity)."""
        return cohesion_energy_density / (self.store_density * G * self.store_diameters.get(rig, math.nan))

    @property
    def model_modulus(self) -> float:
        """The Young's modulus of the material's model: the stores' stiffness number kept."""
        return self.store_modulus / self.factor

    def candidates(self, candidates: list[Candidate], ranges: dict) -> list[Candidate]:
        """The candidates with the material's size spread as the size-spread candidate's neutral value
        (within the stores' range)."""
        spread = self.material.spread
        if spread is None or SPREAD_PARAMETER not in ranges:
            return candidates
        lo, hi = ranges[SPREAD_PARAMETER]
        v = min(max(spread, lo), hi)
        return [dataclasses.replace(c, neutral=lambda theta, v=v: v,
                                    assumption=f"diameters uniform in d (1 +- {v:.3g}), the material's spread")
                if c.parameter == SPREAD_PARAMETER else c for c in candidates]

    def notes(self, ranges: dict | None = None) -> list[str]:
        m, out = self.material, []
        if m.particle_density is not None and self.factor != 1.0:
            out.append(f"particle density {m.particle_density:.6g} kg/m^3 (the stores: {self.store_density:.6g}): bulk "
                       f"densities and flow rates compared as solid fractions, pre-shear stresses scaled by "
                       f"{self.factor:.4g} (similarity: docs/diagnosis.md §1); the model's Young's modulus "
                       f"{self.model_modulus:.4g} Pa keeps the stores' stiffness number")
        if m.youngs_modulus is not None and abs(m.youngs_modulus / self.model_modulus - 1.0) > STIFFNESS_TOLERANCE:
            out.append(f"Young's modulus given {m.youngs_modulus:.4g} Pa, but the stores serve a stiffness number "
                       f"that needs {self.model_modulus:.4g} Pa at this particle density ({m.youngs_modulus / self.model_modulus:.3g}x "
                       f"stiffer than the stores); compared with the stores' stiffness number, the result is "
                       f"unconfirmed for the modulus given (a campaign at that modulus would confirm it)")
        d = m.mean_diameter
        if d is not None:
            where = " (the sieve table's mass mean)" if m.particle_diameter is None else ""
            sizes = ", ".join(f"{rig} {ds * 1e3:.3g} mm" for rig, ds in sorted(self.store_diameters.items()))
            out.append(f"mean particle diameter {d * 1e3:.4g} mm{where}: the model's spheres are the stores' "
                       f"coarse-grained ones ({sizes}); angles and friction coefficients compared as they are, bulk "
                       f"densities where the size is within {100 * SOLID_FRACTION_SIZE_TOLERANCE:g} % of a rig store's" + (", hopper slots at the same slot width over size and flow rates by Beverloo's "
                                      "law" if self.size_ratio("hopper") != 1.0 else ""))
        spread = m.spread
        if spread is not None and ranges is not None and SPREAD_PARAMETER in ranges:
            lo, hi = ranges[SPREAD_PARAMETER]
            src = "given" if m.size_spread is not None else "of the sieve table (sqrt(3) sd / mean)"
            held = "" if lo <= spread <= hi else f"; past the stores' range [{lo:g}, {hi:g}]: the model's is {min(max(spread, lo), hi):g}"
            out.append(f"size spread {spread:.3g} {src}: the base model's{held}")
        return out

    def as_dict(self) -> dict:
        given = dataclasses.asdict(self.material)
        given["sieve"] = [[d, w] for d, w, _ in self.material.sieve]
        return {"given": given, "store_particle_density": self.store_density, "factor": self.factor,
                "model_youngs_modulus": self.model_modulus, "mean_diameter": self.material.mean_diameter,
                "size_spread": self.material.spread, "store_diameters": self.store_diameters,
                "size_ratio": {rig: self.size_ratio(rig) for rig in self.store_diameters}}
