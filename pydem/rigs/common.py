"""What every rig does: a domain from the micro parameters, particles poured into a region,
stepping in chunks with progress and rest detection, frames."""
from __future__ import annotations

import dataclasses
import time
from pathlib import Path
from typing import Callable

import numpy as np

from ..domain import Domain
from ..vtk import VtkSeries
from .checkpoint import CheckpointStop
from .config import ConfigError, Params
from .frames import crop_grey

Progress = Callable[[float, float, dict], None]  # (simulated time, planned time, info)


def params_from(base: Params, params) -> Params:
    """base with the fields given in params (a Params, a dict, or None) replaced."""
    if params is None:
        return base
    if isinstance(params, Params):
        return params
    p = dataclasses.replace(base, effects={k: dict(v) for k, v in base.effects.items()})
    for k, v in dict(params).items():
        if k == "effects":
            for name, values in v.items():
                p.effects.setdefault(name, {}).update(values)
        elif not hasattr(p, k):
            raise KeyError(f"unknown parameter {k!r}")
        else:
            setattr(p, k, v)
    return p


def make_domain(lo, hi, params: Params, num_threads: int = 2, dt: float = 1e-5, skin: float | None = None,
                diameter: float = 1e-3, max_overlap_ratio: float = 0.3):
    """A domain with a particle material and a wall material and their pair constants;
    the effects act between particles."""
    d = Domain(lo=lo, hi=hi, dt=dt, num_threads=num_threads, skin=skin if skin is not None else 0.1 * diameter,
               max_overlap_ratio=max_overlap_ratio)
    mp = d.add_material(params.youngs_modulus, params.poisson_ratio, params.density)
    mw = d.add_material(params.youngs_modulus, params.poisson_ratio, params.density)
    d.set_pair(mp, mp, params.restitution, params.friction, params.rolling_friction, params.rolling_model)
    d.set_pair(mp, mw, params.wall_restitution, params.wall_friction, params.wall_rolling_friction, params.rolling_model)
    for name, values in params.effects.items():
        d.set_effect(mp, mp, name, **values)
    return d, mp, mw


def stable_dt(d: Domain, impact_speed: float = 0.5, fraction: float = 0.2, steps_per_contact: int = 25) -> float:
    """min(fraction x Rayleigh time, Hertz contact time at impact_speed / steps_per_contact):
    20 % of the Rayleigh time is the usual stability bound, 25 steps resolve a collision."""
    s = d.settings
    info = d.timestep_info()
    tc = info["hertz_contact_time"] * (s["reference_velocity"] / impact_speed) ** 0.2  # t_c ~ v^(-1/5)
    return min(fraction * info["rayleigh_time"], tc / steps_per_contact)


def lattice_fill(rng: np.random.Generator, lo, hi, spacing: float, inside: Callable[[np.ndarray], np.ndarray],
                 count: int | None = None, jitter: float = 0.05) -> np.ndarray:
    """Jittered cubic lattice points in [lo, hi] kept by `inside`, lowest first; the first
    `count` of them (all when None)."""
    axes = [np.arange(lo[a] + 0.5 * spacing, hi[a] - 0.49 * spacing, spacing) for a in range(3)]
    g = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    g = g[np.lexsort((g[:, 1], g[:, 0], g[:, 2]))]
    g = g[inside(g)]
    g = g + rng.uniform(-jitter, jitter, g.shape) * spacing
    if count is not None:
        if len(g) < count:
            raise ValueError(f"only {len(g)} places for {count} particles: enlarge the fill region")
        g = g[:count]
    return g


def size_distribution(rng: np.random.Generator, n: int, diameter: float, spread: float, sizes=(), passing=()) -> np.ndarray:
    """Radii: diameters uniform in diameter (1 +- spread), or, given a size table (sieve sizes
    and the cumulative mass fraction passing each, linear between them), drawn from it."""
    if len(sizes) == 0 and len(passing) == 0:
        return 0.5 * diameter * (1.0 + spread * rng.uniform(-1.0, 1.0, n))
    return 0.5 * diameters_from_table(rng, n, sizes, passing)


def diameters_from_table(rng: np.random.Generator, n: int, sizes, passing) -> np.ndarray:
    """n diameters whose *mass* distribution is the table's: cumulative mass fraction passing
    P(d) linear between the sieve sizes (mass uniform in d within each cut). A cut's share of
    the spheres is its mass share times the mean of d^-3 over it (number ~ mass / d^3), and
    within a cut d is drawn with density ~ d^-3 (inverse CDF)."""
    d, cum = np.asarray(sizes, float), np.asarray(passing, float)
    if d.size != cum.size or d.size < 2:
        raise ConfigError(f"psd_sizes and psd_passing need the same number of entries, at least 2 (got {d.size}, {cum.size})")
    if not (np.all(d > 0) and np.all(np.diff(d) > 0)):
        raise ConfigError(f"psd_sizes must be positive and increasing, got {list(d)}")
    if not (np.all(np.diff(cum) >= 0) and cum[0] == 0.0 and cum[-1] == 1.0):
        raise ConfigError(f"psd_passing must rise from 0 (at the smallest size) to 1 (at the largest), got {list(cum)}")
    lo, hi, mass = d[:-1], d[1:], np.diff(cum)
    inv2 = lo ** -2 - hi ** -2
    weight = mass / (hi - lo) * 0.5 * inv2  # number of spheres per cut, up to a constant
    cut = rng.choice(len(mass), size=n, p=weight / weight.sum())
    u = rng.uniform(0.0, 1.0, n)
    return (lo[cut] ** -2 - u * inv2[cut]) ** -0.5


