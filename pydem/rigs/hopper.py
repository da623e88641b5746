"""Wedge-shaped hopper (seed 001): a quasi-3D slab hopper with a slot outlet, binary spheres
filled as packing A (uniformly mixed) or B1-B4 (layers), discharged through the slot.

Outputs: discharge time, NRRP(t) = N_r / N_i, mass flow rate (slope of the remaining mass over
20-80 % discharged, with its standard error), bulk density, and front-view PNG frames labelled
with the remaining discharge time and the NRRP (file names and frames/index.csv).

Assumptions where seed 001 gives no numbers (its Fig. 1 is not in the text): the geometry
(top width 200 mm, walls 30 degrees from vertical, slot 54 mm = 6 large diameters, slab 40 mm
thick, a 150 mm vertical section above the wedge); the layer orders B1: fine below coarse, B2:
coarse below fine, B3: fine-coarse-fine, B4: coarse-fine-coarse (bottom to top), layer
thicknesses by the fine volume fraction; frames are 420 wide x 230 high with the whole hopper
in the middle, so the seed's centre crop to 224 x 224 keeps the hopper and its outlet."""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import geometry
from ..domain import Domain
from ..errors import DemRunError
from ..walls import MeshWall
from .checkpoint import Checkpoint, CheckpointStop, signature
from .common import Frames, diameters_from_table, Stepper, make_domain, params_from, size_distribution, stable_dt
from .config import Params, default_threads, knob
from .result import Metric, RigResult
from .table1 import TABLE1, species_counts  # noqa: F401  (re-exported: the rig's cases by name)

PACKINGS = ("A", "B1", "B2", "B3", "B4")


@dataclass
class HopperConfig:
    particles: int = knob(2000, 10, 2_000_000, "", "number of spheres N")
    d_small: float = knob(6e-3, 1e-4, 0.1, "m", "fine sphere diameter")
    d_large: float = knob(9e-3, 1e-4, 0.1, "m", "coarse sphere diameter")
    psd_sizes: list = knob([], 1e-6, 1.0, "m", "size table: sieve sizes, increasing (replaces the two species; packing A)")
    psd_passing: list = knob([], 0.0, 1.0, "", "size table: cumulative mass fraction passing each size, 0 ... 1")
    fine_fraction: float = knob(0.3, 0.0, 1.0, "", "volume fraction of fine spheres (Phi_s)")
    size_spread: float = knob(0.0, 0.0, 0.5, "", "each species' diameters uniform in d (1 +- spread) "
                              "(0: the two sizes exactly; replaced by a size table)")
    packing: str = knob("A", doc="initial packing: A mixed, B1-B4 layered", choices=PACKINGS)
    top_width: float = knob(0.2, 0.01, 5.0, "m", "width of the vertical section")
    slot_width: float = knob(0.054, 1e-3, 1.0, "m", "outlet slot width b")
    thickness: float = knob(0.04, 1e-3, 1.0, "m", "slab thickness (front to back plate)")
    wall_angle: float = knob(30.0, 0.0, 80.0, "deg", "wedge walls from the vertical")
    vertical_height: float = knob(0.15, 0.0, 5.0, "m", "height of the vertical section above the wedge")
    settle_time: float = knob(0.4, 0.0, 60.0, "s", "settling after the last filling batch")
    density_boxes: str = knob("below_highest", doc="where the bulk density is measured: three boxes ending two "
                              "diameters below the highest sphere (the tiny preset's), or below the free surface's "
                              "lowest point (the default preset's: a sloped surface leaves the "
                              "former's top box part empty, seed scatter 43 -> 14 kg/m^3, studies/hopper_bulk_density.py)",
                              choices=("below_highest", "below_surface"))
    max_time: float = knob(30.0, 0.1, 3600.0, "s", "discharge time limit")
    jam_time: float = knob(1.0, 0.01, 60.0, "s", "no outflow for this long: jammed")
    max_overlap_ratio: float = knob(0.3, 0.05, 0.9, "", "overlap / smaller radius that stops the run as a blow-up "
                                    "(Table 1 cases: 0.6, see apply_case)")
    num_threads: int = knob(default_threads(), 1, 256, "", "OpenMP threads, at most (default: OMP_NUM_THREADS, else the cores)")
    frame_interval: float = knob(0.05, 1e-4, 10.0, "s", "time between frames (with --frames)")
    frame_width: int = knob(420, 16, 8192, "px", "frame width")
    frame_height: int = knob(230, 16, 8192, "px", "frame height")
    case: str = knob("", doc="a seed-001 Table 1 case (A-1 ... B4-5): sets N, sizes, packing, parameters",
                     choices=("",) + tuple(TABLE1))
    params: Params = field(default_factory=Params)

    def __post_init__(self):
        if self.case:
            apply_case(self, self.case)

    @property
    def largest(self) -> float:
        """The largest sphere diameter: the coarse species' (widened by the size spread), or the size
        table's top size."""
        if len(self.psd_sizes):
            return max(self.d_small, self.d_large, self.psd_sizes[-1])
        return max(self.d_small, self.d_large) * (1.0 + self.size_spread)

    def on_set(self, key: str):
        """Setting `case` loads its Table 1 values; keys set after it override them."""
        if key == "case" and self.case:
            apply_case(self, self.case)

    @classmethod
    def preset(cls, name: str) -> "HopperConfig":
        if name == "tiny":  # seconds: for tests
            return cls(particles=250, d_small=4e-3, d_large=6e-3, top_width=0.08, slot_width=0.03, thickness=0.02,
                       vertical_height=0.06, settle_time=0.15, max_time=5.0)
        if name == "default":  # the density below the free surface (a deep bed; the tiny one is too shallow for it
            return cls(density_boxes="below_surface")  # in the vertical section): stores record it, config_drift guards
        if name == "paper":  # a Table 1 case at full size
            return cls(case="B1-1")
        raise ValueError(f"unknown preset {name!r}: tiny, default or paper")


