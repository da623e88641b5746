"""Wall objects: handles into their domain (each keeps its Domain alive)."""
from __future__ import annotations

import os
from typing import Sequence

import numpy as np

from ._libdem import ffi, lib
from .cdata import as_c_array, c_definition, c_pointer


class PlaneWall:
    """An analytic axis-aligned plane (the particles live on its `side`). `index` is libdem's
    dem_plane_wall handle's index (cffi passes [index] where the C API takes the handle)."""

    def __init__(self, domain, index: int):
        self.domain, self.index = domain, index

    @classmethod
    def _create(cls, domain, axis, side, position, material, velocity):
        w = c_definition(lib.dem_default_plane_wall_def, "dem_plane_wall_def *", axis=axis, side=side,
                         position=position, material=None if material is None else [int(material)], velocity=velocity)
        out = ffi.new("dem_plane_wall *")
        domain._check(lib.dem_plane_wall_add(domain._d, w, out))
        return cls(domain, out.index)

    def set_velocity(self, velocity: Sequence[float]):
        self.domain._check(lib.dem_plane_wall_set_velocity(self.domain._d, [self.index], ffi.new("double[3]", list(velocity))))

    @property
    def force(self) -> np.ndarray:
        f = ffi.new("double[3]")
        self.domain._check(lib.dem_plane_wall_force(self.domain._d, [self.index], f))
        return np.array(list(f))

    def reset_mean_force(self) -> None:
        """Starts (or restarts) the time average of the wall force read by mean_force."""
        self.domain._check(lib.dem_plane_wall_reset_mean_force(self.domain._d, [self.index]))

    def mean_force(self) -> tuple[np.ndarray, float]:
        """(force, seconds): the wall force averaged over every step since reset_mean_force, and
        the time averaged (0 with zero force when no step was taken)."""
        f, sec = ffi.new("double[3]"), ffi.new("double *")
        self.domain._check(lib.dem_plane_wall_mean_force(self.domain._d, [self.index], f, sec))
        return np.array(list(f)), float(sec[0])


