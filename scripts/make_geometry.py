"""Writes the small shipped geometries in data/geometry (ASCII STL, millimetres).

    python3 scripts/make_geometry.py

open_box_40mm.stl: an open-topped box 40 x 40 x 60 mm (floor + four sides, two triangles a
face), corner at the origin; used by docs/libdem.md's C example.
"""
from pathlib import Path

OUT = Path(__file__).resolve().parent.parent / "data" / "geometry"


def quad(a, b, c, d):
    return [(a, b, c), (a, c, d)]


def open_box(w, h):
    p = lambda x, y, z: (x * w, y * w, z * h)
    tris = []
    tris += quad(p(0, 0, 0), p(0, 1, 0), p(1, 1, 0), p(1, 0, 0))  # floor
    tris += quad(p(0, 0, 0), p(1, 0, 0), p(1, 0, 1), p(0, 0, 1))  # y = 0
    tris += quad(p(0, 1, 0), p(0, 1, 1), p(1, 1, 1), p(1, 1, 0))  # y = w
    tris += quad(p(0, 0, 0), p(0, 0, 1), p(0, 1, 1), p(0, 1, 0))  # x = 0
    tris += quad(p(1, 0, 0), p(1, 1, 0), p(1, 1, 1), p(1, 0, 1))  # x = w
    return tris


def ascii_stl(name, tris):
    out = [f"solid {name}"]
    for t in tris:
        out += ["  facet normal 0 0 0", "    outer loop"]
        out += [f"      vertex {v[0]:g} {v[1]:g} {v[2]:g}" for v in t]
        out += ["    endloop", "  endfacet"]
    out.append(f"endsolid {name}")
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "open_box_40mm.stl").write_text(ascii_stl("open_box_40mm", open_box(40.0, 60.0)))
    print("wrote", OUT / "open_box_40mm.stl")
