"""Grey relational analysis (seed 001, section 3.1, Eqs. 2-6): how strongly each input
parameter's sequence over the cases follows the response's (the discharge time), as a grade
and as a percentage weight.

    x'_ij = x_ij / x_i1,  y'_j = y_j / y_1                       (initialisation normalisation)
    xi_ij = (min_i min_j |y'_j - x'_ij| + rho max_i max_j |.|) / (|y'_j - x'_ij| + rho max max |.|)
    r_i = mean_j xi_ij,   p_i = 100 r_i / sum_i r_i              (rho = 0.5 in the seed)

Plain numpy: the grades are a few sums over a 11 x 25 table."""
from __future__ import annotations

import numpy as np


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
