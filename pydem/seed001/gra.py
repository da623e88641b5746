"""Grey relational analysis (seed 001, section 3.1, Eqs. 2-6): how strongly each input
parameter's sequence over the cases follows the response's (the discharge time), as a grade
and as a percentage weight.

    x'_ij = x_ij / x_i1,  y'_j = y_j / y_1                       (initialisation normalisation)
    xi_ij = (min_i min_j |y'_j - x'_ij| + rho max_i max_j |.|) / (|y'_j - x'_ij| + rho max max |.|)
    r_i = mean_j xi_ij,   p_i = 100 r_i / sum_i r_i              (rho = 0.5 in the seed)

Plain numpy: the grades are a few sums over a 11 x 25 table."""
from __future__ import annotations

import numpy as np

from ..rigs.table1 import TABLE1


def grey_relational(x, y, rho: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """x: (parameters, cases), y: (cases,) -> (grades r_i, weights p_i in %). The first case is
    the normalisation reference, so it must have no zero entry."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    if x.ndim != 2 or y.ndim != 1 or x.shape[1] != y.size or y.size < 2:
        raise ValueError(f"grey_relational: x must be (parameters, cases) and y (cases,), got {x.shape} and {y.shape}")
    if not 0.0 <= rho <= 1.0:
        raise ValueError(f"grey_relational: the distinguishing coefficient rho must lie in [0, 1], got {rho}")
    if y[0] == 0.0 or np.any(x[:, 0] == 0.0):
        raise ValueError("grey_relational: the first case is the normalisation reference: it needs no zero value")
    delta = np.abs(y / y[0] - x / x[:, :1])
    lo, hi = delta.min(), delta.max()
    xi = np.ones_like(delta) if hi == 0.0 else (lo + rho * hi) / (delta + rho * hi)
    grades = xi.mean(axis=1)
    return grades, 100.0 * grades / grades.sum()


# the 11 Table 1 parameters, in the seed's order, and how to read each from a TABLE1 row
PARAMETERS = ("mu_pp", "mu_pw", "e_pp", "e_pw", "mu_r", "density", "diameter", "youngs_modulus", "poisson_ratio",
              "particles", "fine_fraction")


def parameter_row(case: str) -> dict[str, float]:
    """The case's 11 parameters; the diameter is the volume-weighted mean of its two sizes (the
    seed lists one d per case: its fine/coarse pair weighted by the fine volume fraction)."""
    n, nu, e_gpa, phi, epp, ewp, mupp, muwp, mur, dd, rho = TABLE1[case]
    return {"mu_pp": mupp, "mu_pw": muwp, "e_pp": epp, "e_pw": ewp, "mu_r": mur, "density": float(rho),
            "diameter": phi * dd[0] + (1.0 - phi) * dd[1], "youngs_modulus": e_gpa * 1e9, "poisson_ratio": nu,
            "particles": float(n), "fine_fraction": phi}


def gra_tables(discharge: dict[str, float], rho: float = 0.5) -> dict[str, dict[str, float]]:
    """{group: {parameter: weight %}} for each packing (its cases in Table 1 order) and "all"."""
    groups = {p: [c for c in TABLE1 if c.split("-")[0] == p and c in discharge] for p in ("A", "B1", "B2", "B3", "B4")}
    groups["all"] = [c for c in TABLE1 if c in discharge]
    out = {}
    for name, cases in groups.items():
        if len(cases) < 2:
            continue
        x = np.array([[parameter_row(c)[p] for c in cases] for p in PARAMETERS])
        _, weights = grey_relational(x, [discharge[c] for c in cases], rho)
        out[name] = dict(zip(PARAMETERS, map(float, weights)))
    return out
