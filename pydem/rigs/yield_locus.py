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
- steady-state flow angle phi_sf = atan(tau_pre / sigma_pre)."""
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