class MeshWall:
    """A triangle-mesh wall: moving, load-controlled, with forces per wall and per triangle."""

    def __init__(self, domain, index: int):
        self.domain, self.index = domain, index

    @classmethod
    def _create(cls, domain, source, material, scale, offset, weld_tolerance):
        md = lib.dem_default_mesh_def()
        md.scale, md.material, md.weld_tolerance = float(scale), [int(material)], float(weld_tolerance)
        for a in range(3):
            md.offset[a] = offset[a]
        out = ffi.new("dem_mesh_wall *")
        mdp = ffi.new("dem_mesh_def *", md)
        if isinstance(source, (str, os.PathLike)):
            domain._check(lib.dem_mesh_wall_add_stl(domain._d, os.fsencode(source), mdp, out))
        else:
            vertices, triangles = source
            v = as_c_array(vertices, np.float64, (3,), "vertices")
            t = as_c_array(triangles, np.int32, (3,), "triangles")
            domain._check(lib.dem_mesh_wall_add(domain._d, v.shape[0], c_pointer(v, "double[]"), t.shape[0],
                                                c_pointer(t, "int32_t[]"), mdp, out))
        return cls(domain, out.index)

    def info(self) -> dict:
        i = ffi.new("dem_mesh_info *")
        self.domain._check(lib.dem_mesh_wall_info(self.domain._d, [self.index], i))
        keys = ("vertex_count", "triangle_count", "edge_count", "boundary_edge_count", "nonmanifold_edge_count",
                "skipped_degenerate", "input_triangle_count")
        out = {k: int(getattr(i, k)) for k in keys}
        out["lo"], out["hi"] = tuple(i.lo), tuple(i.hi)
        return out

    @property
    def vertices(self) -> np.ndarray:
        out = np.empty((self.info()["vertex_count"], 3))
        self.domain._check(lib.dem_mesh_wall_get_vertices(self.domain._d, [self.index], c_pointer(out, "double[]"), len(out)))
        return out

    @property
    def triangles(self) -> np.ndarray:
        out = np.empty((self.info()["triangle_count"], 3), dtype=np.int32)
        self.domain._check(lib.dem_mesh_wall_get_triangles(self.domain._d, [self.index], c_pointer(out, "int32_t[]"), len(out)))
        return out

    def set_motion(self, velocity: Sequence[float] = (0, 0, 0), angular_velocity: Sequence[float] | None = None,
                   centre: Sequence[float] | None = None):
        """Translation velocity (m/s) plus rotation (rad/s vector) about an axis through
        `centre` (a point moving with the wall). Ends load control."""
        w = ffi.NULL if angular_velocity is None else ffi.new("double[3]", list(angular_velocity))
        c = ffi.NULL if centre is None else ffi.new("double[3]", list(centre))
        self.domain._check(lib.dem_mesh_wall_set_motion(self.domain._d, [self.index], ffi.new("double[3]", list(velocity)),
                                                        w, c))

    def set_servo(self, direction: Sequence[float] = (0, 0, -1), target_force: float = 0.0, target_stress: float = 0.0,
                  area: float = 0.0, max_speed: float = 0.05, proportional_band: float = 0.2, filter_time: float = 0.0):
        """Load control along `direction` (see docs/walls.md for the law and its gains)."""
        s = lib.dem_default_servo_def()
        for a in range(3):
            s.direction[a] = direction[a]
        s.target_force, s.target_stress, s.area = target_force, target_stress, area
        s.max_speed, s.proportional_band, s.filter_time = max_speed, proportional_band, filter_time
        self.domain._check(lib.dem_mesh_wall_set_servo(self.domain._d, [self.index], ffi.new("dem_servo_def *", s)))

    def servo_off(self):
        self.domain._check(lib.dem_mesh_wall_servo_off(self.domain._d, [self.index]))

    @property
    def pose(self) -> tuple[np.ndarray, np.ndarray]:
        """(translation (3,), rotation (3, 3)): x = R x0 + t."""
        t, r = ffi.new("double[3]"), ffi.new("double[9]")
        self.domain._check(lib.dem_mesh_wall_get_pose(self.domain._d, [self.index], t, r))
        return np.array(list(t)), np.array(list(r)).reshape(3, 3)

    @property
    def velocity(self) -> tuple[np.ndarray, np.ndarray]:
        v, w = ffi.new("double[3]"), ffi.new("double[3]")
        self.domain._check(lib.dem_mesh_wall_get_velocity(self.domain._d, [self.index], v, w))
        return np.array(list(v)), np.array(list(w))

    def force(self, point: Sequence[float] = (0.0, 0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
        """(force, torque about point) the particles exerted on the wall in the last step."""
        f, t = ffi.new("double[3]"), ffi.new("double[3]")
        self.domain._check(lib.dem_mesh_wall_force(self.domain._d, [self.index], ffi.new("double[3]", list(point)), f, t))
        return np.array(list(f)), np.array(list(t))

    def reset_mean_force(self) -> None:
        """Starts (or restarts) the time average of the wall force read by mean_force."""
        self.domain._check(lib.dem_mesh_wall_reset_mean_force(self.domain._d, [self.index]))

    def mean_force(self, point: Sequence[float] = (0.0, 0.0, 0.0)) -> tuple[np.ndarray, np.ndarray, float]:
        """(force, torque about point, seconds): the wall force averaged over every step since
        reset_mean_force, and the time averaged (0 with zero force when no step was taken)."""
        f, t, sec = ffi.new("double[3]"), ffi.new("double[3]"), ffi.new("double *")
        self.domain._check(lib.dem_mesh_wall_mean_force(self.domain._d, [self.index], ffi.new("double[3]", list(point)),
                                                        f, t, sec))
        return np.array(list(f)), np.array(list(t)), float(sec[0])

    def triangle_forces(self) -> np.ndarray:
        out = np.empty((self.info()["triangle_count"], 3))
        self.domain._check(lib.dem_mesh_wall_triangle_forces(self.domain._d, [self.index], c_pointer(out, "double[]"), len(out)))
        return out

    def stress(self, normal: Sequence[float], area: float) -> tuple[float, float]:
        """(normal stress, shear stress) of the wall force over `area` (Pa)."""
        sn, tau = ffi.new("double *"), ffi.new("double *")
        self.domain._check(lib.dem_mesh_wall_stress(self.domain._d, [self.index], ffi.new("double[3]", list(normal)),
                                                    float(area), sn, tau))
        return sn[0], tau[0]
