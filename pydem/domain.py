"""pydem.Domain: a libdem domain owned by Python (freed with the object), numpy in and out.

Arrays cross without copies where safe: inputs that are already C-contiguous float64 (int32,
int64) are passed as they are, outputs are written by libdem straight into new numpy arrays.
Per-particle arrays are in ascending particle-id order, vectors as (n, 3)."""
from __future__ import annotations

import os
from typing import Iterable, Sequence

import numpy as np

from ._libdem import ffi, lib
from .cdata import as_c_array, c_definition, c_pointer
from .errors import DemInvalidArgument, DemUnknownError, check
from .walls import MeshWall, PlaneWall

# the largest seed anywhere in pydem: libdem's is a uint64, and a store keeps seeds as int64
MAX_SEED = 2 ** 63 - 1

ROLLING_MODELS = {"cdt": lib.DEM_ROLLING_CDT, "epsd": lib.DEM_ROLLING_EPSD, "epsd2": lib.DEM_ROLLING_EPSD2}
REGIONS = {"box": lib.DEM_REGION_BOX, "cylinder": lib.DEM_REGION_CYLINDER, "annular_sector": lib.DEM_REGION_ANNULAR_SECTOR}
COLOR_MODES = {"material": lib.DEM_COLOR_MATERIAL, "scalar": lib.DEM_COLOR_SCALAR, "grey": lib.DEM_COLOR_GREY}


def effects() -> list[dict]:
    """The effect registry: name, summary and parameters (name, unit, neutral value, and the
    closed range [min, max] libdem accepts)."""
    out = []
    for i in range(lib.dem_effect_count()):
        name, summary, n_params = ffi.new("const char **"), ffi.new("const char **"), ffi.new("int *")
        check(lib.dem_effect_info(i, name, summary, n_params))
        params = []
        for p in range(n_params[0]):
            pn, unit, neutral = ffi.new("const char **"), ffi.new("const char **"), ffi.new("double *")
            lo, hi = ffi.new("double *"), ffi.new("double *")
            check(lib.dem_effect_param_info(i, p, pn, unit, neutral))
            check(lib.dem_effect_param_range(i, p, lo, hi))
            params.append({"name": ffi.string(pn[0]).decode(), "unit": ffi.string(unit[0]).decode(), "neutral": neutral[0],
                           "min": lo[0], "max": hi[0]})
        out.append({"name": ffi.string(name[0]).decode(), "summary": ffi.string(summary[0]).decode(), "params": params})
    return out


# dem_contact's layout (include/dem/types.h); its size is checked against the C struct at import
_CONTACT_DTYPE = np.dtype([("i", np.int64), ("j", np.int64), ("kind", np.int32), ("wall", np.int32),
                           ("triangle", np.int64), ("point", np.float64, 3), ("normal", np.float64, 3),
                           ("force", np.float64, 3), ("overlap", np.float64), ("normal_force", np.float64),
                           ("tangential_force", np.float64), ("sliding", np.int32), ("reserved", np.int32)], align=True)
assert _CONTACT_DTYPE.itemsize == ffi.sizeof("dem_contact"), "dem_contact layout changed: update _CONTACT_DTYPE"


