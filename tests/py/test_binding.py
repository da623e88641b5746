"""The cffi binding: generated from the headers, objects own their C memory, numpy round
trips, every C status becomes an exception with the C message, and one physics check."""
import re
from pathlib import Path

import numpy as np
import pytest

import pydem
from pydem._libdem import lib

ROOT = Path(__file__).resolve().parents[2]


def test_every_header_function_is_bound():
    names = set()
    for h in (ROOT / "include" / "dem").glob("*.h"):
        names |= set(re.findall(r"DEM_API\s+[^;(]*?\b(dem_\w+)\s*\(", h.read_text()))
    assert len(names) > 60
    missing = sorted(n for n in names if not hasattr(lib, n))
    assert not missing, missing


def test_version_matches():
    assert pydem.LIBDEM_VERSION.split(".")[:2] == pydem.__version__.split(".")[:2]


def _box(n=0, **kw):
    d = pydem.Domain(hi=(0.01, 0.01, 0.01), gravity=(0, 0, 0), **kw)
    m = d.add_material()
    d.set_pair(m, m)
    if n:
        g = (np.arange(n)[:, None] * [1.0, 0.0, 0.0]) * 2.5e-3 + 1.5e-3
        d.add_particles(g, 1e-3, m)
    return d, m


def test_numpy_round_trip_and_id_order():
    d, m = _box()
    rng = np.random.default_rng(1)
    pos = np.column_stack([np.linspace(0.001, 0.009, 4), np.full(4, 0.005), np.full(4, 0.005)])
    vel = rng.normal(size=(4, 3))
    ids = d.add_particles(pos, [1e-3, 0.9e-3, 0.8e-3, 0.7e-3], m, velocities=vel)
    assert ids.dtype == np.int64 and list(ids) == [0, 1, 2, 3]
    np.testing.assert_array_equal(d.positions, pos)
    np.testing.assert_array_equal(d.velocities, vel)
    np.testing.assert_array_equal(d.radii, [1e-3, 0.9e-3, 0.8e-3, 0.7e-3])
    d.remove_particles([1])
    assert list(d.ids) == [0, 2, 3] and len(d) == 3
    np.testing.assert_array_equal(d.positions, pos[[0, 2, 3]])
    # non-contiguous and integer inputs are converted
    w = np.zeros((3, 6))[:, ::2]
    d.angular_velocities = w + 1
    np.testing.assert_array_equal(d.angular_velocities, np.ones((3, 3)))


def test_errors_carry_the_c_message():
    d, m = _box(1)
    with pytest.raises(pydem.DemOverlapError, match="overlaps existing particle id 0"):
        d.add_particles([[0.0015, 0.0015, 0.0015]], 1e-3, m)
    with pytest.raises(pydem.DemInvalidArgument, match="radius must be finite and > 0"):
        d.add_particles([[0.005, 0.005, 0.005]], -1.0, m)
    with pytest.raises(pydem.DemUnknownError, match="unknown material 7"):
        d.add_particles([[0.005, 0.005, 0.005]], 1e-3, 7)
    with pytest.raises(pydem.DemInvalidArgument, match="shape"):
        d.add_particles(np.zeros((2, 2)), 1e-3, m)
    with pytest.raises(pydem.DemInvalidArgument, match="dt"):
        pydem.Domain(dt=-1.0)
    with pytest.raises(pydem.DemIOError, match="cannot open"):
        d.add_mesh_wall("/nonexistent.stl")
    with pytest.raises(pydem.DemFormatError, match="empty file"):
        d.add_mesh_wall(ROOT / "tests/data/stl_corpus/empty.stl")
    with pytest.raises(pydem.DemFormatError, match="not an HDF5 file"):
        pydem.Domain.from_snapshot(ROOT / "tests/data/stl_corpus/seed_ascii_cube.stl")
    with pytest.raises(pydem.DemRunError, match="Rayleigh"):
        d.dt = 1.0
        d.step(1)
    with pytest.raises(pydem.DemUnknownError, match="no effect named"):
        d.set_effect(m, m, "magic", 1.0)
    # the domain still works after all that
    d.dt = 1e-6
    d.step(2)