def apply_case(cfg: HopperConfig, name: str):
    """Sets the 11 Table 1 parameters of case `name` (and its packing) on cfg."""
    cfg.case = name
    apply_row(cfg, TABLE1[name], name.split("-")[0])


def apply_row(cfg: HopperConfig, row: tuple, packing: str):
    """Sets 11 parameters given as a Table 1 row (N, nu, E GPa, fine volume fraction, e_pp, e_wp,
    mu_pp, mu_wp, mu_r, (d_fine, d_coarse) mm, rho) and the packing on cfg: a Table 1 case, or a
    hopper drawn like them."""
    n, nu, e_gpa, phi, epp, ewp, mupp, muwp, mur, dd, rho = row
    cfg.packing = packing
    cfg.particles, cfg.fine_fraction = n, phi
    cfg.d_small, cfg.d_large = dd[0] / 1000.0, dd[1] / 1000.0  # mm -> m (9 / 1000 is exactly 0.009)
    p = cfg.params
    p.poisson_ratio, p.youngs_modulus, p.density = nu, e_gpa * 1e9, float(rho)
    p.restitution, p.wall_restitution, p.friction, p.wall_friction = epp, ewp, mupp, muwp
    p.rolling_friction = p.wall_rolling_friction = mur
    # soft (E = 10 MPa) 3:1 binary cases: a coarse sphere landing on a fine one during the filling
    # presses it beyond 0.3 of the fine radius (A-5 stopped there); the limit only detects
    # blow-ups and changes no trajectory that stays below it
    cfg.max_overlap_ratio = 0.6


