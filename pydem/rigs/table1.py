"""Seed 001's Table 1: the 25 wedge-hopper cases (five packings x five parameter sets) and the
split of a case's N spheres into fine and coarse ones. Plain data and arithmetic, importable
without pydem's compiled binding (the image networks read it on machines where libdem is not
built)."""
from __future__ import annotations

import math

# seed 001, Table 1: N, nu, E (GPa), fine volume fraction, e_pp, e_wp, mu_pp, mu_wp, mu_r, d (mm), rho
TABLE1 = {
    "A-1": (620, 0.35, 0.01, 0.2, 0.3, 0.1, 0.5, 0.2, 0.08, (6, 9), 2800),
    "A-2": (10180, 0.26, 0.375, 0.5, 0.5, 0.8, 0.6, 0.7, 0.02, (3, 6), 2100),
    "A-3": (5450, 0.42, 0.065, 0.2, 0.4, 0.7, 0.9, 0.2, 0.05, (3, 6), 1800),
    "A-4": (14700, 0.3, 0.01, 0.8, 0.7, 0.3, 0.2, 0.9, 0.07, (3, 9), 2500),
    "A-5": (7900, 0.4, 0.01, 0.4, 0.9, 0.1, 0.7, 0.1, 0.01, (3, 9), 2800),
    "B1-1": (6875, 0.42, 0.01, 0.3, 0.9, 0.9, 0.3, 0.3, 0.06, (3, 6), 1500),
    "B1-2": (7596, 0.33, 0.01, 0.4, 0.4, 0.8, 0.4, 0.2, 0.03, (3, 9), 1500),
    "B1-3": (1239, 0.42, 0.01, 0.4, 0.3, 0.5, 0.2, 0.1, 0.08, (6, 9), 1800),
    "B1-4": (2394, 0.3, 0.375, 0.1, 0.7, 0.1, 0.4, 0.5, 0.08, (3, 9), 2100),
    "B1-5": (8464, 0.4, 0.065, 0.4, 0.5, 0.3, 0.5, 0.9, 0.06, (3, 6), 2800),
    "B2-1": (1239, 0.26, 0.375, 0.4, 0.6, 0.7, 0.5, 0.7, 0.04, (6, 9), 2800),
    "B2-2": (3696, 0.45, 0.01, 0.1, 0.2, 0.2, 0.9, 0.2, 0.09, (3, 6), 2500),
    "B2-3": (8464, 0.35, 0.01, 0.4, 0.8, 0.2, 0.5, 0.8, 0.06, (3, 6), 2100),
    "B2-4": (1094, 0.3, 0.01, 0.3, 0.9, 0.9, 0.1, 0.7, 0.01, (6, 9), 2100),
    "B2-5": (9330, 0.4, 0.2, 0.5, 0.1, 0.1, 0.8, 0.2, 0.02, (3, 9), 1800),
    "B3-1": (5285, 0.26, 0.01, 0.2, 0.6, 0.3, 0.3, 0.2, 0.01, (3, 6), 2500),
    "B3-2": (4128, 0.4, 0.2, 0.2, 0.7, 0.1, 0.3, 0.1, 0.07, (3, 9), 2800),
    "B3-3": (950, 0.4, 0.375, 0.2, 0.3, 0.1, 0.2, 0.1, 0.09, (6, 9), 2100),
    "B3-4": (5862, 0.35, 0.065, 0.3, 0.9, 0.8, 0.6, 0.6, 0.04, (3, 9), 2100),
    "B3-5": (5170, 0.35, 0.2, 0.2, 0.8, 0.9, 0.8, 0.9, 0.02, (3, 6), 2800),
    "B4-1": (6874, 0.35, 0.2, 0.3, 0.8, 0.4, 0.9, 0.3, 0.02, (3, 6), 1500),
    "B4-2": (9330, 0.33, 0.01, 0.5, 0.6, 0.1, 0.6, 0.8, 0.04, (3, 9), 2500),
    "B4-3": (805, 0.2, 0.375, 0.1, 0.1, 0.9, 0.1, 0.1, 0.05, (6, 9), 2100),
    "B4-4": (1094, 0.2, 0.065, 0.3, 0.5, 0.5, 0.2, 0.8, 0.09, (6, 9), 2100),
    "B4-5": (4128, 0.2, 0.375, 0.2, 0.9, 0.2, 0.3, 0.9, 0.08, (3, 9), 2100),
}


def species_counts(n: int, d_small: float, d_large: float, fine_fraction: float) -> tuple[int, int]:
    """(fine, coarse) numbers whose fine volume fraction is closest to fine_fraction."""
    ratio = (d_large / d_small) ** 3  # a coarse sphere holds `ratio` fine volumes
    n_fine = round(n * fine_fraction * ratio / (fine_fraction * ratio + (1.0 - fine_fraction)))
    return int(n_fine), int(n - n_fine)


def draw_like_table1(packing: str, hoppers: int, seed: int, volume_scale: float = 1.0) -> dict[str, tuple]:
    """{name: row} of `hoppers` hoppers drawn like Table 1's (named <packing>-x01 ...): each
    parameter from the values its column holds over the 25 cases, independently, and the sphere
    count from the drawn sizes and fine fraction and the solid volume of a Table 1 case drawn at
    random (the seed keeps the bed's volume roughly fixed), times volume_scale (1: Table 1's beds;
    smaller for a quick look). The first k hoppers are the same whatever `hoppers` is."""
    import numpy as np
    rows = list(TABLE1.values())
    rng = np.random.default_rng(seed)
    pick = lambda col: rows[rng.integers(len(rows))][col]  # noqa: E731
    out = {}
    for i in range(hoppers):
        nu, e, phi, epp, ewp, mupp, muwp, mur, dd, rho = (pick(c) for c in range(1, 11))
        like = rows[rng.integers(len(rows))]  # the bed's solid volume of a Table 1 case
        volume = solid_volume(like) * volume_scale
        vs, vl = (math.pi / 6 * (d / 1000.0) ** 3 for d in dd)
        n = max(2, int(round(volume * phi / vs + volume * (1 - phi) / vl)))
        out[f"{packing}-x{i + 1:02d}"] = (n, nu, e, phi, epp, ewp, mupp, muwp, mur, dd, rho)
    return out


def row_as_json(row: tuple) -> list:
    """A Table 1-style row as JSON holds it (the sizes pair as a list): how a hopper drawn like
    Table 1's is stored with its frames (pydem images hoppers)."""
    return [*row[:9], list(row[9]), row[10]]


def row_from_json(r: list) -> tuple:
    """row_as_json's inverse."""
    return tuple(r[:9]) + (tuple(r[9]),) + tuple(r[10:])


def solid_volume(row: tuple) -> float:
    """m^3 of spheres in a Table 1-style row."""
    n, phi, dd = row[0], row[3], row[9]
    nf, nc = species_counts(n, dd[0], dd[1], phi)
    return math.pi / 6 * (nf * (dd[0] / 1000.0) ** 3 + nc * (dd[1] / 1000.0) ** 3)