def test_lifetime_many_domains_and_children():
    """Thousands of domains with walls: freed with their objects; a wall keeps its domain."""
    import resource
    def churn(k):
        for _ in range(k):
            d, m = _box(3)
            mw = d.add_mesh_wall((np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.0]]) * 1e-3, [[0, 1, 2]]), material=m)
            d.step(2)
        return mw
    churn(300)
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    wall = churn(3000)
    after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    assert after - before < 20_000, (before, after)  # kB: no growth with the count
    del churn
    assert wall.info()["triangle_count"] == 1  # its domain is still alive through the wall
    wall.domain.step(1)


def test_hertz_impact_through_python():
    """Elastic frictionless sphere on a plane: peak force and contact time against the
    closed forms (DESIGN section 3), dt = t_c / 2000 -> tolerance 2e-3."""
    R, rho, E, nu, v = 1e-3, 2500.0, 1e8, 0.25, 0.2
    m = rho * 4 / 3 * np.pi * R**3
    es = E / (2 * (1 - nu**2))
    dmax = (15 * m * v**2 / (16 * es * np.sqrt(R))) ** 0.4
    fmax, tc = 4 / 3 * es * np.sqrt(R) * dmax**1.5, 2.94328 * dmax / v
    dt = tc / 2000
    d = pydem.Domain(hi=(0.01, 0.01, 0.01), gravity=(0, 0, 0), dt=dt)
    mat = d.add_material(youngs_modulus=E, poisson_ratio=nu, density=rho)
    d.set_pair(mat, mat, restitution=1.0, friction=0.0)
    d.add_plane_wall(material=mat)
    d.add_particles([[0.005, 0.005, R + 1e-7]], R, mat, velocities=[[0, 0, -v]])
    peak, steps, touching = 0.0, 0, False
    for _ in range(10000):
        d.step(1)
        fz = d.forces[0, 2]
        if fz > 0:
            touching, steps, peak = True, steps + 1, max(peak, fz)
        elif touching:
            break
    assert abs(peak - fmax) / fmax < 2e-3
    assert abs(steps * dt - tc) / tc < 2e-3
    assert d.velocities[0, 2] == pytest.approx(v, rel=2e-3)  # elastic: rebounds at v


def test_plane_wall_mean_force_is_the_impulse_of_an_impact():
    """A sphere bounces off a plane (no gravity, e = 0.5): the wall's time-averaged force times
    the time averaged is the momentum the sphere lost, m (v_in + v_out) (impulse-momentum; to
    rounding), and the rebound speed is e v. The damping factor that delivers e falls as e
    rises and vanishes at e = 1."""
    R, rho, E, nu, v, e = 1e-3, 2500.0, 1e8, 0.25, 0.2, 0.5
    m = rho * 4 / 3 * np.pi * R**3
    d = pydem.Domain(hi=(0.01, 0.01, 0.01), gravity=(0, 0, 0), dt=1e-7)
    mat = d.add_material(youngs_modulus=E, poisson_ratio=nu, density=rho)
    d.set_pair(mat, mat, restitution=e, friction=0.0)
    floor = d.add_plane_wall(material=mat)
    d.add_particles([[0.005, 0.005, R + 1e-7]], R, mat, velocities=[[0, 0, -v]])
    floor.reset_mean_force()
    d.step(3000)  # the contact lasts ~1300 steps
    f, seconds = floor.mean_force()
    v_out = d.velocities[0, 2]
    assert seconds == pytest.approx(3000 * 1e-7, rel=1e-12)
    assert v_out == pytest.approx(e * v, rel=5e-3)
    assert -f[2] * seconds == pytest.approx(m * (v + v_out), rel=1e-9)
    factors = []
    for r in (0.2, 0.5, 0.9, 1.0):
        d.set_pair(mat, mat, restitution=r)
        factors.append(d.pair_damping_factor(mat, mat))
    assert factors[0] > factors[1] > factors[2] > 0.0 and factors[3] == 0.0


