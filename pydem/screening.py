"""Native screening (seed 000): a million parameter combinations through the property nets in
libdem; the admissible set is every combination whose predictions all lie within a relative
window of the measured values; then a second stage (the angle-of-repose nets) narrows it."""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from .campaign.design import design_points
from .measurements import Measurement
from .mlp import NativeMLP, screen


@dataclass
class Stage:
    """One screening stage: which nets against which measured values."""
    name: str
    nets: list[NativeMLP]
    measurements: list[Measurement]
    window: float
    keep: np.ndarray | None = None  # over the stage's input rows
    predictions: np.ndarray | None = None
    seconds: float = math.nan
    rows: int = 0


@dataclass
class Screening:
    names: list[str]
    ranges: dict[str, tuple[float, float]]
    points: np.ndarray
    stages: list[Stage] = field(default_factory=list)
    admissible: list[np.ndarray] = field(default_factory=list)  # indices into points after each stage

    def ranges_of(self, idx: np.ndarray) -> dict[str, tuple[float, float]]:
        if len(idx) == 0:
            return {n: (math.nan, math.nan) for n in self.names}
        sub = self.points[idx]
        return {n: (float(sub[:, j].min()), float(sub[:, j].max())) for j, n in enumerate(self.names)}


def combinations(ranges: dict[str, tuple[float, float]], n: int = 2 ** 20, seed: int = 7) -> np.ndarray:
    """n points of a scrambled Sobol set over the box of ranges (2^20 = 1,048,576 by default)."""
    return design_points("sobol", ranges, 0, n, seed)


def run_stage(stage: Stage, x: np.ndarray, threads: int = 0) -> np.ndarray:
    """Evaluates the stage on rows x; returns the boolean keep mask."""
    stage.rows = len(x)
    if not stage.nets:
        stage.keep, stage.predictions, stage.seconds = np.ones(len(x), bool), np.zeros((len(x), 0)), 0.0
        return stage.keep
    t0 = time.perf_counter()
    stage.keep, stage.predictions = screen(stage.nets, [m.value for m in stage.measurements], stage.window, x,
                                           num_threads=threads)
    stage.seconds = time.perf_counter() - t0
    return stage.keep


def misfit(predictions: np.ndarray, measurements: list[Measurement], window: float) -> np.ndarray:
    """Sum of squared standardised residuals per row; the measured uncertainty, or the window
    times the value when none was published."""
    total = np.zeros(len(predictions))
    for k, m in enumerate(measurements):
        u = m.uncertainty if m.uncertainty == m.uncertainty else window * abs(m.value)
        total += ((predictions[:, k] - m.value) / u) ** 2
    return total


def run(names, ranges, stages: list[Stage], n: int = 2 ** 20, seed: int = 7, threads: int = 0) -> Screening:
    s = Screening(list(names), dict(ranges), combinations(ranges, n, seed))
    idx = np.arange(len(s.points))
    for st in stages:
        keep = run_stage(st, s.points[idx], threads)
        idx = idx[keep]
        s.stages.append(st)
        s.admissible.append(idx)
    return s