class Stepper:
    """Steps a domain in chunks, keeping time series, frames and progress reports; with a
    checkpoint (attach_checkpoint) it saves right after a chunk's steps, before the chunk's
    callback, and a restored stepper resumes the advance it was saved in."""

    def __init__(self, d: Domain, progress: Progress | None = None, planned_time: float = 0.0):
        self.d, self.progress, self.planned = d, progress, planned_time
        self.t_wall0 = time.perf_counter()
        self.wall_before = 0.0  # wall seconds of the run before its last restart
        self.steps = 0
        self.series: dict[str, list] = {}
        self.ck = None            # (Checkpoint, state function) while checkpointing
        self.resume_at = None     # [done, total, n_chunk] of the advance a checkpoint was saved in

    def record(self, **values):
        for k, v in values.items():
            self.series.setdefault(k, []).append(v)

    def attach_checkpoint(self, ck, rig_state: Callable[[], dict]):
        """Save to ck when it is due; rig_state() gives what the rig keeps beside the snapshot
        and the stepper's own state (its protocol's variables, its outputs)."""
        self.ck = (ck, rig_state)

    def state(self) -> dict:
        return {"series": self.series, "steps": self.steps, "wall": self.wall_seconds()}

    def restore(self, state: dict):
        self.series = {k: list(v) for k, v in state["series"].items()}
        self.steps, self.wall_before = state["steps"], state["wall"]
        self.resume_at = state.get("advance")

    def advance(self, seconds: float, chunk: float = 2e-3, each: Callable[[], bool] | None = None) -> bool:
        """Steps `seconds` of simulated time in chunks; `each` is called after every chunk and
        may stop early by returning True (returns True then)."""
        n_chunk = max(1, int(round(chunk / self.d.dt)))
        total = int(round(seconds / self.d.dt))
        done, resumed = 0, False
        if self.resume_at is not None:  # the advance a checkpoint was saved in: its chunk's callback is next
            done, total, n_chunk = self.resume_at
            self.resume_at, resumed = None, True
        while done < total:
            if resumed:
                resumed = False
            else:
                k = min(n_chunk, total - done)
                self.d.step(k)
                done += k
                self.steps += k
                if self.ck is not None and self.ck[0].due(self.d.time):
                    self._save(done, total, n_chunk)
            if self.progress is not None:
                self.progress(self.d.time, self.planned, {"steps": self.steps, "particles": len(self.d), "threads": self.d.num_threads,
                                                          "wall": self.wall_seconds()})
            if each is not None and each():
                return True
        return False

    def _save(self, done: int, total: int, n_chunk: int):
        ck, rig_state = self.ck
        ck.save(self.d, dict(rig_state(), stepper=dict(self.state(), advance=[done, total, n_chunk])))
        if ck.stopping(self.d.time):
            raise CheckpointStop(f"checkpoint at t = {self.d.time:.4g} s in {ck.dir}")

    def wall_seconds(self) -> float:
        return self.wall_before + time.perf_counter() - self.t_wall0


def translational_energy_per_particle(d: Domain, density: float) -> float:
    """Mean translational kinetic energy (J). Spin is left out on purpose: the contact model
    has no twisting resistance, so a sphere may keep spinning about its contact normal in a
    heap that is otherwise at rest."""
    n = len(d)
    if not n:
        return 0.0
    m = density * 4.0 / 3.0 * np.pi * d.radii ** 3
    return float(0.5 * np.sum(m * np.sum(d.velocities ** 2, axis=1)) / n)


class Frames:
    """Where a rig's frames go at its frame times: PNG images (`frames_dir`) and/or a VTK time
    series for ParaView (`vtk_dir`: particles and mesh walls, pydem.vtk)."""

    def __init__(self, frames_dir: str | Path | None = None, vtk_dir: str | Path | None = None, images: bool = False):
        self.dir = Path(frames_dir) if frames_dir else None
        self.vtk = VtkSeries(vtk_dir) if vtk_dir else None
        self.images = [] if images else None  # centre-cropped grey frames kept in memory (pydem.rigs.frames)

    def state(self) -> dict:
        """What a checkpoint keeps of the output (the VTK collections written so far)."""
        return {"vtk": self.vtk.entries if self.vtk is not None else {}}

    def restore(self, state: dict):
        if self.vtk is not None:
            self.vtk.entries = {k: [tuple(e) for e in v] for k, v in state.get("vtk", {}).items()}

    @property
    def active(self) -> bool:
        return self.dir is not None or self.vtk is not None or self.images is not None

    def write(self, d: Domain, name: str, **render) -> str | None:
        """The PNG's path (None without a frames directory)."""
        if self.vtk is not None:
            self.vtk.write(d)
        if self.images is not None:
            self.images.append(crop_grey(d.render(**render)))
        if self.dir is None:
            return None
        self.dir.mkdir(parents=True, exist_ok=True)
        path = self.dir / name
        d.render_png(path, **render)
        return str(path)