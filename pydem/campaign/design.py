"""Space-filling designs over a box of parameter ranges, deterministic per (kind, seed) and
extendable: point i never changes when the design grows.

- sobol: Owen-scrambled Sobol sequence (scipy), seeded; the first n points of a longer sequence
  are the n points of a shorter one, so growing a campaign keeps every finished run.
- lhs: Latin hypercube in batches; batch k (seed + k) covers the points added by the k-th
  growth, each batch is a Latin hypercube of its own size.

A design may hold some parameters at a neutral value (`at_neutral`): then point i varies the
others and at most one of those, the (i mod (n + 1))-th (0: none), so the points lie on the
base model and its one-effect axes, where a diagnosis fits (each point's choice depends on i
alone: growing keeps it)."""
from __future__ import annotations

import warnings

import numpy as np


def unit_points(kind: str, dim: int, start: int, stop: int, seed: int, batches: list[int] | None = None) -> np.ndarray:
    """Points start..stop-1 of the design in the unit cube, shape (stop - start, dim)."""
    if stop <= start:
        return np.zeros((0, dim))
    if kind == "sobol":
        from scipy.stats import qmc
        with warnings.catch_warnings():  # balance warnings for n not a power of two: harmless here
            warnings.simplefilter("ignore")
            pts = qmc.Sobol(d=dim, scramble=True, seed=seed).random(stop)
        return pts[start:stop]
    if kind == "lhs":
        from scipy.stats import qmc
        edges = np.cumsum([0] + list(batches or [stop]))
        if edges[-1] < stop:
            raise ValueError(f"lhs design: batches {batches} cover {edges[-1]} points, asked for {stop}")
        pts = np.vstack([qmc.LatinHypercube(d=dim, seed=seed + k).random(int(n)) for k, n in enumerate(np.diff(edges)) if n > 0])
        return pts[start:stop]
    raise ValueError(f"unknown design {kind!r}: sobol or lhs")


def design_points(kind: str, ranges: dict[str, tuple[float, float]], start: int, stop: int, seed: int,
                  batches: list[int] | None = None, log: tuple[str, ...] = ()) -> np.ndarray:
    """Points start..stop-1 scaled to the ranges (columns in the ranges' order); names listed
    in `log` are sampled uniformly in log space."""
    u = unit_points(kind, len(ranges), start, stop, seed, batches)
    out = np.empty_like(u)
    for j, (name, (lo, hi)) in enumerate(ranges.items()):
        if name in log:
            out[:, j] = np.exp(np.log(lo) + u[:, j] * (np.log(hi) - np.log(lo)))
        else:
            out[:, j] = lo + u[:, j] * (hi - lo)
    return out


def at_neutral(points: np.ndarray, names: list[str], neutral: dict[str, float | str], start: int) -> np.ndarray:
    """Points start.. of a design (columns `names`) with the `neutral` parameters held at their
    neutral values except one per point: point i leaves the k-th of them free, k = i mod (n + 1)
    (k = 0: all held). A neutral value is a number or the name of another column it follows
    (wall friction neutral = the particles' friction)."""
    out = points.copy()
    keys = list(neutral)
    for r in range(len(out)):
        free = (start + r) % (len(keys) + 1) - 1
        for k, name in enumerate(keys):
            if k != free:
                v = neutral[name]
                out[r, names.index(name)] = out[r, names.index(v)] if isinstance(v, str) else float(v)
    return out
