"""The outputs a Schulze ring shear tester reports for one yield locus (Schulze, Powders and Bulk
Solids, ch. 3), from the pre-shear point (sigma_pre, tau_pre) and the shear points (sigma_i,
tau_i) of one consolidation stress. Pure functions; the linearised locus tau = c + sigma tan(phi_lin)
is the least-squares line through the shear points.

- cohesion c: the locus's intercept;
- unconfined yield strength sigma_c: the Mohr circle through the origin tangent to the locus,
  sigma_c = 2 c cos(phi_lin) / (1 - sin(phi_lin));
- major consolidation stress sigma_1: the Mohr circle through the pre-shear point tangent to the
  locus (centre p, radius r = c cos(phi_lin) + p sin(phi_lin)), sigma_1 = p + r;
- flow function ffc = sigma_1 / sigma_c (inf for a cohesionless locus);
- effective angle of internal friction phi_e: the line through the origin tangent to that circle,
  sin(phi_e) = r / p;
- steady-state flow angle phi_sf = atan(tau_pre / sigma_pre);
- Jenike's flowability class of ffc (flowability).

Loci of one material (the rig's configuration but for the consolidation stress) make one flow
function; loci of different materials are never joined (Locus.material)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass
class LocusResult:
    phi_lin: float    # deg
    cohesion: float   # Pa
    sigma_c: float    # Pa
    sigma_1: float    # Pa
    ffc: float
    phi_e: float      # deg
    phi_sf: float     # deg
    centre: float     # consolidation Mohr circle: centre and radius (Pa), for plots
    radius: float


def linear_locus(sigma, tau) -> tuple[float, float]:
    """(tan(phi_lin), c): least squares through the shear points (two or more distinct stresses)."""
    sigma, tau = np.asarray(sigma, float), np.asarray(tau, float)
    if len(np.unique(sigma)) < 2:
        raise ValueError("a yield locus needs shear points at two or more normal stresses")
    slope, icpt = np.polyfit(sigma, tau, 1)
    return float(slope), float(icpt)


def consolidation_circle(sigma_pre: float, tau_pre: float, tan_phi: float, c: float) -> tuple[float, float]:
    """(centre p, radius r) of the Mohr circle through (sigma_pre, tau_pre) tangent to the locus:
    (sigma_pre - p)^2 + tau_pre^2 = (c cos(phi) + p sin(phi))^2, the root with p >= sigma_pre."""
    phi = math.atan(tan_phi)
    s, k = math.sin(phi), c * math.cos(phi)
    # (1 - s^2) p^2 - 2 (sigma_pre + k s) p + sigma_pre^2 + tau_pre^2 - k^2 = 0
    a, b, cc = 1.0 - s * s, -2.0 * (sigma_pre + k * s), sigma_pre ** 2 + tau_pre ** 2 - k * k
    disc = b * b - 4 * a * cc
    if disc < 0:
        raise ValueError("the pre-shear point lies above the yield locus: no Mohr circle through it is tangent")
    p = (-b + math.sqrt(disc)) / (2 * a)
    return p, k + p * s


def evaluate(sigma_pre: float, tau_pre: float, sigma, tau) -> LocusResult:
    tan_phi, c = linear_locus(sigma, tau)
    phi = math.atan(tan_phi)
    c_pos = max(c, 0.0)  # a negative intercept is no cohesion (a concave locus)
    sigma_c = 2 * c_pos * math.cos(phi) / (1 - math.sin(phi))
    p, r = consolidation_circle(sigma_pre, tau_pre, tan_phi, c)
    sigma_1 = p + r
    return LocusResult(math.degrees(phi), c, sigma_c, sigma_1, sigma_1 / sigma_c if sigma_c > 0 else math.inf,
                       math.degrees(math.asin(min(r / p, 1.0))), math.degrees(math.atan2(tau_pre, sigma_pre)), p, r)


# Jenike's classes of the flow function ffc (Schulze, Powders and Bulk Solids, §3.3): lower bounds
FLOWABILITY = ((10.0, "free-flowing"), (4.0, "easy-flowing"), (2.0, "cohesive"), (1.0, "very cohesive"),
               (-math.inf, "not flowing"))
# a rig configuration's keys that set the test's conditions, not the material
CONDITION_KEYS = {"preshear_stress", "shear_points", "seed"}


def flowability(ffc: float) -> str:
    """Jenike's class of a flow function value: ffc < 1 not flowing, 1-2 very cohesive, 2-4
    cohesive, 4-10 easy-flowing, >= 10 free-flowing (a cohesionless locus: ffc infinite)."""
    return next(name for bound, name in FLOWABILITY if ffc >= bound)


@dataclass
class Locus:
    """One yield locus as measured: the pre-shear point and the shear points, and the material's
    identity (the rig's configuration without its conditions; "" when the result does not say)."""
    label: str
    sigma_pre: float
    tau_pre: float
    sigma: list
    tau: list
    material: str = ""

    @classmethod
    def from_result(cls, data: dict, label: str = "") -> "Locus":
        """From a ring-shear rig result (RigResult.to_dict() or its JSON file)."""
        if data.get("rig") != "ring-shear":
            raise ValueError(f"{label or 'result'}: a ring-shear result is needed, got rig {data.get('rig')!r}")
        m, pts = data["metrics"], data.get("info", {}).get("shear_points", [])
        if len({p["fraction"] for p in pts}) < 2:
            raise ValueError(f"{label or 'result'}: a yield locus needs shear points at two or more fractions "
                             f"(run with --set shear_points=[0.4,0.6,0.8])")
        config = data.get("provenance", {}).get("config", {})
        material = ", ".join(f"{k}={v}" for k, v in sorted(config.items()) if k not in CONDITION_KEYS)
        return cls(label, float(m["sigma_preshear"]["value"]), float(m["tau_preshear"]["value"]),
                   [p["sigma"] for p in pts], [p["tau_peak"] for p in pts], material)

    def evaluate(self) -> LocusResult:
        return evaluate(self.sigma_pre, self.tau_pre, self.sigma, self.tau)


def plot_loci(loci: list[Locus], path) -> None:
    """Left: each locus — shear points, pre-shear point, the linearised locus, the consolidation
    Mohr circle (sigma_1) and the unconfined-yield circle (sigma_c). Right: one flow function
    sigma_c(sigma_1) per material (Locus.material), with Jenike's ffc = 1, 2, 4, 10 lines."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax, af) = plt.subplots(1, 2, figsize=(11, 4.6), layout="constrained")
    t = np.linspace(0.0, np.pi, 200)
    s1s, scs = [], []
    for k, lc in enumerate(loci):
        r = lc.evaluate()
        col = f"C{k}"
        ax.plot(lc.sigma, lc.tau, "o", color=col, label=f"{lc.label}: shear points")
        ax.plot([lc.sigma_pre], [lc.tau_pre], "s", color=col, mfc="none", ms=8, label=f"{lc.label}: pre-shear")
        x = np.linspace(0.0, r.sigma_1, 50)
        ax.plot(x, r.cohesion + x * math.tan(math.radians(r.phi_lin)), "-", color=col, lw=1)
        ax.plot(r.centre + r.radius * np.cos(t), r.radius * np.sin(t), "--", color=col, lw=1)
        if r.sigma_c > 0:
            ax.plot(0.5 * r.sigma_c * (1 + np.cos(t)), 0.5 * r.sigma_c * np.sin(t), ":", color=col, lw=1)
        s1s.append(r.sigma_1)
        scs.append(r.sigma_c)
    ax.set_xlabel("normal stress sigma (Pa)")
    ax.set_ylabel("shear stress tau (Pa)")
    ax.set_xlim(left=0.0)
    ax.set_ylim(bottom=0.0)
    ax.set_aspect("equal")
    ax.legend(fontsize=6)
    ax.set_title("yield loci with Mohr circles (dashed: sigma_1, dotted: sigma_c)", fontsize=9)
    top = max(s1s) * 1.1
    for ffc in (1, 2, 4, 10):
        af.plot([0, top], [0, top / ffc], color="0.7", lw=0.8)
        af.text(top, top / ffc, f"ffc = {ffc}", fontsize=7, color="0.4", va="center")
    materials = list(dict.fromkeys(lc.material for lc in loci))
    for m, material in enumerate(materials):
        pts = sorted((s1, sc) for s1, sc, lc in zip(s1s, scs, loci) if lc.material == material)
        name = f"material {m + 1}" if len(materials) > 1 else "flow function"
        af.plot(*zip(*pts), "o-", color="k" if len(materials) == 1 else f"C{m}", label=name)
    if len(materials) > 1:
        af.legend(fontsize=7)
    af.set_xlabel("major consolidation stress sigma_1 (Pa)")
    af.set_ylabel("unconfined yield strength sigma_c (Pa)")
    af.set_xlim(0, top * 1.15)
    af.set_ylim(bottom=0.0)
    af.set_title("flow function", fontsize=9)
    fig.savefig(path, dpi=110)
    plt.close(fig)
