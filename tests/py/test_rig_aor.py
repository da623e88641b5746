"""Static angle of repose at the tiny preset (seconds): the protocol runs to rest, the metrics
are plausible, the angle rises with rolling friction, configs and the command line work."""
import json
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

from pydem.rigs import AngleOfRepose, AorConfig, ConfigError, load
from pydem.rigs.aor import heap_angle

ROOT = Path(__file__).resolve().parents[2]


def test_heap_angle_estimator_on_a_cone():
    """Spheres on an ideal 30 degree cone surface: the estimator returns 30 (closed form)."""
    rng = np.random.default_rng(0)
    r = np.sqrt(rng.uniform(0, 0.05**2, 20000))
    a = rng.uniform(0, 2 * np.pi, r.size)
    z = (0.05 - r) * np.tan(np.radians(30.0))
    pos = np.column_stack([r * np.cos(a), r * np.sin(a), z])
    angle, se, n = heap_angle(pos, np.full(r.size, 1e-3), 2e-3)
    assert n == 4
    assert angle == pytest.approx(30.0, abs=0.3)


def test_a_standing_column_has_no_angle_and_a_steep_heap_has_one():
    """A column of the cylinder's radius (25 mm, 36 mm high) with a skirt of fallen spheres at its
    foot, as a cohesive fill stands after the lift: every quadrant is a standing face (the flank
    fit alone would find the skirt's few degrees). Cones at 30 and 60 deg: none (closed form:
    the surface falls from 80 % to 20 % over 0.6 h / tan(angle), 0.35 h at 60 deg against the
    0.22 h of a 70 deg face)."""
    from pydem.rigs.aor import standing_quadrants
    rng = np.random.default_rng(1)
    r = 0.025 * np.sqrt(rng.uniform(0, 1, 20000))
    z = rng.uniform(0, 0.036, r.size)
    rs = rng.uniform(0.025, 0.04, 600)  # the skirt: spheres lying on the base around the column
    a = rng.uniform(0, 2 * np.pi, r.size + rs.size)
    rr, zz = np.r_[r, rs], np.r_[z, rng.uniform(0, 0.004, rs.size)]
    column = np.column_stack([rr * np.cos(a), rr * np.sin(a), zz])
    assert standing_quadrants(column, np.full(len(rr), 1.5e-3), 3e-3) == 4
    for angle in (30.0, 60.0):
        r = np.sqrt(rng.uniform(0, 0.05 ** 2, 20000))
        a = rng.uniform(0, 2 * np.pi, r.size)
        cone = np.column_stack([r * np.cos(a), r * np.sin(a), (0.05 - r) * np.tan(np.radians(angle))])
        assert standing_quadrants(cone, np.full(r.size, 1e-3), 2e-3) == 0, angle
        assert heap_angle(cone, np.full(r.size, 1e-3), 2e-3)[0] == pytest.approx(angle, abs=0.5)


@pytest.fixture(scope="module")
def tiny_runs():
    out = {}
    for mu_r in (0.0, 0.6):
        cfg = load(AorConfig, "tiny", overrides=[f"rolling_friction={mu_r}"])
        out[mu_r] = AngleOfRepose(cfg).run(seed=3)
    return out


def test_tiny_run_is_plausible(tiny_runs):
    res = tiny_runs[0.6]
    assert res.info["at_rest"]
    a = res.metrics["angle_of_repose"]
    assert 10.0 < a.value < 50.0 and a.uncertainty > 0
    rho = res.metrics["bulk_density"].value
    assert 0.45 * 2500 < rho < 0.70 * 2500  # random packings of spheres
    assert res.info["particles_on_base"] > 0.9 * 600


def test_angle_rises_with_rolling_friction(tiny_runs):
    """At this scale (a heap a few spheres high on a rough base) only a large change shows
    beyond the quadrant scatter; the default-scale sweep is studies/plausibility.py aor."""
    low, high = tiny_runs[0.0].metrics["angle_of_repose"], tiny_runs[0.6].metrics["angle_of_repose"]
    assert high.value > low.value + 2 * np.hypot(high.uncertainty, low.uncertainty)


def test_config_toml_and_errors(tmp_path):
    toml = tmp_path / "aor.toml"
    toml.write_text('preset = "tiny"\nparticles = 123\n[params]\nfriction = 0.7\n'
                    '[effects.cohesion_sjkr]\ncohesion_energy_density = 5e4\n')
    cfg = load(AorConfig, "default", toml)
    assert cfg.particles == 123 and cfg.params.friction == 0.7
    assert cfg.params.effects == {"cohesion_sjkr": {"cohesion_energy_density": 5e4}}
    with pytest.raises(ConfigError, match=r"unknown key 'nope'"):
        load(AorConfig, "tiny", overrides=["nope=1"])
    with pytest.raises(ConfigError, match=r"restitution = 1.5 is out of range \[0.05, 1\]"):
        load(AorConfig, "tiny", overrides=["restitution=1.5"])
    with pytest.raises(ConfigError, match="expected a number"):
        load(AorConfig, "tiny", overrides=["particles=many"])
    with pytest.raises(ConfigError, match="unknown effect"):
        load(AorConfig, "tiny", overrides=["effects.glue.strength=1"])
    with pytest.raises(ConfigError, match="unknown preset 'cel': tiny, default or paper"):
        load(AorConfig, "cel")


def test_command_line(tmp_path):
    out = tmp_path / "r.h5"
    r = subprocess.run([sys.executable, "-m", "pydem", "rig", "aor", "--preset", "tiny", "--set", "particles=150",
                        "--out", str(out), "--frames", str(tmp_path / "frames"), "--quiet"],
                       capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert r.returncode == 0, r.stderr
    assert "angle_of_repose" in r.stdout
    with h5py.File(out) as f:
        assert f["metrics"].attrs["angle_of_repose_unit"] == "deg"
        assert json.loads(f.attrs["info"])["particles"] == 150
    assert len(list((tmp_path / "frames").glob("*.png"))) > 3
    bad = subprocess.run([sys.executable, "-m", "pydem", "rig", "aor", "--set", "lift_speed=-1"],
                         capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert bad.returncode == 2 and "lift_speed = -1 is out of range" in bad.stderr
