"""Static angle of repose (seed 000): a cylinder standing on a rough base disk is filled, lifted
slowly, and the heap left on the disk comes to rest; the angle is fitted to the heap surface.

Estimator (stated with every result): in each of four azimuthal quadrants, the heap surface
h(r) is the highest sphere top in radial bins one diameter wide; a straight line is fitted to
the bins whose height lies between 20 % and 80 % of the heap height (the flank, without the
rounded top and the toe); the angle is atan(-slope). Reported: mean of the quadrants ± their
standard error. Where the surface of a quadrant falls from 80 % to 20 % of the heap height more
steeply than 70 deg, the material stands (a cohesive column) and has no angle of repose: nan,
with the reason in the note. Bulk density: solid fraction of the filled cylinder (three slabs away from the
walls and the free surface) times the solid density, before the lift."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import geometry
from ..domain import Domain
from ..walls import MeshWall
from .checkpoint import Checkpoint, CheckpointStop, signature
from .common import (Frames, Stepper, lattice_fill, make_domain, params_from, size_distribution, stable_dt,
                     translational_energy_per_particle)
from .config import Params, default_threads, knob
from .result import Metric, RigResult, block_average


@dataclass
class AorConfig:
    particles: int = knob(3000, 20, 2_000_000, "", "number of spheres")
    diameter: float = knob(3e-3, 1e-4, 0.1, "m", "mean sphere diameter")
    size_spread: float = knob(0.1, 0.0, 0.5, "", "diameters uniform in d (1 +- spread)")
    psd_sizes: list = knob([], 1e-6, 1.0, "m", "size table: sieve sizes, increasing (replaces size_spread; docs/rigs.md)")
    psd_passing: list = knob([], 0.0, 1.0, "", "size table: cumulative mass fraction passing each size, 0 ... 1")
    cylinder_radius: float = knob(0.025, 1e-3, 1.0, "m", "inner radius of the lifted cylinder")
    base_radius: float = knob(0.07, 1e-3, 5.0, "m", "radius of the base disk the heap forms on")
    base_friction: float = knob(0.9, 0.0, 2.0, "", "sliding friction sphere-base (a rough base)")
    base_rolling_friction: float = knob(0.3, 0.0, 1.0, "", "rolling friction sphere-base")
    lift_speed: float = knob(0.01, 1e-4, 1.0, "m/s", "cylinder lifting speed (slow: at 0.05 m/s the column collapses, docs/rigs.md)")
    rest_energy: float = knob(1e-5, 1e-9, 1.0, "", "at rest when translational kinetic energy per sphere < this x m g d")
    max_time: float = knob(10.0, 0.05, 600.0, "s", "simulated time limit")
    num_threads: int = knob(default_threads(), 1, 256, "", "OpenMP threads, at most (default: OMP_NUM_THREADS, else the cores)")
    frame_interval: float = knob(0.05, 1e-4, 10.0, "s", "time between PNG frames (with --frames)")
    params: Params = field(default_factory=Params)

    @classmethod
    def preset(cls, name: str) -> "AorConfig":
        if name == "tiny":  # seconds: for tests
            return cls(particles=600, cylinder_radius=0.01, base_radius=0.035, lift_speed=0.1, max_time=3.0)
        if name == "default":  # 2-14 min on one core (median ~6 min over the campaign box; 1.8 min at mu 0.5, mu_r 0.3)
            return cls()
        if name == "paper":  # a lab-scale cylinder (50 mm) of 2 mm spheres
            return cls(particles=60000, diameter=2e-3, cylinder_radius=0.025, base_radius=0.1, lift_speed=0.01,
                       max_time=30.0)
        raise ValueError(f"unknown preset {name!r}: tiny, default or paper")


class AngleOfRepose:
    name = "aor"
    protocol = 1  # raised whenever a metric's definition changes (campaigns refuse to mix protocols)

    def __init__(self, config: AorConfig | None = None):
        self.config = config or AorConfig.preset("default")

    def run(self, params=None, seed: int = 0, frames_dir: str | Path | None = None, progress=None,
            vtk_dir: str | Path | None = None, checkpoint: str | Path | None = None, checkpoint_every: float = 600.0,
            stop_at: float | None = None) -> RigResult | None:
        """Fill, settle, lift, come to rest; the angle by the module's estimator.

        checkpoint: a directory where the run saves its state (pydem.rigs.checkpoint) every
        `checkpoint_every` seconds of wall time; given a directory with a checkpoint of the same
        configuration, parameters and seed, the run resumes from it, bitwise. stop_at: save and
        return None at this simulated time (a run split across batch jobs)."""
        c = self.config
        p = params_from(c.params, params)
        ck = Checkpoint(checkpoint, "aor", signature(self, p, seed), checkpoint_every, stop_at) if checkpoint else None
        saved = ck.load() if ck else None
        dmean = c.diameter
        half = c.base_radius + 6 * dmean
        out = Frames(frames_dir, vtk_dir)
        if saved:
            d = Domain.from_snapshot(saved["snapshot"])
            d.num_threads = c.num_threads
            cyl = MeshWall(d, 1)
            s = saved["protocol"]
            out.restore(saved["frames"])
        else:
            d, cyl = self._build(p, seed)
            s = {"phase": 0, "frames": [], "next_frame": 0.0}
        mass = p.density * 4 / 3 * math.pi * (0.5 * dmean) ** 3
        ke_rest = c.rest_energy * mass * 9.81 * dmean
        st = Stepper(d, progress, planned_time=c.max_time)
        if saved:
            st.restore(saved["stepper"])
        if ck:
            st.attach_checkpoint(ck, lambda: {"protocol": s, "frames": out.state()})
        resumed_at = d.time if saved else None

        def each():
            x = d.positions
            off = (x[:, 2] < -dmean) | (np.hypot(x[:, 0], x[:, 1]) > c.base_radius + dmean)
            lost = d.ids[off]  # rolled off the base disk: gone, as in the lab
            if len(lost):
                d.remove_particles(lost)
            ke = translational_energy_per_particle(d, p.density)
            st.record(time=d.time, kinetic_energy=ke, cylinder_z=cyl.pose[0][2], particles=len(d))
            if out.active and d.time >= s["next_frame"]:
                s["frames"].append(out.write(d, f"aor_{len(s['frames']):04d}.png",
                                             window=((-half, half), (-0.1 * half, 0.995 * half))))
                s["next_frame"] += c.frame_interval
            return False

        def at_rest_after(t0: float):
            return lambda: each() or (d.time > t0 and translational_energy_per_particle(d, p.density) < ke_rest)

        try:
            if s["phase"] == 0:  # 1. settle the filled cylinder
                st.advance(0.1, each=each)
                s["phase"] = 1
            if s["phase"] == 1:
                st.advance(c.max_time, each=at_rest_after(0.15))
                s["density"] = list(self._bulk_density(d, p, c.cylinder_radius, dmean))
                # 2. lift until the cylinder's bottom is above the material, then take it away
                s["top"] = float((d.positions[:, 2] + d.radii).max())
                cyl.set_motion(velocity=(0.0, 0.0, c.lift_speed))
                s["phase"] = 2
            if s["phase"] == 2:
                st.advance(c.max_time, each=lambda: each() or cyl.pose[0][2] > s["top"] + dmean)
                cyl.set_motion(velocity=(0.0, 0.0, 0.0))
                s["lift_end"] = d.time
                s["rest_time"] = max(0.0, c.max_time - d.time)
                s["phase"] = 3
            # 3. the heap comes to rest
            at_rest = st.advance(s["rest_time"], each=at_rest_after(s["lift_end"] + 0.1))
        except CheckpointStop:
            return None
        angle, angle_se, n_sectors = heap_angle(d.positions, d.radii, dmean)
        note = f"surface fit, {n_sectors} quadrants"
        standing = standing_quadrants(d.positions, d.radii, dmean)
        if standing:  # no slope at repose to measure; the bulk density (before the lift) stands
            angle, angle_se = math.nan, math.nan
            note = (f"no heap: the material stands after the lift (a face steeper than {STANDING_FACE_DEG:.0f} deg over "
                    f"60 % of the heap height in {standing} of 4 quadrants), so there is no angle of repose")
        res = RigResult("aor")
        res.metrics["angle_of_repose"] = Metric(angle, angle_se, "deg", note)
        res.metrics["bulk_density"] = Metric(*s["density"], "kg/m^3", "filled cylinder, 3 slabs")
        res.series = {k: np.asarray(v) for k, v in st.series.items()}
        res.frames = [f for f in s["frames"] if f]
        res.info = {"particles": c.particles, "particles_on_base": len(d), "steps": st.steps, "dt": d.dt,
                    "simulated_time": d.time, "at_rest": bool(at_rest), "wall_seconds": st.wall_seconds(),
                    "engine_profile": d.profile(), "resumed_at": resumed_at,
                    "seed": seed, "estimator": __doc__.split("Estimator")[1].split("Bulk density")[0].strip()}
        if ck:
            ck.remove()
        return res

    def _build(self, p: Params, seed: int):
        """The domain with the base disk and the filled cylinder: (domain, the cylinder wall)."""
        c = self.config
        rng = np.random.default_rng(seed)
        dmean, rc = c.diameter, c.cylinder_radius
        radii = size_distribution(rng, c.particles, dmean, c.size_spread, c.psd_sizes, c.psd_passing)
        # fill height: the lattice (spacing 1.05 d_max) up to the particle count, inside the cylinder
        spacing = 1.05 * 2 * radii.max()
        inner = rc - 0.55 * spacing
        layer = max(1, int(np.sum(np.hypot(*np.meshgrid(np.arange(-rc, rc, spacing) + 0.5 * spacing,
                                                        np.arange(-rc, rc, spacing) + 0.5 * spacing)) < inner)))
        fill_top = spacing * (math.ceil(c.particles / layer) + 1)
        half = c.base_radius + 6 * dmean
        lo, hi = (-half, -half, -6 * dmean), (half, half, fill_top + 4 * dmean)
        d, mp, mw = make_domain(lo, hi, p, c.num_threads, diameter=dmean)
        d.seed = seed
        mb = d.add_material(p.youngs_modulus, p.poisson_ratio, p.density)
        d.set_pair(mp, mb, p.wall_restitution, c.base_friction, c.base_rolling_friction, p.rolling_model)
        d.add_mesh_wall(geometry.disk(c.base_radius, 0.0, segments=64), material=mb)
        cyl = d.add_mesh_wall(geometry.cylinder(rc, 0.0, fill_top + 2 * dmean, segments=64), material=mw)
        pos = lattice_fill(rng, (-rc, -rc, 0.0), (rc, rc, fill_top), spacing,
                           lambda g: np.hypot(g[:, 0], g[:, 1]) < inner, count=c.particles, jitter=0.02)
        d.add_particles(pos, radii, mp)
        d.dt = stable_dt(d)
        return d, cyl

    @staticmethod
    def _bulk_density(d, p: Params, rc: float, dmean: float) -> tuple[float, float]:
        top = float(d.positions[:, 2].max())
        z0, z1 = 2 * dmean, top - 2 * dmean
        if z1 - z0 < 3 * dmean:
            z0, z1 = 0.5 * dmean, max(top - dmean, 1.5 * dmean)
        edges = np.linspace(z0, z1, 4)
        fr = [d.region_stress("cylinder", centre=(0, 0, 0), axis=2, r_outer=rc - 1.5 * dmean, h_lo=a, h_hi=b)["solid_fraction"]
              for a, b in zip(edges[:-1], edges[1:])]
        mean, se = block_average(fr, 3)
        return p.density * mean, p.density * se


STANDING_FACE_DEG = 70.0  # a flank steeper than this is a standing face, not a slope at repose


def quadrant_profiles(pos: np.ndarray, radii: np.ndarray, bin_width: float):
    """The heap surface in each of four azimuthal quadrants with 10 spheres or more: (bin
    centres, highest sphere top per radial bin; nan where a bin is empty)."""
    r = np.hypot(pos[:, 0], pos[:, 1])
    top = pos[:, 2] + radii
    sector = ((np.arctan2(pos[:, 1], pos[:, 0]) + np.pi) // (np.pi / 2)).astype(int) % 4
    for s in range(4):
        m = sector == s
        if m.sum() < 10:
            continue
        b = (r[m] // bin_width).astype(int)
        h = np.full(b.max() + 1, np.nan)
        np.fmax.at(h, b, top[m])
        yield (np.arange(len(h)) + 0.5) * bin_width, h


def heap_angle(pos: np.ndarray, radii: np.ndarray, bin_width: float) -> tuple[float, float, int]:
    """The module's estimator; returns (mean angle deg, standard error, quadrants used)."""
    angles = []
    for centres, h in quadrant_profiles(pos, radii, bin_width):
        ok = ~np.isnan(h)
        hmax = np.nanmax(h)
        flank = ok & (h > 0.2 * hmax) & (h < 0.8 * hmax)
        if flank.sum() < 3:
            continue
        slope = np.polyfit(centres[flank], h[flank], 1)[0]
        angles.append(math.degrees(math.atan(max(0.0, -slope))))
    if not angles:
        return math.nan, math.nan, 0
    a = np.array(angles)
    se = a.std(ddof=1) / math.sqrt(len(a)) if len(a) > 1 else math.nan
    return float(a.mean()), float(se), len(a)


def standing_quadrants(pos: np.ndarray, radii: np.ndarray, bin_width: float) -> int:
    """Quadrants where the material stands instead of forming a slope: the surface falls from 80 %
    to 20 % of the heap height within less than 0.6 h / tan(STANDING_FACE_DEG) of radius (the
    farthest bins at or above each level), a face steeper than 70 deg over 60 % of the height.
    Why: a cohesive fill can stand as the cylinder's column after the lift with a skirt of fallen
    spheres at its foot; the flank fit then finds the skirt (8.2 deg for run 173 of the default
    diagnosis store, cohesion 9.3e4 J/m^3). A heap at 60 deg falls over 0.35 h: not flagged."""
    n = 0
    for centres, h in quadrant_profiles(pos, radii, bin_width):
        hmax = np.nanmax(h)
        r80, r20 = (centres[np.nan_to_num(h, nan=-np.inf) >= f * hmax].max() for f in (0.8, 0.2))
        n += (r20 - r80) < 0.6 * hmax / math.tan(math.radians(STANDING_FACE_DEG))
    return int(n)
