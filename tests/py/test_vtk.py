"""VTK output read back with meshio (an independent reader from PyPI): every particle field and
the mesh wall's triangles and forces exactly as the domain holds them (17 significant digits:
an exact round trip), Newton's third law between the triangles' forces and the wall's total,
the .pvd series, the `pydem rig --vtk` option, and errors that name the problem."""
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import meshio
import numpy as np
import pytest

import pydem
from pydem.vtk import VtkSeries

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def box():
    """Spheres dropped into the shipped 40 mm STL box, stepped until they press on its floor."""
    d = pydem.Domain(lo=(-0.005, -0.005, -0.005), hi=(0.045, 0.045, 0.065), dt=2e-6)
    glass = d.add_material(youngs_modulus=5e6)
    steel = d.add_material(youngs_modulus=5e6)
    d.set_pair(glass, glass, 0.5, 0.5, 0.0)
    d.set_pair(glass, steel, 0.5, 0.5, 0.0)
    wall = d.add_mesh_wall(str(ROOT / "data/geometry/open_box_40mm.stl"), material=steel, scale=1e-3)  # mm
    g = np.stack(np.meshgrid(*[np.linspace(0.008, 0.032, 4)] * 2, indexing="ij"), -1).reshape(-1, 2)
    pos = np.column_stack([g, np.full(len(g), 0.004)])
    pos = np.vstack([pos, pos + [0.002, 0.0, 0.006]])
    d.add_particles(pos, 0.0025, glass, angular_velocities=np.tile([0.0, 3.0, 0.0], (len(pos), 1)))
    d.step(20000)  # 40 ms: the lower layer lands (1.5 mm gap), the upper one lands on it
    return d, wall


def by_id(ids, *arrays):
    order = np.argsort(ids)
    return [a[order] for a in arrays]


def test_particles_and_mesh_round_trip_exactly(box, tmp_path):
    d, wall = box
    d.write_vtk(tmp_path / "p.vtu")
    d.write_mesh_vtk(wall.index, tmp_path / "w.vtu")
    m = meshio.read(tmp_path / "p.vtu")
    assert m.cells[0].type == "vertex" and len(m.points) == len(d)
    got = by_id(m.point_data["id"], m.points, m.point_data["radius"], m.point_data["velocity"],
                m.point_data["angular_velocity"], m.point_data["force"], m.point_data["material"])
    want = by_id(d.ids, d.positions, d.radii, d.velocities, d.angular_velocities, d.forces, np.zeros(len(d)))
    for name, a, b in zip(("position", "radius", "velocity", "angular velocity", "force"), got[:5], want[:5]):
        assert np.array_equal(a, b), name  # %.17g: every double comes back bit for bit
    assert np.abs(want[4]).max() > 0  # the spheres do press on each other and on the floor
    assert m.field_data["TIME"][0] == d.time
    w = meshio.read(tmp_path / "w.vtu")
    assert w.cells[0].type == "triangle"
    assert np.array_equal(w.points, wall.vertices) and np.array_equal(w.cells[0].data, wall.triangles)
    # the force on each triangle sums to the wall's total force (the particles' push on it)
    total, _ = wall.force()
    assert np.allclose(w.cell_data["force"][0].sum(axis=0), total, rtol=1e-12, atol=1e-15)
    assert total[2] < 0  # the spheres rest on the floor: they push it down


def test_series_collection_lists_every_step_in_order(box, tmp_path):
    d, _ = box
    s = VtkSeries(tmp_path / "vtk")
    times = []
    for _ in range(3):
        s.write(d)
        times.append(d.time)
        d.step(50)
    for name in ("particles", "mesh0"):
        root = ET.parse(tmp_path / "vtk" / f"{name}.pvd").getroot()
        sets = root.findall("./Collection/DataSet")
        assert [float(e.get("timestep")) for e in sets] == times
        assert [e.get("file") for e in sets] == [f"{name}_{k:05d}.vtu" for k in range(3)]
        assert all((tmp_path / "vtk" / e.get("file")).exists() for e in sets)


def test_rig_writes_a_series_paraview_opens(tmp_path):
    r = subprocess.run([sys.executable, "-m", "pydem", "rig", "aor", "--preset", "tiny", "--set", "particles=150",
                        "--set", "max_time=0.3", "--set", "frame_interval=0.1", "--vtk", str(tmp_path / "vtk"), "--quiet"],
                       cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    files = sorted((tmp_path / "vtk").glob("particles_*.vtu"))
    assert len(files) >= 2
    first = meshio.read(files[0])
    assert len(first.points) == 150 and np.all(first.point_data["radius"] > 0)
    assert sorted((tmp_path / "vtk").glob("mesh*.pvd"))  # the cylinder and the base at every frame


def test_errors_name_the_problem(box, tmp_path):
    d, _ = box
    with pytest.raises(pydem.DemIOError, match="cannot write '/nonexistent/dir/p.vtu'"):
        d.write_vtk("/nonexistent/dir/p.vtu")
    with pytest.raises(pydem.DemError, match="no mesh wall 7"):
        d.write_mesh_vtk(7, tmp_path / "w.vtu")
