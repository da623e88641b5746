"""Seed 001's frames as a network sees them, and how the study splits and scores them.

- `load_frames`: every stored frame of the chosen cases as float32 (n, 1, size, size) in [0, 1]
  (area-averaged from the stored 224 x 224 crop when size < 224), or its two species as two
  channels (`species_frames`), with its case, time, remaining discharge time and NRRP;
- splits: `random_split` (seed 001's 60/20/20 over frames: neighbouring frames of one run are
  near-duplicates, so it flatters) and `case_split` (whole cases held out: what a user predicting
  a new hopper gets);
- `scores`: MAE, RMSE, R^2 (seed 001, Eqs. 7-9) and the average relative error (Eq. 10, away
  from the empty end)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import torch

from .store import FrameStore, species_masks


@dataclass
class Frames:
    x: np.ndarray          # (n, channels, size, size) float32 in [0, 1]
    case: np.ndarray       # (n,) case names
    time: np.ndarray       # s since the gate opened
    remaining: np.ndarray  # remaining discharge time (s)
    nrrp: np.ndarray
    discharge: dict        # case -> discharge time (s)
    attrs: dict            # case -> stored attributes

    def take(self, idx) -> "Frames":
        return Frames(self.x[idx], self.case[idx], self.time[idx], self.remaining[idx], self.nrrp[idx],
                      self.discharge, self.attrs)


def concat(parts: list[Frames]) -> Frames:
    """The frames of several loads as one (each case's frames stay in time order)."""
    return Frames(*(np.concatenate([getattr(f, k) for f in parts]) for k in ("x", "case", "time", "remaining", "nrrp")),
                  {c: v for f in parts for c, v in f.discharge.items()}, {c: v for f in parts for c, v in f.attrs.items()})


def shrink(frames: np.ndarray, size: int) -> np.ndarray:
    """uint8 (n, H, W) -> float32 (n, 1, size, size) in [0, 1], area-averaged."""
    x = torch.from_numpy(np.asarray(frames, np.float32) / 255.0)[:, None]
    if size != x.shape[-1]:
        x = torch.nn.functional.adaptive_avg_pool2d(x, size)
    return x.numpy()


def species_frames(frames: np.ndarray, size: int) -> np.ndarray:
    """uint8 (n, H, W) grey frames -> float32 (n, 2, size, size): one frame per species (fine,
    coarse; pydem.frames.species_masks), each in the grey frames' convention — 0 where the
    species covers the pixel, 1 where it does not — area-averaged to size."""
    out = []
    for i in range(0, len(frames), 256):
        m = torch.from_numpy(species_masks(frames[i:i + 256]).astype(np.float32))
        if size != m.shape[-1]:
            m = torch.nn.functional.adaptive_avg_pool2d(m, size)
        out.append(1.0 - m.numpy())
    return np.concatenate(out) if out else np.zeros((0, 2, size, size), np.float32)


INPUTS = {"grey": shrink, "species": species_frames}  # what a network sees of a stored frame


def load_frames(store_path, cases=None, size: int = 224, every: int = 1, inputs: str = "grey") -> Frames:
    """Every `every`-th frame of each case (all stored cases when cases is None), in time order,
    as `inputs` gives it: the grey frame (1 channel) or its two species (INPUTS)."""
    if inputs not in INPUTS:
        raise ValueError(f"inputs: one of {sorted(INPUTS)}, got {inputs!r}")
    store = FrameStore(store_path)
    names = cases or store.cases()
    xs, cs, ts, rs, ns, dis, attrs = [], [], [], [], [], {}, {}
    for c in names:
        d = store.read_case(c)
        sl = slice(None, None, every)
        xs.append(INPUTS[inputs](d["frames"][sl], size))
        cs += [c] * len(xs[-1])
        ts.append(d["time"][sl]), rs.append(d["remaining_time"][sl]), ns.append(d["nrrp"][sl])
        dis[c] = float(d["discharge_time"])
        attrs[c] = {"case": c} | {k: v for k, v in d.items() if k not in ("frames", "time", "remaining_time", "nrrp")}
    if not xs:
        raise ValueError(f"{store_path}: no frames of the cases {names}")
    return Frames(np.concatenate(xs), np.array(cs), np.concatenate(ts), np.concatenate(rs), np.concatenate(ns), dis, attrs)


def random_split(n: int, seed: int = 0, fractions=(0.6, 0.2, 0.2)) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(train, validation, test) frame indices, seed 001's random 60/20/20."""
    order = np.random.default_rng(seed).permutation(n)
    a, b = int(round(fractions[0] * n)), int(round((fractions[0] + fractions[1]) * n))
    return np.sort(order[:a]), np.sort(order[a:b]), np.sort(order[b:])


def case_split(case: np.ndarray, test_cases, validation_cases) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(train, validation, test) indices with whole cases held out."""
    test, val = np.isin(case, list(test_cases)), np.isin(case, list(validation_cases))
    if (test & val).any():
        raise ValueError("a case cannot be both a validation and a test case")
    return np.flatnonzero(~test & ~val), np.flatnonzero(val), np.flatnonzero(test)


def scores(y: np.ndarray, pred: np.ndarray, floor: float = 0.1) -> dict:
    """MAE, RMSE, R^2 (seed 001 Eqs. 7-9) and the average relative error |y - pred| / y (Eq. 10)
    over the rows with y >= floor x max(y): the remaining time and the NRRP both fall to zero at
    the end of a discharge, where a relative error has no bound and would drown the rest."""
    y, pred = np.asarray(y, float), np.asarray(pred, float)
    if len(y) == 0:
        return {"mae": math.nan, "rmse": math.nan, "r2": math.nan, "relative_error": math.nan, "n": 0}
    err = pred - y
    rel = y >= floor * y.max()
    rel &= y > 0
    return {"mae": float(np.mean(np.abs(err))), "rmse": float(np.sqrt(np.mean(err ** 2))),
            "r2": float(1.0 - np.sum(err ** 2) / np.sum((y - y.mean()) ** 2)) if len(y) > 1 else math.nan,
            "relative_error": float(np.mean(np.abs(err[rel]) / y[rel])) if rel.any() else math.nan, "n": int(len(y))}