class Domain:
    """A simulation box with materials, particles and walls. SI units throughout. Arguments left
    at None take libdem's defaults (dem_default_domain_def: a 0.1 m box from the origin, gravity
    -9.81 m/s^2 along z, dt 1e-5 s, skin 2e-4 m, 1 thread, ...; `settings` shows them)."""

    def __init__(self, lo: Sequence[float] | None = None, hi: Sequence[float] | None = None,
                 periodic: Sequence[bool] | None = None, gravity: Sequence[float] | None = None,
                 dt: float | None = None, skin: float | None = None, num_threads: int | None = None,
                 max_overlap_ratio: float | None = None, insert_overlap_ratio: float | None = None,
                 reference_velocity: float | None = None, _ptr=None):
        if _ptr is not None:  # from a snapshot
            self._d = ffi.gc(_ptr, lib.dem_domain_destroy)
            return
        d = c_definition(lib.dem_default_domain_def, "dem_domain_def *", lo=lo, hi=hi,
                         periodic=None if periodic is None else [int(bool(p)) for p in periodic], gravity=gravity,
                         dt=dt, skin=skin, num_threads=None if num_threads is None else int(num_threads),
                         max_overlap_ratio=max_overlap_ratio, insert_overlap_ratio=insert_overlap_ratio,
                         reference_velocity=reference_velocity)
        out, msg = ffi.new("dem_domain **"), ffi.new("char[512]")
        check(lib.dem_domain_create(d, out, msg, 512), message=ffi.string(msg).decode())
        self._d = ffi.gc(out[0], lib.dem_domain_destroy)

    @classmethod
    def from_snapshot(cls, path: str | os.PathLike) -> "Domain":
        """A domain continuing, bit for bit, the run that wrote the HDF5 snapshot."""
        out, msg = ffi.new("dem_domain **"), ffi.new("char[512]")
        check(lib.dem_snapshot_read(os.fsencode(path), out, msg, 512), message=ffi.string(msg).decode())
        return cls(_ptr=out[0])

    def _check(self, status: int) -> int:
        return check(status, self._d)

    # ---- settings ------------------------------------------------------------------------
    @property
    def settings(self) -> dict:
        d = ffi.new("dem_domain_def *")
        self._check(lib.dem_domain_get_def(self._d, d))
        return {"lo": tuple(d.lo), "hi": tuple(d.hi), "periodic": tuple(bool(p) for p in d.periodic),
                "gravity": tuple(d.gravity), "dt": d.dt, "skin": d.skin, "num_threads": d.num_threads,
                "max_overlap_ratio": d.max_overlap_ratio, "insert_overlap_ratio": d.insert_overlap_ratio,
                "reference_velocity": d.reference_velocity}

    @property
    def dt(self) -> float:
        return self.settings["dt"]

    @dt.setter
    def dt(self, value: float):
        self._check(lib.dem_domain_set_dt(self._d, value))

    @property
    def num_threads(self) -> int:
        return self.settings["num_threads"]

    @num_threads.setter
    def num_threads(self, value: int):
        self._check(lib.dem_domain_set_num_threads(self._d, int(value)))

    def set_adaptive_threads(self, adaptive: bool):
        """True (the default): the steps use fewer than num_threads threads while that measures
        faster (a busy machine, a small system); results do not depend on it."""
        self._check(lib.dem_domain_set_adaptive_threads(self._d, int(bool(adaptive))))

    def set_gravity(self, g: Sequence[float]):
        self._check(lib.dem_domain_set_gravity(self._d, ffi.new("double[3]", list(g))))

    @property
    def seed(self) -> int:
        return int(lib.dem_domain_seed(self._d))

    @seed.setter
    def seed(self, value: int):
        if not 0 <= int(value) <= MAX_SEED:
            raise DemInvalidArgument(f"seed {value} outside 0..{MAX_SEED}")
        self._check(lib.dem_domain_set_seed(self._d, int(value)))

    # ---- materials and pairs ---------------------------------------------------------------
    def add_material(self, youngs_modulus: float | None = None, poisson_ratio: float | None = None,
                     density: float | None = None, shear_modulus: float | None = None) -> int:
        """A material (None: libdem's default, dem_default_material_def: E 5 MPa, nu 0.25, 2500 kg/m^3,
        isotropic: G = E / (2 (1 + nu))); shear_modulus gives G apart from E and nu."""
        m = c_definition(lib.dem_default_material_def, "dem_material_def *", youngs_modulus=youngs_modulus,
                         poisson_ratio=poisson_ratio, density=density, shear_modulus=shear_modulus)
        out = ffi.new("dem_material *")
        self._check(lib.dem_material_create(self._d, m, out))
        return out.index

    @property
    def material_count(self) -> int:
        return lib.dem_material_count(self._d)

    def set_pair(self, a: int, b: int, restitution: float | None = None, friction: float | None = None,
                 rolling_friction: float | None = None, rolling_model: str | None = None,
                 rolling_damping: float | None = None):
        """Contact constants of materials a and b (None: libdem's default, dem_default_pair_def:
        restitution 0.5, friction 0.5, no rolling friction, EPSD2)."""
        if rolling_model is not None and rolling_model not in ROLLING_MODELS:
            raise DemInvalidArgument(f"rolling_model must be one of {sorted(ROLLING_MODELS)}, got {rolling_model!r}",
                                     "DEM_ERR_INVALID_ARGUMENT")
        p = c_definition(lib.dem_default_pair_def, "dem_pair_def *", restitution=restitution, friction=friction,
                         rolling_friction=rolling_friction,
                         rolling_model=None if rolling_model is None else ROLLING_MODELS[rolling_model],
                         rolling_damping=rolling_damping)
        self._check(lib.dem_pair_set(self._d, [a], [b], p))

    def get_pair(self, a: int, b: int) -> dict:
        p = ffi.new("dem_pair_def *")
        self._check(lib.dem_pair_get(self._d, [a], [b], p))
        model = {v: k for k, v in ROLLING_MODELS.items()}[p.rolling_model]
        return {"restitution": p.restitution, "friction": p.friction, "rolling_friction": p.rolling_friction,
                "rolling_model": model, "rolling_damping": p.rolling_damping}

    def pair_damping_factor(self, a: int, b: int) -> float:
        """The damping factor libdem uses for pair (a, b) so that the delivered restitution is the
        requested one with the normal force clipped at zero: gamma_n = factor sqrt(S_n m*)
        (docs/libdem.md, "Restitution")."""
        out = ffi.new("double *")
        self._check(lib.dem_pair_damping_factor(self._d, [a], [b], out))
        return float(out[0])

    def set_effect(self, a: int, b: int, name: str, *values: float, **named: float):
        """Switches effect `name` on for pair (a, b): parameters by position or by name;
        all-neutral values switch it off."""
        spec = next((e for e in effects() if e["name"] == name), None)
        if spec is None:
            names = ", ".join(e["name"] for e in effects())
            raise DemUnknownError(f"no effect named {name!r} (known: {names})", "DEM_ERR_UNKNOWN_EFFECT")
        params = list(values)
        for p in spec["params"][len(params):]:
            if p["name"] not in named:
                raise DemInvalidArgument(f"effect {name!r} needs parameter {p['name']!r} ({p['unit']})",
                                         "DEM_ERR_INVALID_ARGUMENT")
            params.append(named.pop(p["name"]))
        if named:
            raise DemInvalidArgument(f"effect {name!r} has no parameter(s) {sorted(named)}", "DEM_ERR_INVALID_ARGUMENT")
        arr = ffi.new("double[]", [float(v) for v in params] or [0.0])
        self._check(lib.dem_pair_set_effect(self._d, [a], [b], name.encode(), arr, len(params)))

    # ---- particles -------------------------------------------------------------------------
    def add_particles(self, positions, radii, materials, velocities=None, angular_velocities=None) -> np.ndarray:
        """Adds n spheres (all or nothing); returns their ids (int64)."""
        pos = as_c_array(positions, np.float64, (3,), "positions")
        n = pos.shape[0]
        rad = as_c_array(np.broadcast_to(np.asarray(radii, dtype=np.float64), (n,)), np.float64, (), "radii", n)
        mat = as_c_array(np.broadcast_to(np.asarray(materials, dtype=np.int32), (n,)), np.int32, (), "materials", n)
        vel = None if velocities is None else as_c_array(velocities, np.float64, (3,), "velocities", n)
        ang = None if angular_velocities is None else as_c_array(angular_velocities, np.float64, (3,), "angular_velocities", n)
        ids = np.empty(n, dtype=np.int64)
        self._check(lib.dem_particles_add(self._d, n, c_pointer(pos, "double[]"), c_pointer(rad, "double[]"), c_pointer(mat, "dem_material[]"),
                                          ffi.NULL if vel is None else c_pointer(vel, "double[]"),
                                          ffi.NULL if ang is None else c_pointer(ang, "double[]"),
                                          c_pointer(ids, "int64_t[]")))
        return ids

    def remove_particles(self, ids: Iterable[int]):
        a = as_c_array(ids, np.int64, (), "ids")
        self._check(lib.dem_particles_remove(self._d, a.shape[0], c_pointer(a, "int64_t[]")))

    def __len__(self) -> int:
        return int(lib.dem_particle_count(self._d))

    def _get(self, fn, dtype, width: int) -> np.ndarray:
        n = len(self)
        out = np.empty((n, width) if width else (n,), dtype=dtype)
        if n:
            self._check(fn(self._d, c_pointer(out, "int64_t[]" if dtype == np.int64 else "double[]"), n))
        return out

    @property
    def ids(self) -> np.ndarray:
        return self._get(lib.dem_particles_get_ids, np.int64, 0)

    @property
    def positions(self) -> np.ndarray:
        return self._get(lib.dem_particles_get_positions, np.float64, 3)

    @property
    def velocities(self) -> np.ndarray:
        return self._get(lib.dem_particles_get_velocities, np.float64, 3)

    @velocities.setter
    def velocities(self, v):
        a = as_c_array(v, np.float64, (3,), "velocities", len(self))
        self._check(lib.dem_particles_set_velocities(self._d, c_pointer(a, "double[]")))

    @property
    def angular_velocities(self) -> np.ndarray:
        return self._get(lib.dem_particles_get_angular_velocities, np.float64, 3)

    @angular_velocities.setter
    def angular_velocities(self, w):
        a = as_c_array(w, np.float64, (3,), "angular_velocities", len(self))
        self._check(lib.dem_particles_set_angular_velocities(self._d, c_pointer(a, "double[]")))

    @property
    def forces(self) -> np.ndarray:
        return self._get(lib.dem_particles_get_forces, np.float64, 3)

    @property
    def torques(self) -> np.ndarray:
        return self._get(lib.dem_particles_get_torques, np.float64, 3)

    @property
    def radii(self) -> np.ndarray:
        return self._get(lib.dem_particles_get_radii, np.float64, 0)

    # ---- stepping and diagnostics ---------------------------------------------------------
    def step(self, n: int = 1):
        """Advances n steps in one C call (no per-step Python overhead)."""
        self._check(lib.dem_domain_step(self._d, int(n)))

    def diagnostics(self) -> dict:
        g = ffi.new("dem_diagnostics *")
        self._check(lib.dem_domain_diagnostics(self._d, g))
        return {"step": g.step, "time": g.time, "particle_count": g.particle_count, "contact_count": g.contact_count,
                "wall_contact_count": g.wall_contact_count, "kinetic_energy": g.kinetic_energy,
                "elastic_energy": g.elastic_energy, "max_overlap_ratio": g.max_overlap_ratio,
                "momentum": tuple(g.momentum)}

    @property
    def time(self) -> float:
        return self.diagnostics()["time"]

    def timestep_info(self) -> dict:
        t = ffi.new("dem_timestep_info *")
        self._check(lib.dem_domain_timestep_info(self._d, t))
        return {"rayleigh_time": t.rayleigh_time, "hertz_contact_time": t.hertz_contact_time,
                "suggested_dt": t.suggested_dt}

    def profile(self) -> dict:
        p = ffi.new("dem_profile *")
        self._check(lib.dem_domain_profile(self._d, p))
        return {k: getattr(p, k) for k in ("neighbor_s", "contact_s", "integrate_s", "steps", "neighbor_builds",
                                           "neighbor_pairs", "steps_fewer_threads")}

    def state_hash(self) -> int:
        h = ffi.new("uint64_t *")
        self._check(lib.dem_domain_state_hash(self._d, h))
        return int(h[0])

    # ---- walls ------------------------------------------------------------------------------
    def add_plane_wall(self, axis: int | None = None, side: int | None = None, position: float | None = None,
                       material: int | None = None, velocity: Sequence[float] | None = None):
        """A plane wall (None: libdem's default, dem_default_plane_wall_def: the floor z >= 0,
        material 0, at rest)."""
        return PlaneWall._create(self, axis, side, position, material, velocity)

    def add_mesh_wall(self, source, material: int = 0, scale: float = 1.0, offset: Sequence[float] = (0.0, 0.0, 0.0),
                      weld_tolerance: float = 0.0):
        """A triangle-mesh wall from an STL path or a (vertices (nv, 3), triangles (nt, 3)) pair."""
        return MeshWall._create(self, source, material, scale, offset, weld_tolerance)

    # ---- contacts -----------------------------------------------------------------------------
    def contacts(self) -> dict:
        """Every contact of the current state (dem_contacts_get) as numpy arrays: i, j (partner id,
        -1 for a wall), kind (0 particle, 1 plane wall, 2 mesh wall), wall, triangle, point (n, 3),
        normal (n, 3, from the partner towards i), force (n, 3, on i), overlap, normal_force,
        tangential_force, sliding (at the Coulomb limit)."""
        count = ffi.new("int64_t *")
        self._check(lib.dem_contacts_get(self._d, ffi.NULL, 0, count))
        n = int(count[0])
        buf = ffi.new("dem_contact[]", max(n, 1))
        self._check(lib.dem_contacts_get(self._d, buf, n, count))
        raw = np.frombuffer(ffi.buffer(buf, n * ffi.sizeof("dem_contact")), dtype=_CONTACT_DTYPE)
        return {name: raw[name].copy() for name in _CONTACT_DTYPE.names if name != "reserved"}

    # ---- stress -------------------------------------------------------------------------------
    def region_stress(self, kind: str = "box", *, lo=(0, 0, 0), hi=(1, 1, 1), centre=(0, 0, 0), axis: int = 2,
                      r_inner: float = 0.0, r_outer: float = 1.0, h_lo: float = 0.0, h_hi: float = 1.0,
                      angle_lo: float = -np.pi, angle_hi: float = np.pi) -> dict:
        """Love–Weber stress (Pa, compression positive) in a box, cylinder or annular sector."""
        if kind not in REGIONS:
            raise DemInvalidArgument(f"region kind must be one of {sorted(REGIONS)}, got {kind!r}",
                                     "DEM_ERR_INVALID_ARGUMENT")
        g = ffi.new("dem_region *", {"kind": REGIONS[kind], "lo": list(lo), "hi": list(hi), "centre": list(centre),
                                      "axis": axis, "r_inner": r_inner, "r_outer": r_outer, "h_lo": h_lo,
                                      "h_hi": h_hi, "angle_lo": angle_lo, "angle_hi": angle_hi})
        s = ffi.new("dem_stress *")
        self._check(lib.dem_region_stress(self._d, g, s))
        m = lambda arr: np.frombuffer(ffi.buffer(arr), dtype=np.float64).reshape(3, 3).copy()  # noqa: E731
        return {"total": m(s.total), "contact": m(s.contact), "kinetic": m(s.kinetic), "volume": s.volume,
                "particle_count": s.particle_count, "solid_fraction": s.solid_fraction,
                "mean_velocity": tuple(s.mean_velocity)}

    # ---- output -------------------------------------------------------------------------------
    def write_snapshot(self, path: str | os.PathLike):
        self._check(lib.dem_snapshot_write(self._d, os.fsencode(path)))

    def write_vtk(self, path: str | os.PathLike):
        """The particles as a VTK .vtu file (ParaView): radius, velocity, angular_velocity, force,
        id, material per sphere; the domain time as the field TIME."""
        self._check(lib.dem_vtk_write_particles(self._d, os.fsencode(path)))

    @property
    def mesh_wall_count(self) -> int:
        return int(lib.dem_mesh_wall_count(self._d))

    def write_mesh_vtk(self, mesh: int, path: str | os.PathLike):
        """Mesh wall `mesh` at its current pose as a VTK .vtu file, with each triangle's force."""
        self._check(lib.dem_vtk_write_mesh(self._d, [int(mesh)], os.fsencode(path)))

    def _render_def(self, width, height, view_axis, window, color, scalar, scalar_range, walls, background):
        r = lib.dem_default_render_def()
        r.width, r.height, r.view_axis, r.draw_walls = int(width), int(height), int(view_axis), int(bool(walls))
        if window is not None:
            (r.lo[0], r.hi[0]), (r.lo[1], r.hi[1]) = window
        if color not in COLOR_MODES:
            raise DemInvalidArgument(f"color must be one of {sorted(COLOR_MODES)}", "DEM_ERR_INVALID_ARGUMENT")
        r.color_mode = COLOR_MODES[color]
        keep = None
        if color == "scalar":
            keep = as_c_array(scalar, np.float64, (), "scalar", len(self))
            r.scalar = c_pointer(keep, "double[]")
            lo, hi = scalar_range if scalar_range is not None else (float(keep.min(initial=0)), float(keep.max(initial=1)))
            r.scalar_min, r.scalar_max = lo, hi
        for a in range(3):
            r.background[a] = background[a]
        return r, keep

    def render(self, width: int = 420, height: int = 230, view_axis: int = 1, window=None, color: str = "material",
               scalar=None, scalar_range=None, walls: bool = True, background=(255, 255, 255)) -> np.ndarray:
        """RGB image (height, width, 3) uint8: orthographic view along view_axis; window is
        ((right_lo, right_hi), (up_lo, up_hi)) in metres, None for the domain's box."""
        r, keep = self._render_def(width, height, view_axis, window, color, scalar, scalar_range, walls, background)
        img = np.empty((height, width, 3), dtype=np.uint8)
        self._check(lib.dem_render_rgb(self._d, ffi.new("dem_render_def *", r), c_pointer(img, "unsigned char[]")))
        del keep
        return img

    def render_png(self, path: str | os.PathLike, width: int = 420, height: int = 230, view_axis: int = 1, window=None,
                   color: str = "material", scalar=None, scalar_range=None, walls: bool = True,
                   background=(255, 255, 255)):
        r, keep = self._render_def(width, height, view_axis, window, color, scalar, scalar_range, walls, background)
        self._check(lib.dem_render_png(self._d, ffi.new("dem_render_def *", r), os.fsencode(path)))
        del keep