def test_snapshot_and_render_round_trip(tmp_path):
    d, m = _box(3)
    d.velocities = [[0.01, 0, 0]] * 3
    d.step(100)
    d.write_snapshot(tmp_path / "s.h5")
    e = pydem.Domain.from_snapshot(tmp_path / "s.h5")
    d.step(50)
    e.step(50)
    assert d.state_hash() == e.state_hash()
    img = d.render(width=64, height=32, color="scalar", scalar=[0.0, 0.5, 1.0])
    assert img.shape == (32, 64, 3) and (img != 255).any()
    d.render_png(tmp_path / "f.png")
    assert (tmp_path / "f.png").read_bytes()[1:4] == b"PNG"


def test_integer_arrays_refuse_fractions():
    """A triangle index 2.5 is an error naming the array, never silently truncated to 2."""
    import numpy as np
    import pytest
    d = pydem.Domain(hi=(1, 1, 1))
    m = d.add_material()
    verts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.0]])
    with pytest.raises(pydem.DemInvalidArgument, match=r"triangles must be whole numbers, got \[2.5\]"):
        d.add_mesh_wall((verts, np.array([[0, 1, 2.5]])), material=m)
    d.add_mesh_wall((verts, np.array([[0, 1, 2.0]])), material=m)  # whole floats are fine


def test_python_defaults_are_libdem_s():
    """pydem keeps no defaults of its own: every optional argument is None and takes libdem's
    dem_default_*_def value (one owner per default)."""
    import inspect
    from pydem import _lib
    for fn in (pydem.Domain.__init__, pydem.Domain.add_material, pydem.Domain.set_pair, pydem.Domain.add_plane_wall):
        for name, prm in inspect.signature(fn).parameters.items():
            if name not in ("self", "a", "b", "_ptr"):
                assert prm.default is None, (fn.__name__, name)
    d = pydem.Domain()
    c = _lib.dem_default_domain_def()
    s = d.settings
    assert (s["dt"], s["skin"], s["num_threads"], s["max_overlap_ratio"]) == (c.dt, c.skin, c.num_threads, c.max_overlap_ratio)
    assert s["gravity"] == tuple(c.gravity) and s["lo"] == tuple(c.lo) and s["hi"] == tuple(c.hi)
    m = d.add_material()
    d.set_pair(m, m)
    p, cp = d.get_pair(m, m), _lib.dem_default_pair_def()
    assert (p["restitution"], p["friction"], p["rolling_friction"]) == (cp.restitution, cp.friction, cp.rolling_friction)
    w = d.add_plane_wall()
    # the default wall is the floor z >= 0: a sphere pressed 1 um into it (the default insertion
    # tolerance allows 1e-3 of its radius) pushes it down
    d.add_particles(np.array([[0.05, 0.05, 0.002 - 1e-6]]), 0.002, m)
    d.step(0)
    assert w.force[2] < 0


def _tangential_frequency(shear_modulus):
    """A sphere resting on a plane under gravity (no damping, sticking friction), pushed
    sideways: its contact point oscillates at omega = sqrt(k_t (1/m + R^2/I)) = sqrt(3.5 k_t / m)
    with k_t = 8 G* sqrt(R delta), delta the Hertz overlap of its weight. Returns (measured
    omega, closed-form omega)."""
    R, rho, E, nu, g = 1e-3, 2500.0, 1e7, 0.3, 9.81
    m = rho * 4 / 3 * np.pi * R**3
    G = shear_modulus or E / (2 * (1 + nu))
    e_star, g_star = E / (2 * (1 - nu**2)), G / (2 * (2 - nu))
    delta = (m * g / (4 / 3 * e_star * np.sqrt(R))) ** (2 / 3)
    omega = np.sqrt(3.5 * 8 * g_star * np.sqrt(R * delta) / m)
    dt = 2 * np.pi / omega / 400
    d = pydem.Domain(hi=(0.01, 0.01, 0.01), gravity=(0, 0, -g), dt=dt)
    mat = d.add_material(youngs_modulus=E, poisson_ratio=nu, density=rho, shear_modulus=shear_modulus)
    d.set_pair(mat, mat, restitution=1.0, friction=1.0, rolling_friction=0.0)
    d.add_plane_wall(material=mat)
    d.add_particles([[0.005, 0.005, R - delta]], R, mat, velocities=[[1e-4, 0, 0]])  # at rest on its overlap
    vx = []
    for _ in range(2000):  # five periods
        d.step(1)
        vx.append(d.velocities[0, 0])
    v = np.array(vx) - np.mean(vx)  # the oscillation about the rolling mean
    up = np.flatnonzero((v[:-1] < 0) & (v[1:] >= 0))
    t = (up + v[up] / (v[up] - v[up + 1])) * dt  # crossings, interpolated
    return 2 * np.pi / np.mean(np.diff(t)), omega


