"""Size distributions given as a table (sieve sizes, cumulative mass fraction passing): the
spheres' mass distribution is the table's — checked on 400,000 draws at the sieve sizes and
between them (linear in the table: mass uniform in d within a cut), to 0.005 (the sampling
error of a mass fraction from ~1e5 spheres per cut is ~0.002) — bad tables are refused, and a
rig run fills with spheres from the table."""
import numpy as np
import pytest

from pydem.rigs import RIGS, ConfigError, load
from pydem.rigs.common import diameters_from_table


def mass_passing(d, at):
    o = np.argsort(d)
    cum = np.cumsum(d[o] ** 3) / np.sum(d ** 3)
    return np.interp(at, d[o], cum)


def test_mass_distribution_is_the_table_s():
    sizes, passing = [1e-3, 1.6e-3, 2.5e-3, 4e-3], [0.0, 0.1, 0.55, 1.0]
    d = diameters_from_table(np.random.default_rng(0), 400_000, sizes, passing)
    assert d.min() >= 1e-3 and d.max() <= 4e-3
    probe = [1.6e-3, 2.5e-3, 1.3e-3, 2.05e-3, 3.25e-3]  # sieve sizes, then mid-cut (linear)
    want = [0.1, 0.55, 0.05, 0.325, 0.775]
    assert np.allclose(mass_passing(d, probe), want, atol=0.005)


@pytest.mark.parametrize("sizes,passing,message", [
    ([1e-3], [1.0], "at least 2"),
    ([1e-3, 2e-3], [0.0, 0.5, 1.0], "same number"),
    ([2e-3, 1e-3], [0.0, 1.0], "increasing"),
    ([1e-3, 2e-3], [0.1, 1.0], "rise from 0"),
    ([1e-3, 2e-3, 3e-3], [0.0, 0.6, 0.5], "rise from 0"),
])
def test_bad_tables_are_refused(sizes, passing, message):
    with pytest.raises(ConfigError, match=message):
        diameters_from_table(np.random.default_rng(0), 10, sizes, passing)


def test_a_rig_fills_from_the_table(tmp_path):
    import meshio
    cls, cfg_cls = RIGS["aor"]
    cfg = load(cfg_cls, "tiny", None, ["particles=150", "max_time=0.12", "frame_interval=1", "psd_sizes=[2e-3,4e-3]",
                                       "psd_passing=[0,1]", "diameter=3e-3"])
    cls(cfg).run(seed=1, vtk_dir=tmp_path)
    r = meshio.read(tmp_path / "particles_00000.vtu").point_data["radius"]
    assert len(r) == 150 and r.min() >= 1e-3 and r.max() <= 2e-3 and r.max() - r.min() > 0.5e-3


def test_the_hopper_fills_from_the_table_and_refuses_layers():
    cls, cfg_cls = RIGS["hopper"]
    table = ["psd_sizes=[3e-3,4e-3,6e-3]", "psd_passing=[0,0.3,1]", "max_time=0.1", "settle_time=0.0"]
    res = cls(load(cfg_cls, "tiny", None, table)).run(seed=2)
    assert res.info["particles"] == 250 and res.info["fine"] + res.info["coarse"] == 250
    with pytest.raises(ValueError, match="packing A"):
        cls(load(cfg_cls, "tiny", None, table + ["packing=B1"])).run(seed=2)