class Hopper:
    name = "hopper"
    protocol = 1  # raised whenever a metric's definition changes (campaigns refuse to mix protocols)

    def __init__(self, config: HopperConfig | None = None):
        self.config = config or HopperConfig.preset("default")

    # ---- geometry --------------------------------------------------------------------------
    def _geometry(self):
        c = self.config
        half_b, half_w = 0.5 * c.slot_width, 0.5 * c.top_width
        h_wedge = (half_w - half_b) / max(math.tan(math.radians(c.wall_angle)), 1e-9) if c.wall_angle > 0 else 0.0
        z_top = h_wedge + c.vertical_height
        T = c.thickness
        walls = [
            geometry.rectangle((-half_b, 0, 0), (0, T, 0), (-(half_w - half_b), 0, h_wedge)),  # left wedge wall
            geometry.rectangle((half_b, 0, 0), (half_w - half_b, 0, h_wedge), (0, T, 0)),  # right wedge wall
            geometry.rectangle((-half_w, 0, h_wedge), (0, T, 0), (0, 0, c.vertical_height)),
            geometry.rectangle((half_w, 0, h_wedge), (0, 0, c.vertical_height), (0, T, 0)),
        ]
        return geometry.merge(*walls), h_wedge, z_top

    def _inside(self, g, h_wedge, margin):
        c = self.config
        half_b, half_w = 0.5 * c.slot_width, 0.5 * c.top_width
        wall_x = np.where(g[:, 2] < h_wedge, half_b + (half_w - half_b) * g[:, 2] / max(h_wedge, 1e-12), half_w)
        return (np.abs(g[:, 0]) < wall_x - margin / max(math.cos(math.radians(c.wall_angle)), 1e-3)) & (g[:, 2] > margin)

    # ---- the run ------------------------------------------------------------------------------
    def run(self, params=None, seed: int = 0, frames_dir: str | Path | None = None, progress=None,
            vtk_dir: str | Path | None = None, images: bool = False, checkpoint: str | Path | None = None,
            checkpoint_every: float = 600.0, stop_at: float | None = None) -> RigResult | None:
        """Fill, settle, open the gate, discharge; the metrics of the module's docstring.

        checkpoint / checkpoint_every / stop_at: as AngleOfRepose.run (saved during the filling,
        the settling and the discharge; resumed bitwise). Not with images=True (those frames
        are kept in memory, not on disk)."""
        c = self.config
        p = params_from(c.params, params)
        if checkpoint and images:
            raise ValueError("checkpoint: not with images=True (the cropped frames live in memory); write --frames instead")
        ck = Checkpoint(checkpoint, "hopper", signature(self, p, seed), checkpoint_every, stop_at) if checkpoint else None
        saved = ck.load() if ck else None
        rng = np.random.default_rng(seed)
        mesh, h_wedge, z_top = self._geometry()
        order, diameters = self._pouring_order(rng)  # bottom first (rng's first draws); True = fine
        n_fine, n_coarse = int(order.sum()), int((~order).sum())
        dl = c.largest
        half = 0.5 * c.top_width + 2 * dl
        lo = (-half, 0.0, -0.25 * z_top - 4 * dl)
        out = Frames(frames_dir, vtk_dir, images)  # images: seed 001's crop/grey frames in memory
        if saved:
            d = Domain.from_snapshot(saved["snapshot"])
            d.num_threads = c.num_threads
            gate = MeshWall(d, 1)
            s = saved["protocol"]
            rng.bit_generator.state = s["rng"]
            out.restore(saved["frames"])
        else:
            d, gate = self._build(p, seed, mesh, lo, z_top)
            s = {"phase": "fill", "placed": 0, "batch_pending": False, "frames": []}
        mp, mf = 0, 2  # the coarse and the fine species' materials (_build)
        st = Stepper(d, progress, planned_time=c.max_time)
        if saved:
            st.restore(saved["stepper"])
        if ck:
            st.attach_checkpoint(ck, lambda: {"protocol": dict(s, rng=rng.bit_generator.state), "frames": out.state()})
        resumed_at = d.time if saved else None
        masses = lambda: p.density * 4 / 3 * math.pi * d.radii ** 3  # noqa: E731
        win = self._window(h_wedge, z_top)

        def each():  # during the discharge: the gate drops away; spheres below the slot leave the count and the domain
            if gate.pose[0][2] < lo[2] + 2 * dl:
                gate.set_motion(velocity=(0.0, 0.0, 0.0))
            z = d.positions[:, 2]
            gone = z < -2 * dl
            if gone.any():
                d.remove_particles(d.ids[gone])
            z = d.positions[:, 2]
            inside = z > 0.0
            n_r = int(inside.sum())
            st.record(time=d.time - s["t0"], remaining=n_r, remaining_mass=float(masses()[inside].sum()))
            if n_r < s["last_out"][1]:
                s["last_out"] = [d.time, n_r]
            if out.active and d.time >= s["next_frame"]:
                s["frames"].append((out.write(d, f"frame_{len(s['frames']):05d}.png", width=c.frame_width,
                                              height=c.frame_height, window=win, color="grey"),
                                    d.time - s["t0"], n_r / s["n_initial"]))
                s["next_frame"] += c.frame_interval
            return n_r == 0 or d.time - s["last_out"][0] > c.jam_time

        try:
            if s["phase"] == "fill":
                self._fill(d, rng, order, diameters, mf, mp, h_wedge, z_top, st, s)  # sets the time step as it pours
                s["phase"] = "settle"
            if s["phase"] == "settle":
                st.advance(c.settle_time)
                s["density"] = list(self._bulk_density(d, p, h_wedge))
                s["n_initial"] = len(d)
                s["t0"] = d.time
                gate.set_motion(velocity=(0.0, 0.0, -2.0))
                s.update(next_frame=d.time, last_out=[d.time, len(d)], phase="discharge")
            # frames are taken between chunks: with frames on, chunks no longer than their interval
            st.advance(c.max_time, chunk=min(5e-3, c.frame_interval) if out.active else 5e-3, each=each)
        except CheckpointStop:
            return None
        n_initial, density = s["n_initial"], s["density"]
        frames = [tuple(f) for f in s["frames"]]
        series = {k: np.asarray(v) for k, v in st.series.items()}
        t, nr, mr = series["time"], series["remaining"], series["remaining_mass"]
        emptied = bool(nr[-1] == 0)
        t_dis = float(t[np.argmax(nr == 0)]) if emptied else math.nan
        flow, flow_se = mass_flow_rate(t, mr)
        res = RigResult("hopper")
        res.metrics["discharge_time"] = Metric(t_dis, math.nan, "s", "gate opening to empty" if emptied else
                                               f"not emptied: {nr[-1]} left (jammed or time limit)")
        res.metrics["mass_flow_rate"] = Metric(flow, flow_se, "kg/s", "slope over 20-80 % discharged")
        res.metrics["bulk_density"] = Metric(density[0], density[1], "kg/m^3", "settled bed in the vertical section")
        series["nrrp"] = nr / n_initial
        res.series = series
        res.frames = self._label_frames(frames, t_dis, out.dir)
        if images:
            res.images = np.stack(out.images) if out.images else np.zeros((0, 224, 224), np.uint8)
            res.series["frame_time"] = np.array([t for _, t, _ in frames])
            res.series["frame_nrrp"] = np.array([q for _, _, q in frames])  # without PNGs (VTK only) there is nothing to label
        res.info = {"particles": n_initial, "fine": n_fine, "coarse": n_coarse, "case": c.case, "packing": c.packing,
                    "steps": st.steps, "dt": d.dt, "simulated_time": d.time, "emptied": emptied,
                    "engine_profile": d.profile(), "resumed_at": resumed_at,
                    "wall_seconds": st.wall_seconds(), "seed": seed, "slot_width": c.slot_width,
                    "thickness": c.thickness}
        if ck:
            ck.remove()
        return res

    def _build(self, p: Params, seed: int, mesh, lo, z_top):
        """The empty hopper with its gate closed: (domain, the gate wall). Materials: 0 the
        coarse species, 1 the walls, 2 the fine species (same solid)."""
        c = self.config
        dl = c.largest
        hi = (-lo[0], c.thickness, z_top + 2 * dl)
        d, mp, mw = make_domain(lo, hi, p, c.num_threads, diameter=dl, max_overlap_ratio=c.max_overlap_ratio)
        d.seed = seed
        mf = d.add_material(p.youngs_modulus, p.poisson_ratio, p.density)  # the fine species, same solid
        assert (mp, mw, mf) == (0, 1, 2)
        for a, b in ((mf, mf), (mf, mp)):
            d.set_pair(a, b, p.restitution, p.friction, p.rolling_friction, p.rolling_model)
        d.set_pair(mf, mw, p.wall_restitution, p.wall_friction, p.wall_rolling_friction, p.rolling_model)
        for name, values in p.effects.items():
            for a, b in ((mf, mf), (mf, mp)):
                d.set_effect(a, b, name, **values)
        d.add_mesh_wall(mesh, material=mw)
        d.add_plane_wall(axis=1, side=1, position=0.0, material=mw)
        d.add_plane_wall(axis=1, side=-1, position=c.thickness, material=mw)
        gate = d.add_mesh_wall(geometry.rectangle((-0.5 * c.slot_width - dl, 0, 0), (c.slot_width + 2 * dl, 0, 0),
                                                  (0, c.thickness, 0)), material=mw)
        return d, gate

    def _pouring_order(self, rng) -> tuple[np.ndarray, np.ndarray]:
        """(fine?, diameter) of every sphere, bottom first: the two species in the packing's
        order, or, given a size table, diameters drawn from it (mixed: packing A; "fine" means
        below the table's middle size, for the counts only)."""
        c = self.config
        if len(c.psd_sizes) or len(c.psd_passing):
            if c.packing != "A":
                raise ValueError(f"a size table fills the hopper mixed (packing A), not {c.packing}: layers need two species")
            diam = diameters_from_table(rng, c.particles, c.psd_sizes, c.psd_passing)
            return diam < 0.5 * (c.psd_sizes[0] + c.psd_sizes[-1]), diam
        n_fine, n_coarse = species_counts(c.particles, c.d_small, c.d_large, c.fine_fraction)
        order = self._filling_order(rng, n_fine, n_coarse)
        diam = np.where(order, c.d_small, c.d_large)
        if c.size_spread > 0.0:  # no draw at 0: the two-size runs stay as they were
            diam = 2.0 * size_distribution(rng, len(diam), diam, c.size_spread)  # radii -> diameters
        return order, diam

    def _filling_order(self, rng, n_fine: int, n_coarse: int) -> np.ndarray:
        fine, coarse = np.ones(n_fine, bool), np.zeros(n_coarse, bool)
        pk = self.config.packing
        if pk == "A":
            order = np.concatenate([fine, coarse])
            rng.shuffle(order)
            return order
        if pk == "B1":
            return np.concatenate([fine, coarse])
        if pk == "B2":
            return np.concatenate([coarse, fine])
        if pk == "B3":
            h = n_fine // 2
            return np.concatenate([fine[:h], coarse, fine[h:]])
        h = n_coarse // 2  # B4
        return np.concatenate([coarse[:h], fine, coarse[h:]])

    def _fill(self, d, rng, order, diameters, mf, mp, h_wedge, z_top, st, s: dict):
        """Pours the spheres in batches: each batch fills the free space above the bed on a
        lattice of the coarse spacing, in the given bottom-to-top order, then settles a little.
        s["placed"] counts the spheres poured; s["batch_pending"]: the last batch is still
        settling (a checkpoint inside its settling resumes there)."""
        while s["placed"] < len(order) or s["batch_pending"]:
            if not s["batch_pending"]:
                self._pour_batch(d, rng, order, diameters, mf, mp, h_wedge, z_top, s)
                s["batch_pending"] = True
            st.advance(0.15 if s["placed"] < len(order) else 0.0)
            s["batch_pending"] = False

    def _pour_batch(self, d, rng, order, diameters, mf, mp, h_wedge, z_top, s: dict):
        c = self.config
        dl = c.largest
        spacing = 1.05 * dl
        placed = s["placed"]
        # lattice centres start 0.55 spacing above the highest sphere top: clear of it
        # whatever the jitter (0.58 dl >= r_new + 2 % jitter)
        bed = float((d.positions[:, 2] + d.radii).max()) + 0.55 * spacing if len(d) else 0.0
        g = np.stack(np.meshgrid(np.arange(-0.5 * c.top_width + 0.5 * spacing, 0.5 * c.top_width, spacing),
                                 np.arange(0.5 * spacing, c.thickness - 0.49 * spacing, spacing),
                                 np.arange(max(bed, 0.5 * spacing), z_top - 0.5 * spacing, spacing), indexing="ij"),
                     -1).reshape(-1, 3)
        if len(g) == 0 or c.thickness < spacing:
            raise ValueError(f"the hopper cannot hold {len(order)} spheres of {dl * 1e3:g} mm: "
                             f"{placed} placed (thickness {c.thickness * 1e3:g} mm)")
        g = g[np.lexsort((g[:, 0], g[:, 1], g[:, 2]))]
        g = g[self._inside(g, h_wedge, 0.55 * spacing)]
        g = g[: len(order) - placed]
        if len(g) == 0:
            raise ValueError(f"the hopper is full after {placed} of {len(order)} spheres: enlarge it")
        g += rng.uniform(-0.02, 0.02, g.shape) * spacing
        fine = order[placed:placed + len(g)]
        radii = 0.5 * diameters[placed:placed + len(g)]
        # a row 0.49 spacing from the back wall, jittered towards it, puts a sphere of the largest
        # size 0.0065 of its diameter into the wall (1 hopper run of 631 failed so): held clear.
        # Only such spheres move; every other fill is unchanged.
        g[:, 1] = np.clip(g[:, 1], radii * (1 + 1e-6), c.thickness - radii * (1 + 1e-6))
        d.add_particles(g, radii, np.where(fine, mf, mp))
        s["placed"] = placed + len(g)
        # each batch may bring the smaller species first (B2, B4): the step follows
        d.dt = stable_dt(d, impact_speed=math.sqrt(2 * 9.81 * 0.2 * z_top))

    def _bulk_density(self, d, p: Params, h_wedge: float) -> tuple[float, float]:
        """(density, its block standard error) of the settled bed: solid fraction x particle density
        in boxes across the section (where: density_boxes)."""
        boxes = (self._boxes_below_surface if self.config.density_boxes == "below_surface" else
                 self._boxes_below_highest)(d, h_wedge)
        fr = np.array([d.region_stress("box", lo=lo, hi=hi)["solid_fraction"] for lo, hi in boxes])
        sem = fr.std(ddof=1) / math.sqrt(len(fr)) if len(fr) > 1 else math.nan
        return p.density * float(fr.mean()), p.density * float(sem)

    def _boxes_below_highest(self, d, h_wedge: float) -> list[tuple]:
        """The tiny preset's: three boxes from the wedge's top
        (or 0.3 of the bed) to two diameters below the highest sphere, as wide as the vertical
        section less a diameter."""
        c = self.config
        top = float(d.positions[:, 2].max())
        z0, z1 = max(h_wedge, 0.3 * top), top - 2 * c.largest
        if z1 - z0 < 2 * c.largest:
            z0, z1 = 0.2 * top, 0.8 * top
        half = 0.5 * (c.top_width if z0 >= h_wedge else c.slot_width) - c.largest
        edges = np.linspace(z0, z1, 4)
        return [((-half, 0.0, a), (half, c.thickness, b)) for a, b in zip(edges[:-1], edges[1:])]

    def _boxes_below_surface(self, d, h_wedge: float) -> list[tuple]:
        """Three boxes of two largest diameters each, the highest ending two diameters below the free
        surface's lowest point (the lowest of the column tops, columns two diameters wide across the
        section: a sloped surface or a sphere resting high on a wall moves no box into empty space);
        a box inside the wedge is as wide as the wedge at its lower edge, less a diameter."""
        c = self.config
        dl = c.largest
        x, z = d.positions[:, 0], d.positions[:, 2]
        half_b, half_w = 0.5 * c.slot_width, 0.5 * c.top_width
        column = np.floor((x + half_w) / (2 * dl)).astype(int)
        lowest_top = min(z[column == k].max() for k in np.unique(column))
        z1 = lowest_top - 2 * dl
        slant = 1.0 / max(math.cos(math.radians(c.wall_angle)), 1e-3)
        boxes = []
        for k in range(3):
            a, b = z1 - 2 * dl * (k + 1), z1 - 2 * dl * k
            wall = half_w if a >= h_wedge else half_b + (half_w - half_b) * max(a, 0.0) / max(h_wedge, 1e-12)
            half = wall - dl * slant
            if a <= 0.0 or half <= dl:
                break  # the bed is too shallow for this box: the ones above it
            boxes.append(((-half, 0.0, a), (half, c.thickness, b)))
        if not boxes:
            raise DemRunError(f"hopper: the settled bed is too shallow to measure its bulk density (free surface "
                              f"at {lowest_top:.4g} m, largest sphere {dl:.3g} m)")
        return boxes

    def _window(self, h_wedge, z_top):
        """The whole hopper and a little below the slot, at the frame's aspect ratio."""
        c = self.config
        need_w, need_h = 1.1 * c.top_width, 1.2 * z_top
        aspect = c.frame_width / c.frame_height
        width, height = (need_w, need_w / aspect) if need_w / need_h > aspect else (need_h * aspect, need_h)
        z0 = 0.5 * (z_top - 0.15 * z_top) - 0.5 * height + 0.05 * z_top
        return (-0.5 * width, 0.5 * width), (z0, z0 + height)

    @staticmethod
    def _label_frames(frames, t_dis: float, fdir: Path | None) -> list[str]:
        """Renames frames to carry their labels and writes frames/index.csv."""
        if fdir is None:
            return []
        out = []
        with open(fdir / "index.csv", "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["file", "time_s", "remaining_discharge_time_s", "nrrp"])
            for path, t, nrrp in frames:
                rem = t_dis - t if t_dis == t_dis else math.nan
                new = Path(path).with_name(f"{Path(path).stem}_rem{rem:.3f}s_nrrp{nrrp:.3f}.png")
                Path(path).rename(new)
                w.writerow([new.name, f"{t:.5f}", f"{rem:.5f}", f"{nrrp:.5f}"])
                out.append(str(new))
        return out


def mass_flow_rate(t: np.ndarray, remaining_mass: np.ndarray) -> tuple[float, float]:
    """Steady discharge rate (kg/s): least-squares slope of the remaining mass between 80 % and
    20 % of the initial mass, with the slope's standard error."""
    m0 = remaining_mass[0] if len(remaining_mass) else 0.0
    sel = (remaining_mass <= 0.8 * m0) & (remaining_mass >= 0.2 * m0)
    if sel.sum() < 3:
        return math.nan, math.nan
    x, y = t[sel], remaining_mass[sel]
    A = np.column_stack([x, np.ones_like(x)])
    coef, res, *_ = np.linalg.lstsq(A, y, rcond=None)
    dof = max(len(x) - 2, 1)
    s2 = float(np.sum((y - A @ coef) ** 2)) / dof
    se = math.sqrt(s2 / float(np.sum((x - x.mean()) ** 2)))
    return float(-coef[0]), se


def beverloo_fit(slot_widths, flow_rates, d: float, bulk_density: float, length: float) -> dict:
    """Beverloo's slot form W = C rho_b sqrt(g) L (b - k d)^(3/2), fitted as the straight line
    W^(2/3) = A (b - k d): C = A^(3/2) / (rho_b sqrt(g) L), k = -intercept / (A d)."""
    b = np.asarray(slot_widths, float)
    w23 = np.asarray(flow_rates, float) ** (2.0 / 3.0)
    (A, icpt), *_ = np.linalg.lstsq(np.column_stack([b, np.ones_like(b)]), w23, rcond=None)
    C = A ** 1.5 / (bulk_density * math.sqrt(9.81) * length)
    k = -icpt / (A * d)
    pred = (C * bulk_density * math.sqrt(9.81) * length * np.clip(b - k * d, 0, None) ** 1.5)
    r2 = 1.0 - np.sum((np.asarray(flow_rates) - pred) ** 2) / np.sum((np.asarray(flow_rates) - np.mean(flow_rates)) ** 2)
    return {"C": float(C), "k": float(k), "r2": float(r2)}