def test_shear_modulus_apart_from_e_and_nu_sets_the_tangential_stiffness():
    """The tangential oscillation of a resting sphere against its closed form (1 %: a period
    sampled at 400 steps, and the normal overlap rattles slightly about its static value), for the
    isotropic G and a G three times it; a bad shear modulus is refused by name."""
    measured, expected = _tangential_frequency(None)
    assert measured == pytest.approx(expected, rel=1e-2)
    G3 = 3 * 1e7 / (2 * 1.3)
    stiff, expected3 = _tangential_frequency(G3)
    assert stiff == pytest.approx(expected3, rel=1e-2) and stiff / measured == pytest.approx(np.sqrt(3), rel=1e-2)
    with pytest.raises(pydem.DemInvalidArgument, match="shear modulus"):
        pydem.Domain().add_material(shear_modulus=-1.0)


def test_openmp_threads_spin_briefly_unless_the_user_chose():
    """pydem asks libgomp for a short spin at barriers before libdem loads it (a small rig on
    2 threads ran slower than on 1 with passive waiting, studies/JOURNAL.md); a user's own choice
    wins."""
    import os
    import subprocess
    import sys
    code = "import os, pydem; print(os.environ.get('OMP_WAIT_POLICY'), os.environ.get('GOMP_SPINCOUNT'))"
    env = {k: v for k, v in os.environ.items() if k not in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT")}
    run = lambda extra: subprocess.run([sys.executable, "-c", code], env=env | extra, capture_output=True,  # noqa: E731
                                       text=True, check=True).stdout.strip()
    assert run({}) == "None 10000"
    assert run({"OMP_WAIT_POLICY": "passive"}) == "passive None"
    assert run({"GOMP_SPINCOUNT": "300"}) == "None 300"


def test_fewer_threads_give_the_same_run():
    """The thread governor may run steps on fewer threads than asked; results do not depend on
    it: a settling column on 2 adaptive threads, on 2 fixed threads and on 1 thread, bitwise."""
    def column(threads, adaptive):
        d = pydem.Domain(lo=(0, 0, 0), hi=(0.02, 0.02, 0.06), num_threads=threads)
        d.set_adaptive_threads(adaptive)
        mat = d.add_material()
        for axis, side, pos in ((0, 1, 0.0), (0, -1, 0.02), (1, 1, 0.0), (1, -1, 0.02), (2, 1, 0.0)):
            d.add_plane_wall(axis=axis, side=side, position=pos)
        g = np.stack(np.meshgrid(*(np.arange(8),) * 2, np.arange(12), indexing="ij"), -1).reshape(-1, 3)
        d.add_particles(1.2e-3 + 2.4e-3 * g, np.full(len(g), 1e-3), np.full(len(g), mat))
        d.step(2000)
        return d.state_hash(), d.profile()
    (h1, _), (h2, p2), (h3, p3) = column(1, True), column(2, True), column(2, False)
    assert h1 == h2 == h3
    assert p3["steps_fewer_threads"] == 0 and 0 <= p2["steps_fewer_threads"] <= p2["steps"]
