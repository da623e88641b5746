"""A material's own particle density, served by stores made at another one (docs/diagnosis.md §1,
"The material, said once").

Similarity: a DEM model whose particle density, Young's modulus, cohesion energy density and
applied stresses are all multiplied by one factor k, with sizes, friction, restitution, gravity
and wall speeds unchanged, moves exactly as before. Every force scales by k — weight and inertia
(mass), Hertz contact (E), cohesion (energy density), the damping of a restitution-based dashpot
(sqrt(m k_n)), friction and rolling resistance (normal force), loads (stress x area) — so the
accelerations, overlaps and trajectories do not change. What a rig measures then scales as:
bulk densities and mass flow rates by k (the solid fraction phi = rho_b / rho_p and a time do
not), friction coefficients and angles not at all, stresses by k.

So a material of particle density rho_p is compared with stores made at rho_s through
s = rho_s / rho_p: its bulk densities and flow rates (and their uncertainties) times s, its
pre-shear stresses times s; the parameters found are the stores', and back in the material's
terms the cohesion energy density is divided by s and the model's Young's modulus is the
stores' divided by s — the same stiffness number rho g d / E as the stores, the rule the tool
applies. A Young's modulus the user gives that differs from that rule changes the stiffness
number, which the stores do not vary: the report says so, and by how much, and the comparison
keeps the rule. The particle size is not scaled: the stores' spheres are coarse-grained to a
size of their own (3 mm), and a different size given is reported, not used."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from ..quantity_table import metric_spec
from .quantities import Observation

MATERIAL_TEST = "material"  # the measurement file's test of the rows that describe the material
STIFFNESS_TOLERANCE = 0.1   # a given modulus this far (relative) from the similarity rule is reported


@dataclass
class MaterialProperties:
    """What the measurement file says of the material itself (None: not given)."""
    particle_density: float | None = None
    particle_diameter: float | None = None
    youngs_modulus: float | None = None
    poisson_ratio: float | None = None

    @classmethod
    def from_rows(cls, rows) -> "MaterialProperties":
        return cls(**{m.quantity: float(m.value) for m in rows if m.test == MATERIAL_TEST})


@dataclass
class Scaling:
    """How one material's rows are compared with stores made at `store_density`."""
    material: MaterialProperties
    store_density: float
    store_modulus: float

    @property
    def factor(self) -> float:
        """s = rho_store / rho_material (1 when the file gives no particle density)."""
        rho = self.material.particle_density
        return 1.0 if rho is None else self.store_density / rho

    def observation(self, o: Observation) -> Observation:
        """The row in the stores' terms: a density-like value and its uncertainty times s, a
        pre-shear stress times s."""
        s = self.factor
        if s == 1.0:
            return o
        k = s if metric_spec(o.quantity.metric).scales_with_density else 1.0
        cond = {c: v * s if c == "preshear_stress" else v for c, v in o.conditions.items()}
        return dataclasses.replace(o, value=o.value * k, uncertainty=o.uncertainty * k, conditions=cond)

    def cohesion_to_material(self, value: float) -> float:
        return value / self.factor

    @property
    def model_modulus(self) -> float:
        """The Young's modulus of the material's model: the stores' stiffness number kept."""
        return self.store_modulus / self.factor

    def notes(self) -> list[str]:
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
        if m.particle_diameter is not None:
            out.append(f"particle diameter given {m.particle_diameter * 1e3:.4g} mm: the stores' spheres are "
                       f"coarse-grained to their own size (3 mm), which the comparison keeps (slot widths are "
                       f"compared as given)")
        return out

    def as_dict(self) -> dict:
        return {"given": dataclasses.asdict(self.material), "store_particle_density": self.store_density,
                "factor": self.factor, "model_youngs_modulus": self.model_modulus}
