"""Schulze ring shear tester (seed 000): an annular trough with radial bars turns under a lid
with bars; the lid is held against rotation and servo-loaded to a normal stress; the shear
stress comes from the lid torque about the axis, tau = T / integral(r dA) = 3 T / (2 pi
(Ro^3 - Ri^3)), the normal stress from the lid force over its area.

Procedure (DESIGN section 6): pre-shear at sigma_pre to steady flow; then for each shear point
(40/60/80 % of sigma_pre): a fresh pre-shear, stop, reduce the load to sigma_sh, shear again
until failure -> tau_sh (the peak). With `shear_repeats` > 1 each point is measured that many
times (pre-shear + shear to failure each time) and reported as the mean with its standard
error: in a cell of a few thousand spheres one peak is a noisy sample of the yield stress.
tau_pre: the mean over the steady halves of all pre-shears.
Lid stresses are time averages of the wall force between samples (libdem's mean wall force),
not snapshots. Outputs mu_ie-ps = tau_pre / sigma_pre,
mu_ie-s = tau_sh / sigma_sh per point, the yield locus (least-squares line through the shear
points: slope and intercept), bulk density under the lid, and the inertial number reached,
I = gamma_dot d / sqrt(sigma_pre / rho_s) with gamma_dot = (omega R_mean) / bed height.
Steady flow: the mean shear stress of the last two quarters of a pre-shear differ by less
than `steady_tolerance` (else it continues, up to `max_preshear`)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import geometry
from ..domain import Domain
from ..walls import MeshWall
from .checkpoint import Checkpoint, signature
from .common import Frames, Stepper, lattice_fill, make_domain, params_from, size_distribution, stable_dt
from .config import Params, default_threads, knob
from . import yield_locus as locus
from .result import Metric, RigResult, block_average


@dataclass
class RingShearConfig:
    particles: int = knob(4000, 50, 2_000_000, "", "number of spheres")
    diameter: float = knob(3e-3, 1e-4, 0.1, "m", "mean sphere diameter")
    size_spread: float = knob(0.1, 0.0, 0.5, "", "diameters uniform in d (1 +- spread)")
    psd_sizes: list = knob([], 1e-6, 1.0, "m", "size table: sieve sizes, increasing (replaces size_spread; docs/rigs.md)")
    psd_passing: list = knob([], 0.0, 1.0, "", "size table: cumulative mass fraction passing each size, 0 ... 1")
    inner_radius: float = knob(0.025, 1e-3, 2.0, "m", "trough inner radius Ri")
    outer_radius: float = knob(0.052, 1e-3, 2.0, "m", "trough outer radius Ro (width >= ~10 d)")
    bars: int = knob(12, 0, 200, "", "radial bars on the trough floor and under the lid (each)")
    bar_height: float = knob(2e-3, 0.0, 0.1, "m", "height of the bars (the bed must stay well above 2 bar heights)")
    preshear_stress: float = knob(2000.0, 10.0, 1e7, "Pa", "pre-shear normal stress sigma_pre")
    shear_points: list = knob([0.4, 0.6, 0.8], 0.05, 1.0, "", "shear normal stresses as fractions of sigma_pre")
    shear_repeats: int = knob(1, 1, 100, "", "pre-shear + shear to failure cycles per shear point (averaged)")
    shear_speed: float = knob(0.03, 1e-4, 1.0, "m/s", "trough speed at the mean radius")
    preshear_displacement: float = knob(5e-3, 1e-4, 1.0, "m", "shear displacement of each pre-shear (at R_mean)")
    first_preshear_displacement: float = knob(1.2e-2, 1e-4, 1.0, "m", "the first pre-shear (from the filled state)")
    max_preshear: float = knob(3e-2, 1e-4, 1.0, "m", "longest pre-shear when flow is not yet steady")
    shear_displacement: float = knob(5e-3, 1e-4, 1.0, "m", "longest shear to failure")
    steady_tolerance: float = knob(0.05, 1e-4, 1.0, "", "steady flow: relative change between the last quarters")
    servo_speed: float = knob(0.02, 1e-5, 1.0, "m/s", "lid servo speed limit")
    max_overlap_ratio: float = knob(0.9, 0.05, 0.9, "", "overlap / smaller radius that stops the run as a blow-up (see below)")
    num_threads: int = knob(default_threads(), 1, 256, "", "OpenMP threads, at most (default: OMP_NUM_THREADS, else the cores)")
    frame_interval: float = knob(0.1, 1e-4, 10.0, "s", "time between frames (with --frames)")
    params: Params = field(default_factory=Params)

    @classmethod
    def preset(cls, name: str) -> "RingShearConfig":
        if name == "tiny":  # tens of seconds: for tests
            return cls(particles=1200, diameter=3e-3, inner_radius=0.02, outer_radius=0.036, bars=8, bar_height=1.5e-3,
                       shear_points=[0.5], preshear_displacement=4e-3, first_preshear_displacement=6e-3,
                       max_preshear=8e-3, shear_displacement=3e-3, shear_speed=0.05)
        if name == "cell":  # ~2 minutes on one core: the smallest cell found that feels mu_s (campaigns)
            # 8 d wide, ~7 d deep, bars of 1 d: in the tiny cell the shear localises under the lid
            # and mu_ie-ps even falls with mu_s; here it rises (0.536 -> 0.594 for mu_s 0.2 -> 0.8 at
            # mu_r 0.1, seed sd 0.017; studies/results/ring_shear_design.txt). First pre-shear 20 mm.
            # The peak of one shear to failure scatters by ~0.04 (sd) between repeats in this small
            # cell, as much as mu_s moves it: six repeats, each after a 3 mm (1 d) pre-shear that
            # restores steady flow, average it to ~0.015 (studies/results/ring_shear_design.txt).
            return cls(particles=4300, diameter=3e-3, inner_radius=0.02, outer_radius=0.044, bars=12, bar_height=3e-3,
                       shear_points=[0.5], shear_repeats=6, preshear_displacement=3e-3, first_preshear_displacement=2e-2,
                       max_preshear=3e-2, shear_displacement=3e-3, shear_speed=0.05)
        if name == "default":  # <= 3 minutes on 2 cores
            return cls()
        if name == "paper":  # a lab Schulze cell of 2 mm spheres (seed 000: silibeads)
            return cls(particles=60000, diameter=2e-3, inner_radius=0.05, outer_radius=0.1, bars=18,
                       bar_height=4e-3, shear_speed=0.01)
        raise ValueError(f"unknown preset {name!r}: tiny, cell, default or paper")


class RingShear:
    name = "ring-shear"
    # raised whenever a metric's definition changes (campaigns refuse to mix protocols):
    # 1: lid snapshots, tau_pre from the first pre-shear; 2: lid time averages, tau_pre over all pre-shears;
    # 3: repeated shear points (mean and standard error of the repeats; the cell preset repeats 6 times)
    protocol = 3

    def __init__(self, config: RingShearConfig | None = None):
        self.config = config or RingShearConfig.preset("default")

    def run(self, params=None, seed: int = 0, frames_dir: str | Path | None = None, progress=None,
            vtk_dir: str | Path | None = None, checkpoint: str | Path | None = None, checkpoint_every: float = 600.0,
            max_phases: int | None = None) -> RigResult | None:
        """The Schulze procedure, phase by phase (module docstring); the metrics from the
        measured lid stresses by the pure functions below.

        checkpoint: a directory where the run saves its state (an HDF5 snapshot and the
        protocol's state) at the first phase boundary after every `checkpoint_every` seconds of
        wall time; a run given a directory holding a checkpoint of the same configuration and
        seed resumes from it, with results bitwise those of an uninterrupted run. max_phases:
        stop (with a checkpoint, returning None) after that many phases of this call — a run
        split across batch jobs."""
        c = self.config
        p = params_from(c.params, params)
        ck = Checkpoint(checkpoint, "ring_shear", signature(self, p, seed), every=checkpoint_every) if checkpoint else None
        saved = ck.load() if ck else None
        state = saved["protocol"] if saved else None
        t = Tester(c, p, seed, Frames(frames_dir, vtk_dir), progress, self._planned_time(), resume=saved)
        steady = [tuple(np.asarray(a) for a in part) for part in state["steady"]] if state else []
        points = [tuple(q) for q in state["points"]] if state else []
        plan = self._plan()
        k0 = state["phase"] if state else 0
        for k in range(k0, len(plan)):
            kind, arg = plan[k]
            if kind == "load":
                t.load_to(*arg)
            elif kind == "preshear":
                steady.append(t.preshear(arg))
            else:
                tau_sh, sigma_sh = t.shear_to_failure()
                points.append((arg, sigma_sh, tau_sh))
            stop = max_phases is not None and k + 1 - k0 >= max_phases and k + 1 < len(plan)
            # at a phase boundary only: the lid's mean-force accumulator is not in snapshots (it
            # was just reset by the phase's last sample), and a phase ends right after a step
            if ck and (stop or ck.due(t.d.time)) and k + 1 < len(plan):
                ck.save(t.d, {"protocol": t.protocol_state(k + 1, steady, points), "stepper": t.st.state(),
                              "frames": t.out.state()})
            if stop:
                return None
        res = RigResult("ring-shear")
        tau_pre, sigma_pre, z_lid = preshear_metrics(steady, res.metrics, target=c.preshear_stress)
        shear_point_metrics(points, res.metrics)
        locus_metrics(sigma_pre, tau_pre, points, res.metrics, res.info)
        d = t.d
        mass = float(np.sum(t.p.density * 4 / 3 * math.pi * d.radii ** 3))
        res.metrics["bulk_density"] = Metric(mass / (t.area * z_lid), math.nan, "kg/m^3", "mass / (lid area x lid height)")
        gamma_dot = c.shear_speed / z_lid
        res.metrics["inertial_number"] = Metric(gamma_dot * c.diameter / math.sqrt(sigma_pre / t.p.density), math.nan, "",
                                                "shear rate = speed at R_mean / bed height")
        res.series = {k: np.asarray(v) for k, v in t.st.series.items()}
        res.frames = [f for f in t.frames if f]
        res.info.update({"particles": c.particles, "steps": t.st.steps, "dt": d.dt, "simulated_time": d.time,
                         "engine_profile": d.profile(), "wall_seconds": t.st.wall_seconds(), "seed": seed,
                         "phases": t.phase_log, "resumed_at_phase": k0 if state else None,
                         "shear_points": [{"fraction": f, "sigma": s, "tau_peak": tp} for f, s, tp in points]})
        if ck:
            ck.remove()
        return res

    def _plan(self) -> list[tuple[str, object]]:
        """The procedure as a list of phases: (load, (sigma, max seconds)), (preshear,
        displacement), (shear, fraction)."""
        c = self.config
        plan = [("load", (c.preshear_stress, 1.0)), ("preshear", c.first_preshear_displacement)]
        for frac in [f for f in c.shear_points for _ in range(c.shear_repeats)]:
            plan += [("preshear", c.preshear_displacement), ("load", (frac * c.preshear_stress, 0.5)), ("shear", frac),
                     ("load", (c.preshear_stress, 0.5))]
        return plan

    def _planned_time(self) -> float:
        c = self.config
        cycles = len(c.shear_points) * c.shear_repeats
        shear = c.first_preshear_displacement + cycles * (c.preshear_displacement + c.shear_displacement)
        return 0.25 + 0.2 + shear / c.shear_speed + 0.1 * cycles


class Tester:
    """The rig in one state: the filled, settled trough under its lid, and the phases of the
    procedure as methods (each samples the lid stresses into the stepper's series)."""

    def __init__(self, c: RingShearConfig, p: Params, seed: int, out: Frames, progress, planned_time: float,
                 resume: dict | None = None):
        if not c.outer_radius > c.inner_radius + 4 * c.diameter:
            raise ValueError("outer_radius must exceed inner_radius by at least 4 diameters")
        self.c, self.p, self.out = c, p, out
        rng = np.random.default_rng(seed)
        ri, ro, dm = c.inner_radius, c.outer_radius, c.diameter
        self.area = math.pi * (ro ** 2 - ri ** 2)
        self.moment = 2.0 * math.pi / 3.0 * (ro ** 3 - ri ** 3)  # integral of r dA over the lid
        self.omega = c.shear_speed / (0.5 * (ri + ro))
        if resume is not None:  # a checkpoint (Checkpoint.load): no filling, no settling
            state = resume["protocol"]
            self.d = Domain.from_snapshot(resume["snapshot"])
            self.d.num_threads = c.num_threads
            self.trough, self.lid = MeshWall(self.d, 0), MeshWall(self.d, 1)
            self.lid.reset_mean_force()  # as the phase's last sample left it: averaging, from zero (not in snapshots)
            self.height, self.lid_z0 = state["height"], state["lid_z0"]
            self.st = Stepper(self.d, progress, planned_time=planned_time)
            self.st.restore(resume["stepper"])
            out.restore(resume["frames"])
            self.frames, self.next_frame, self.phase_log = state["frames"], state["next_frame"], state["phase_log"]
            self.trough_moving = state["trough_moving"]
            return
        radii = size_distribution(rng, c.particles, dm, c.size_spread, c.psd_sizes, c.psd_passing)
        spacing = 1.05 * 2 * radii.max()
        ring = math.pi * ((ro - 0.55 * spacing) ** 2 - (ri + 0.55 * spacing) ** 2) / spacing ** 2
        fill_top = spacing * (c.particles / max(ring * 0.7, 1.0) + 2) + c.bar_height
        self.height = height = fill_top + 3 * c.bar_height + 4 * dm
        lo, hi = (-ro - 2 * dm, -ro - 2 * dm, -2 * dm), (ro + 2 * dm, ro + 2 * dm, height)
        # Spheres dragged along the turning side walls jam against the held lid's bars; at E = 5 MPa
        # such a jam reaches 0.3-0.6 of a radius before it releases (a third of the runs of a tiny-
        # preset campaign stopped at the engine's default 0.3), and beyond 0.6 at pre-shear stresses
        # of 4-10 kPa (17 of the default diagnosis store's 49 runs there stopped at 0.6; the first of
        # them, rerun at 0.9, finished with mu_ie_ps 0.62). Hence 0.9: a blow-up, which grows without
        # bound, still trips it, and a run that stays below any bound is the same run. Stiffer
        # spheres (E = 2e7 passes) avoid the jams at 1.7x the cost.
        d, mp, mw = make_domain(lo, hi, p, c.num_threads, diameter=dm, max_overlap_ratio=c.max_overlap_ratio)
        d.seed = seed
        self.d = d
        self.trough = d.add_mesh_wall(geometry.merge(
            geometry.annulus(ri, ro, 0.0, segments=72, rings=2),
            geometry.cylinder(ri, 0.0, height, segments=72), geometry.cylinder(ro, 0.0, height, segments=72),
            geometry.radial_bars(ri, ro, 0.0, c.bar_height, c.bars, 0.1 * dm)), material=mw)
        pos = lattice_fill(rng, (-ro, -ro, c.bar_height), (ro, ro, fill_top), spacing,
                           lambda g: (np.hypot(g[:, 0], g[:, 1]) > ri + 0.55 * spacing)
                           & (np.hypot(g[:, 0], g[:, 1]) < ro - 0.55 * spacing), count=c.particles, jitter=0.02)
        d.add_particles(pos, radii, mp)
        d.dt = stable_dt(d, impact_speed=0.3)  # slow shearing: enduring contacts, gentle impacts
        self.st = Stepper(d, progress, planned_time=planned_time)
        self.st.advance(0.25)  # settle
        settle_airborne(d, self.st, dm)
        top = float((d.positions[:, 2] + d.radii).max())
        gap = 0.3e-3
        lid_mesh = geometry.merge(geometry.annulus(ri + gap, ro - gap, 0.0, segments=72, rings=2),
                                  geometry.radial_bars(ri + gap, ro - gap, -c.bar_height, 0.0, c.bars, 0.1 * dm,
                                                       phase=math.pi / max(c.bars, 1)))
        v = lid_mesh[0].copy()
        v[:, 2] += top + dm + max(0.0, c.bar_height - 0.8 * dm)  # bar tips start above the bed
        self.lid_z0 = v[0, 2]
        self.lid = d.add_mesh_wall((v, lid_mesh[1]), material=mw)
        self.lid.reset_mean_force()
        self.frames, self.next_frame, self.phase_log = [], 0.0, []
        self.trough_moving = False

    def protocol_state(self, phase: int, steady, points) -> dict:
        """What a checkpoint at the start of `phase` keeps besides the snapshot and the series."""
        return {"phase": phase, "height": self.height, "lid_z0": float(self.lid_z0), "frames": self.frames,
                "next_frame": self.next_frame, "phase_log": self.phase_log, "trough_moving": self.trough_moving,
                "steady": [[np.asarray(a).tolist() for a in part] for part in steady], "points": [list(q) for q in points]}

    def lid_state(self) -> tuple[float, float]:
        """Lid stresses averaged over the steps since the previous sample (a snapshot rattles
        by tens of per cent from step to step)."""
        f, t, seconds = self.lid.mean_force((0.0, 0.0, 0.0))
        if seconds == 0.0:
            f, t = self.lid.force((0.0, 0.0, 0.0))
        self.lid.reset_mean_force()
        return f[2] / self.area, t[2] / self.moment  # sigma: particles push the lid up; tau: they drag it along +omega

    def sample(self, tag: str):
        """A stepper callback that records sigma, tau and the lid height (and frames when due)."""
        def each():
            s, tau = self.lid_state()
            self.st.record(time=self.d.time, sigma=s, tau=tau, lid_z=self.lid.pose[0][2] + self.lid_z0, phase=tag)
            if self.out.active and self.d.time >= self.next_frame:
                ro, h = self.c.outer_radius, self.height
                self.frames.append(self.out.write(self.d, f"ring_{len(self.frames):04d}.png", width=420, height=230,
                                                  window=((-ro * 1.05, ro * 1.05), (-0.1 * h, -0.1 * h + 2.1 * ro * 230 / 420))))
                self.next_frame += self.c.frame_interval
            return False
        return each

    def stop_trough(self):
        """The trough stops at the start of the phase after a shear, not at the end of the shear:
        so every phase ends right after a step, with valid forces, and a checkpoint written
        there changes nothing (a snapshot of invalid forces would recompute them first)."""
        if self.trough_moving:
            self.trough.set_motion((0, 0, 0))
            self.trough_moving = False

    def turn_trough(self):
        self.trough.set_motion((0, 0, 0), (0, 0, self.omega), (0, 0, 0))
        self.trough_moving = True

    def load_to(self, sigma: float, max_seconds: float = 0.5):
        """Servo to sigma and wait until the lid holds it (5 samples within 3 %)."""
        self.stop_trough()
        self.lid.set_servo(direction=(0, 0, -1), target_stress=sigma, area=self.area, max_speed=self.c.servo_speed,
                           proportional_band=0.3, filter_time=2e-3)
        record = self.sample("load")

        def settled():
            record()
            last = self.st.series["sigma"][-5:]
            return len(last) == 5 and all(abs(x - sigma) < 0.03 * sigma for x in last)

        self.st.advance(max_seconds, chunk=2e-3, each=settled)

    def preshear(self, displacement: float):
        """Shears at sigma_pre until steady (or max_preshear); returns the tau, sigma and lid
        height samples of the steady part (its second half)."""
        c, st = self.c, self.st
        self.turn_trough()
        start = len(st.series.get("tau", []))
        chunk = min(0.05 * displacement / c.shear_speed, 0.01)  # >= 20 samples: quarters of 5+
        st.advance(displacement / c.shear_speed, chunk=chunk, each=self.sample("preshear"))
        total = displacement
        while True:
            taus = np.array(st.series["tau"][start:])
            q = len(taus) // 4
            if q >= 2:
                a, b = taus[-2 * q:-q].mean(), taus[-q:].mean()
                if abs(b - a) <= c.steady_tolerance * abs(b) or total >= c.max_preshear:
                    break
            st.advance(0.25 * displacement / c.shear_speed, chunk=chunk, each=self.sample("preshear"))
            total += 0.25 * displacement
        half = start + (len(st.series["tau"]) - start) // 2
        self.phase_log.append(("preshear", total))
        return tuple(np.array(st.series[k][half:]) for k in ("tau", "sigma", "lid_z"))

    def shear_to_failure(self) -> tuple[float, float]:
        """Shears at the current load until tau falls below 90 % of its peak (after 0.3 d):
        (peak tau, sigma at the peak)."""
        c, st, d = self.c, self.st, self.d
        self.turn_trough()
        start = len(st.series["tau"])
        peak = -math.inf
        record = self.sample("shear")
        t_start = d.time

        def each():
            nonlocal peak
            record()
            tau = st.series["tau"][-1]
            peak = max(peak, tau)
            return (d.time - t_start) * c.shear_speed > 0.3 * c.diameter and tau < 0.9 * peak  # past the peak: failed

        st.advance(c.shear_displacement / c.shear_speed, chunk=0.1 * c.diameter / c.shear_speed, each=each)
        taus = np.array(st.series["tau"][start:])
        self.phase_log.append(("shear", (d.time - t_start) * c.shear_speed))
        return float(taus.max()), float(np.array(st.series["sigma"][start:])[np.argmax(taus)])


def settle_airborne(d, st, diameter: float, margin: float = 5.0, step: float = 0.05, limit: float = 2.0) -> float:
    """Settles on (in steps of `step` s, at most `limit` s) while a sphere is more than `margin`
    diameters above the bed's surface (the 99th percentile of the sphere tops); returns the time
    added. Why: the lid starts just above the highest sphere, and a bouncy sphere still in the air
    after the settle once put it 9 cm above a 2 cm bed (restitution 0.87, size spread 0.48, one of
    the 256 default diagnosis runs) — farther than the servo travels in the whole procedure, so
    the lid never touched the bed and the run had no stresses. Where no sphere is that high the
    run is bitwise as before (no step added); a sphere that stays up (stuck to a wall) is left
    there after `limit`, and the lid comes down on it as before."""
    extra = 0.0
    while extra < limit:
        tops = d.positions[:, 2] + d.radii
        if tops.max() <= np.percentile(tops, 99) + margin * diameter:
            break
        st.advance(step)
        extra += step
    return extra


PRESHEAR_STRESS_TOLERANCE = 0.1  # the steady pre-shear's mean normal stress must be within 10 % of the requested


def preshear_metrics(steady: list[tuple[np.ndarray, np.ndarray, np.ndarray]], metrics: dict,
                     target: float | None = None) -> tuple[float, float, float]:
    """tau_pre, sigma_pre and mu_ie-ps from the steady parts (tau, sigma, lid height samples) of
    every pre-shear: each ends in the same steady flow, so they are means over all of them (as a
    Schulze tester's operator averages). Returns (tau_pre, sigma_pre, mean lid height).

    target: the requested pre-shear stress; a steady pre-shear whose mean normal stress misses it
    by more than PRESHEAR_STRESS_TOLERANCE is an error, as a tester's operator rejects such a
    test. Why: two of the 256 default diagnosis runs, made before settle_airborne, pre-sheared at
    45 and 61 % of their stress (the lid still coming down from above a bouncing sphere) and
    reported bulk densities ~350 kg/m^3 low, the two largest errors of the density net."""
    tau_steady, sig_steady, z_steady = (np.concatenate([part[k] for part in steady]) for k in range(3))
    tau_pre, tau_pre_se = block_average(tau_steady, 4)
    sigma_pre = float(np.mean(sig_steady))
    if not sigma_pre > 0:  # seen once in 256 default runs, before settle_airborne: the lid never reached the bed
        raise RuntimeError(f"ring shear: the lid carried no load in the steady pre-shear (mean normal stress "
                           f"{sigma_pre:.3g} Pa): the bed lost contact with the lid, so there is no mu_ie-ps")
    if target is not None and abs(sigma_pre / target - 1.0) > PRESHEAR_STRESS_TOLERANCE:
        raise RuntimeError(f"ring shear: the steady pre-shear's mean normal stress {sigma_pre:.4g} Pa misses the requested "
                           f"{target:.4g} Pa by more than {PRESHEAR_STRESS_TOLERANCE:.0%}: the lid did not hold the load, "
                           f"so the test is not a pre-shear at that stress")
    metrics["tau_preshear"] = Metric(tau_pre, tau_pre_se, "Pa", "steady halves of all pre-shears")
    metrics["sigma_preshear"] = Metric(sigma_pre, float(np.std(sig_steady) / math.sqrt(4)), "Pa", "lid")
    metrics["mu_ie_ps"] = Metric(tau_pre / sigma_pre, tau_pre_se / sigma_pre, "", "tau_pre / sigma_pre")
    return tau_pre, sigma_pre, float(np.mean(z_steady))


def shear_point_metrics(points: list[tuple[float, float, float]], metrics: dict):
    """mu_ie-s and tau_sh per shear fraction from (fraction, sigma_sh, tau_sh) points: the mean
    of the repeats with its standard error."""
    for frac in dict.fromkeys(f for f, _, _ in points):  # distinct fractions, in order
        rep = np.array([(s, t) for f, s, t in points if f == frac])
        if not np.all(rep[:, 0] > 0):
            raise RuntimeError(f"ring shear: the lid carried no load at the {frac:.0%} shear point "
                               f"(normal stress {rep[:, 0].min():.3g} Pa), so there is no mu_ie-s there")
        mu, mu_se = mean_and_se(rep[:, 1] / rep[:, 0])
        tau, tau_se = mean_and_se(rep[:, 1])
        tag, what = int(round(frac * 100)), f"at {frac:.0%}" + (f", mean of {len(rep)} repeats" if len(rep) > 1 else "")
        metrics[f"mu_ie_s_{tag}"] = Metric(mu, mu_se, "", f"peak tau / sigma {what}")
        metrics[f"tau_shear_{tag}"] = Metric(tau, tau_se, "Pa", f"sigma_sh = {rep[:, 0].mean():.0f} Pa, {what}")


def locus_metrics(sigma_pre: float, tau_pre: float, points, metrics: dict, info: dict):
    """The yield locus through the shear points (two fractions at least) and the outputs a
    Schulze tester reports (yield_locus.py); a locus they cannot be read from is noted in info."""
    if len({f for f, _, _ in points}) < 2:
        return
    sig, tau = [q[1] for q in points], [q[2] for q in points]
    slope, icpt = yield_locus(sig, tau)
    metrics["yield_locus_slope"] = Metric(*slope, "", "least squares through the shear points")
    metrics["yield_locus_intercept"] = Metric(*icpt, "Pa", "cohesion estimate")
    try:
        loc = locus.evaluate(sigma_pre, tau_pre, sig, tau)
    except ValueError as exc:
        info["yield_locus_note"] = str(exc)
        return
    for key, value, unit, note in (
            ("phi_lin", loc.phi_lin, "deg", "linearised angle of internal friction"),
            ("phi_e", loc.phi_e, "deg", "effective angle of internal friction"),
            ("phi_sf", loc.phi_sf, "deg", "steady-state flow angle"),
            ("sigma_1", loc.sigma_1, "Pa", "major consolidation stress"),
            ("sigma_c", loc.sigma_c, "Pa", "unconfined yield strength"),
            ("ffc", loc.ffc, "", "flow function sigma_1 / sigma_c")):
        metrics[key] = Metric(value, math.nan, unit, note)


def mean_and_se(x) -> tuple[float, float]:
    """Mean of independent repeats and its standard error (nan for a single value)."""
    x = np.asarray(x, float)
    return float(x.mean()), (float(x.std(ddof=1) / math.sqrt(x.size)) if x.size > 1 else math.nan)


def yield_locus(sigma, tau) -> tuple[tuple[float, float], tuple[float, float]]:
    """Least-squares line tau = intercept + slope sigma through the shear points:
    ((slope, its standard error), (intercept, its standard error)); errors need 3+ points."""
    sigma, tau = np.asarray(sigma, float), np.asarray(tau, float)
    if len(sigma) > 2:
        (slope, icpt), cov = np.polyfit(sigma, tau, 1, cov=True)
        err = np.sqrt(np.diag(cov))
    else:
        slope, icpt = np.polyfit(sigma, tau, 1)
        err = (math.nan, math.nan)
    return (float(slope), float(err[0])), (float(icpt), float(err[1]))
