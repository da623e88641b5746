"""Rig geometry as triangle meshes (vertices (n, 3), triangles (m, 3)), written as STL by the
project itself so every run is reproducible from its own files. Lengths in metres."""
from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

Mesh = tuple[np.ndarray, np.ndarray]


def write_stl(path: str | Path, mesh: Mesh, name: str = "pydem") -> Path:
    """Binary STL (little endian, float32, facet normals from the vertex order)."""
    v, t = np.asarray(mesh[0], dtype=np.float64), np.asarray(mesh[1], dtype=np.int64)
    a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    n = np.cross(b - a, c - a)
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    rec = np.zeros(len(t), dtype=[("n", "<f4", 3), ("v", "<f4", 9), ("attr", "<u2")])
    rec["n"], rec["v"] = n, np.hstack([a, b, c])
    path = Path(path)
    with open(path, "wb") as f:
        f.write(name.encode()[:80].ljust(80, b" ") + struct.pack("<I", len(t)) + rec.tobytes())
    return path


def _merge(*meshes: Mesh) -> Mesh:
    vs, ts, off = [], [], 0
    for v, t in meshes:
        vs.append(v)
        ts.append(t + off)
        off += len(v)
    return np.vstack(vs), np.vstack(ts)


def _grid(corner, du, dv, nu: int, nv: int) -> Mesh:
    """A parallelogram corner + s du + t dv split into nu x nv squares, two triangles each."""
    s, t = np.meshgrid(np.linspace(0, 1, nu + 1), np.linspace(0, 1, nv + 1))
    v = np.asarray(corner) + s.reshape(-1, 1) * np.asarray(du) + t.reshape(-1, 1) * np.asarray(dv)
    i = np.arange(nu)[None, :] + (nu + 1) * np.arange(nv)[:, None]
    a, b, c, d = i, i + 1, i + nu + 1, i + nu + 2
    tri = np.stack([np.stack([a, b, d], -1), np.stack([a, d, c], -1)], axis=2).reshape(-1, 3)
    return v, tri


def rectangle(corner, du, dv, nu: int = 1, nv: int = 1) -> Mesh:
    return _grid(corner, du, dv, nu, nv)


def _stacked_loops(loops: list[np.ndarray]) -> Mesh:
    """Triangulates the band between consecutive closed loops of equally many vertices."""
    segments = len(loops[0])
    tri = []
    for r in range(len(loops) - 1):
        for s in range(segments):
            a, b = r * segments + s, r * segments + (s + 1) % segments
            tri += [[a, b, b + segments], [a, b + segments, a + segments]]
    return np.vstack(loops), np.array(tri)


def _circle(radius: float, z: float, centre, segments: int) -> np.ndarray:
    ang = np.linspace(0, 2 * np.pi, segments + 1)[:-1]
    return np.column_stack([centre[0] + radius * np.cos(ang), centre[1] + radius * np.sin(ang), np.full(segments, z)])


def cylinder(radius: float, z0: float, z1: float, centre=(0.0, 0.0), segments: int = 48, rows: int = 1) -> Mesh:
    """Open cylinder (side wall only) about the vertical axis through centre."""
    return _stacked_loops([_circle(radius, z, centre, segments) for z in np.linspace(z0, z1, rows + 1)])


def annulus(r_inner: float, r_outer: float, z: float, centre=(0.0, 0.0), segments: int = 48, rings: int = 1) -> Mesh:
    """Flat ring at height z."""
    return _stacked_loops([_circle(r, z, centre, segments) for r in np.linspace(r_inner, r_outer, rings + 1)])


def disk(radius: float, z: float, centre=(0.0, 0.0), segments: int = 48) -> Mesh:
    v = np.vstack([[centre[0], centre[1], z], _circle(radius, z, centre, segments)])
    tri = np.array([[0, 1 + s, 1 + (s + 1) % segments] for s in range(segments)])
    return v, tri


def radial_bars(r_inner: float, r_outer: float, z0: float, z1: float, count: int, thickness: float,
                centre=(0.0, 0.0), phase: float = 0.0) -> Mesh:
    """`count` thin radial plates (bars) standing between z0 and z1, evenly spaced in angle."""
    meshes = []
    for k in range(count):
        a = phase + 2 * np.pi * k / count
        e, n = np.array([np.cos(a), np.sin(a), 0.0]), np.array([-np.sin(a), np.cos(a), 0.0])
        c = np.array([centre[0], centre[1], 0.0])
        for side in (-0.5, 0.5):  # the two faces of the bar
            corner = c + e * r_inner + n * side * thickness + np.array([0, 0, z0])
            meshes.append(rectangle(corner, e * (r_outer - r_inner), [0, 0, z1 - z0]))
        top = c + e * r_inner - n * 0.5 * thickness + np.array([0, 0, z1])
        meshes.append(rectangle(top, e * (r_outer - r_inner), n * thickness))
    return _merge(*meshes)


def merge(*meshes: Mesh) -> Mesh:
    return _merge(*meshes)
