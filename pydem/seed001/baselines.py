"""The physics baselines and image gauges seed 001's networks are judged beside: Beverloo's slot
law for a case's discharge time (C and k fitted on training cases only) and, per frame, the
remaining time as the frame's fill fraction times it; a constant-rate extrapolation of the first
20 % of NRRP(t); and the NRRP as two image gauges calibrated on training cases read it: from the
frame's fill level, and from each species' visible fill."""
from __future__ import annotations

import json
import math

import numpy as np

from ..rigs.table1 import TABLE1, row_from_json, solid_volume, species_counts
from .store import species_masks


def case_mass_and_size(attrs: dict) -> tuple[float, float, float]:
    """(total mass kg, mean diameter m, solid density) of a stored Table 1 case from its attributes,
    or of a hopper drawn like them from the row stored with it (pydem images hoppers)."""
    row = row_from_json(json.loads(attrs["row"])) if "row" in attrs else TABLE1[attrs["case"]]
    phi, dd, rho = row[3], row[9], row[10]
    return rho * solid_volume(row), (phi * dd[0] + (1.0 - phi) * dd[1]) / 1000.0, float(rho)


def beverloo_discharge(train: dict[str, float], attrs: dict[str, dict], slot: float = 0.054, length: float = 0.04):
    """Beverloo's slot law W = C rho sqrt(g) L (b - k d)^(3/2) with the solid density (the packing
    fraction goes into C), C and k fitted on the training cases' mean flow rates M / t_dis (least
    squares in W^(2/3), a grid over k); returns (C, k, predict(case attrs) -> discharge time)."""
    rows = [(case_mass_and_size(attrs[c]), t) for c, t in train.items()]
    best = None
    for k in np.linspace(0.0, 3.0, 301):
        feats = np.array([rho * math.sqrt(9.81) * length * max(slot - k * d, 1e-6) ** 1.5 for (m, d, rho), _ in rows])
        w = np.array([m / t for (m, d, rho), t in rows])
        c = float(feats @ w / (feats @ feats))
        err = float(np.sum((w ** (2 / 3) - (c * feats) ** (2 / 3)) ** 2))
        if best is None or err < best[0]:
            best = (err, c, float(k))
    _, c, k = best

    def discharge_time(a: dict) -> float:
        m, d, rho = case_mass_and_size(a)
        return m / (c * rho * math.sqrt(9.81) * length * max(slot - k * d, 1e-6) ** 1.5)
    return c, k, discharge_time


def fill_fraction(x: np.ndarray, first: np.ndarray) -> np.ndarray:
    """Each frame's particle pixels (darker than the background) over those of its case's first
    frame: an image-only estimate of the NRRP."""
    dark = lambda f: np.sum(f < 0.9 * np.median(f), axis=(-2, -1)).reshape(len(f))  # noqa: E731
    return dark(x) / max(float(dark(first[None])[0]), 1.0)


def fill_level_nrrp(fill_train: np.ndarray, nrrp_train: np.ndarray, fill: np.ndarray, degree: int = 3) -> np.ndarray:
    """The NRRP a fill-level gauge reads: a polynomial (degree 3) of the frame's fill fraction
    fitted to training cases' whole discharges, clipped to [0, 1] — what the image's fill level
    alone carries about the count that remains, once calibrated on other hoppers."""
    coeffs = np.polyfit(np.asarray(fill_train, float), np.asarray(nrrp_train, float), degree)
    return np.clip(np.polyval(coeffs, np.asarray(fill, float)), 0.0, 1.0)


def fines_count_share(case: str, row: tuple | None = None) -> float:
    """The fine spheres' share of a Table 1 case's count (its fine volume fraction and two sizes),
    or of a hopper given by its Table 1-style row."""
    n, _nu, _e, phi, *_, dd, _rho = row if row is not None else TABLE1[case]
    nf, nc = species_counts(n, dd[0], dd[1], phi)
    return nf / (nf + nc)


def species_fill(frames: np.ndarray) -> np.ndarray:
    """(n, H, W) uint8 grey frames of one case -> (n, 2): the pixels only fine spheres, and only
    coarse ones, can show (pydem.frames.species_masks), each over its case's first frame's —
    how much of each species the front view still shows."""
    counts = species_masks(frames).sum(axis=(-2, -1))
    return counts / np.maximum(counts[:1], 1.0)


def species_design(fill: np.ndarray, fines_share: float, degree: int = 3) -> np.ndarray:
    """The species gauge's regressors: w F^i and (1 - w) K^i for i = 1..degree, F and K the
    species' fill (species_fill), w the fines' share of the count: the count that remains is the
    fines' share times the share of fines left plus the coarse's, each read from its own fill."""
    f, k = np.asarray(fill, float).T
    return np.column_stack([fines_share * f ** i for i in range(1, degree + 1)]
                           + [(1.0 - fines_share) * k ** i for i in range(1, degree + 1)])


def species_gauge_nrrp(design_train: np.ndarray, nrrp_train: np.ndarray, design: np.ndarray) -> np.ndarray:
    """The NRRP a species gauge reads: least squares of the count on species_design's regressors
    over training cases' whole discharges, clipped to [0, 1]."""
    beta = np.linalg.lstsq(np.asarray(design_train, float), np.asarray(nrrp_train, float), rcond=None)[0]
    return np.clip(np.asarray(design, float) @ beta, 0.0, 1.0)


def constant_rate_nrrp(t: np.ndarray, nrrp: np.ndarray, fraction: float = 0.2) -> np.ndarray:
    """NRRP(t) extrapolated at the constant rate of a straight line through the first `fraction`
    of the (time-ordered) series, clipped to [0, 1]."""
    k = max(2, int(round(fraction * len(t))))
    slope, icpt = np.polyfit(t[:k], nrrp[:k], 1)
    return np.clip(icpt + slope * t, 0.0, 1.0)
