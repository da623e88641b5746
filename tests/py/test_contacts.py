"""The contact list (dem_contacts_get, Domain.contacts): spheres settling in an STL box against
a plane side wall — every contact's force summed per particle (+ on i, - on a partner j) equals the
particle's contact force, and per wall the wall's force (Newton's third law), to round-off
(the engine sums in another order: 1e-12 of the largest force); geometry consistent (unit
normals, overlap = radii - distance); a too-small buffer is an error that says how many."""
from pathlib import Path

import numpy as np
import pytest

import pydem
from pydem import _ffi, _lib

ROOT = Path(__file__).resolve().parents[2]


def test_contact_forces_add_up_to_particle_and_wall_forces():
    # gravity tilted towards +x: the spheres rest on the box's floor and lean on a plane side wall
    d = pydem.Domain(lo=(-0.005, -0.005, -0.005), hi=(0.045, 0.045, 0.065), dt=2e-6, gravity=(4.0, 0.0, -9.81))
    m = d.add_material(youngs_modulus=5e6)
    d.set_pair(m, m, 0.5, 0.5, 0.1)
    box = d.add_mesh_wall(str(ROOT / "data/geometry/open_box_40mm.stl"), material=m, scale=1e-3)
    plane = d.add_plane_wall(axis=0, side=-1, position=0.0365, material=m)  # x <= 36.5 mm
    g = np.stack(np.meshgrid(np.linspace(0.005, 0.033, 6), np.linspace(0.005, 0.035, 6), indexing="ij"), -1).reshape(-1, 2)
    pos = np.vstack([np.column_stack([g, np.full(len(g), z)]) for z in (0.005, 0.011, 0.017)])
    rng = np.random.default_rng(0)
    d.add_particles(pos + rng.uniform(-2e-4, 2e-4, pos.shape), rng.uniform(0.0022, 0.0026, len(pos)), m)
    d.step(20000)
    c = d.contacts()
    kinds = set(c["kind"].tolist())
    assert kinds == {0, 1, 2}, kinds  # pairs, the plane and the box's walls all in contact
    ids, forces = d.ids, d.forces
    row = {int(i): k for k, i in enumerate(ids)}
    total = np.zeros_like(forces)
    for i, j, f in zip(c["i"], c["j"], c["force"]):
        total[row[int(i)]] += f
        if j >= 0:
            total[row[int(j)]] -= f
    scale = np.abs(forces).max()
    assert np.allclose(total, forces, rtol=0, atol=1e-12 * scale)
    for kind, wall_force in ((1, plane.force), (2, box.force()[0])):
        assert np.allclose(-c["force"][c["kind"] == kind].sum(axis=0), wall_force, rtol=0, atol=1e-12 * scale)
    assert np.allclose(np.linalg.norm(c["normal"], axis=1), 1.0, atol=1e-12)
    pairs = c["kind"] == 0
    x = {int(i): p for i, p in zip(ids, d.positions)}
    r = {int(i): rr for i, rr in zip(ids, d.radii)}
    dist = np.array([np.linalg.norm(x[int(i)] - x[int(j)]) for i, j in zip(c["i"][pairs], c["j"][pairs])])
    want = np.array([r[int(i)] + r[int(j)] for i, j in zip(c["i"][pairs], c["j"][pairs])]) - dist
    assert np.allclose(c["overlap"][pairs], want, rtol=0, atol=1e-15) and np.all(want > 0)


def test_small_buffer_is_an_error_naming_the_count():
    d = pydem.Domain()
    m = d.add_material()
    d.add_plane_wall(material=m)
    d.add_particles(np.array([[0.02, 0.02, 0.002 - 1e-6], [0.05, 0.05, 0.002 - 1e-6]]), 0.002, m)
    n = _ffi.new("int64_t *")
    assert _lib.dem_contacts_get(d._d, _ffi.NULL, 0, n) == 0 and n[0] == 2
    one = _ffi.new("dem_contact[]", 1)
    assert _lib.dem_contacts_get(d._d, one, 1, n) == _lib.DEM_ERR_INVALID_ARGUMENT
    assert "2 contacts, room for 1" in _ffi.string(_lib.dem_domain_last_error(d._d)).decode()
    assert one[0].kind == 1 and one[0].j == -1  # the first one was written


def test_normal_tangential_split_and_the_sliding_flag():
    """A sphere pushed along the floor slides (its friction is at mu F_n: flagged); one at rest
    on the floor does not; the split adds back to the force."""
    d = pydem.Domain()
    m = d.add_material()
    d.set_pair(m, m, friction=0.4)
    d.add_plane_wall(material=m)
    z = 0.002 - 2e-6
    d.add_particles(np.array([[0.02, 0.05, z], [0.07, 0.05, z]]), 0.002, m,
                    velocities=np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 0.0]]))
    d.step(20)
    c = d.contacts()
    assert list(c["kind"]) == [1, 1]
    n, f = c["normal"], c["force"]
    assert np.allclose(c["normal_force"], np.sum(f * n, axis=1), rtol=1e-14)
    tang = f - c["normal_force"][:, None] * n
    assert np.allclose(c["tangential_force"], np.linalg.norm(tang, axis=1), rtol=1e-12, atol=1e-18)
    moving = int(np.flatnonzero(c["i"] == 0)[0])
    assert c["sliding"][moving] == 1 and c["tangential_force"][moving] == pytest.approx(0.4 * c["normal_force"][moving], rel=1e-9)
    assert c["sliding"][1 - moving] == 0
    assert np.all(c["tangential_force"] <= 0.4 * c["normal_force"] * (1 + 1e-9))
