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
    beyond the quadrant scatter; the default-scale sweep is bench/plausibility_aor.py."""
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
