"""Wedge hopper at the tiny preset: fills, discharges completely, NRRP falls from 1 to 0,
frames carry their labels, Table 1 cases load by name, the Beverloo fit recovers known C, k."""
import csv
import math

import numpy as np
import pytest

from pydem.rigs import TABLE1, Hopper, HopperConfig, beverloo_fit, load
from pydem.rigs.hopper import mass_flow_rate, species_counts


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    frames = tmp_path_factory.mktemp("frames")
    return Hopper(load(HopperConfig, "tiny")).run(seed=2, frames_dir=frames), frames


def test_discharges_completely(tiny):
    res, _ = tiny
    assert res.info["emptied"]
    nrrp = res.series["nrrp"]
    assert nrrp[0] == 1.0 and nrrp[-1] == 0.0
    assert np.all(np.diff(nrrp) <= 0)  # particles only leave
    t = res.metrics["discharge_time"].value
    w = res.metrics["mass_flow_rate"]
    assert 0.05 < t < 5.0 and w.value > 0 and w.uncertainty < 0.1 * w.value
    # mass balance: the steady rate times the discharge time is about the initial mass
    m0 = res.series["remaining_mass"][0]
    assert 0.6 < w.value * t / m0 < 1.6


def test_frames_are_labelled(tiny):
    res, frames = tiny
    rows = list(csv.DictReader(open(frames / "index.csv")))
    assert len(rows) == len(res.frames) >= 3
    t_dis = res.metrics["discharge_time"].value
    for row in rows:
        assert (frames / row["file"]).exists()
        assert float(row["remaining_discharge_time_s"]) == pytest.approx(t_dis - float(row["time_s"]), abs=1e-4)
        assert 0.0 <= float(row["nrrp"]) <= 1.0
    assert float(rows[0]["nrrp"]) == 1.0


def test_table1_cases_by_name():
    assert len(TABLE1) == 25
    cfg = load(HopperConfig, "default", overrides=["case=A-4", "friction=0.25"])
    assert cfg.particles == 14700 and cfg.packing == "A" and cfg.fine_fraction == 0.8
    assert cfg.d_small == 3e-3 and cfg.d_large == 9e-3 and cfg.params.youngs_modulus == 1e7
    assert cfg.params.friction == 0.25  # set after the case: overrides it
    assert load(HopperConfig, "paper").case == "B1-1"
    n_fine, n_coarse = species_counts(14700, 3e-3, 9e-3, 0.8)
    phi = n_fine * 27 ** -1 / (n_fine * 27 ** -1 + n_coarse)
    assert phi == pytest.approx(0.8, abs=1e-3)


def test_layered_packings_order():
    h = Hopper(load(HopperConfig, "tiny", overrides=["packing=B3"]))
    order = h._filling_order(np.random.default_rng(0), 10, 4)
    assert list(order) == [True] * 5 + [False] * 4 + [True] * 5


def test_size_spread_widens_each_species_and_leaves_two_sizes_alone():
    """size_spread s: each species' diameters uniform in d (1 +- s) (mean d, the bounds exact);
    at 0 no random draw is taken, so every run of the two-size hopper stays bitwise as it was."""
    plain = Hopper(load(HopperConfig, "default"))
    rng = np.random.default_rng(5)
    fine, diam = plain._pouring_order(rng)
    assert set(diam[fine]) == {6e-3} and set(diam[~fine]) == {9e-3}
    ref = np.random.default_rng(5)
    Hopper(load(HopperConfig, "default"))._filling_order(ref, int(fine.sum()), int((~fine).sum()))
    assert np.random.default_rng(5).bit_generator.state != ref.bit_generator.state
    assert rng.bit_generator.state == ref.bit_generator.state  # the order's draws and nothing else
    wide = Hopper(load(HopperConfig, "default", overrides=["size_spread=0.4"]))
    fine, diam = wide._pouring_order(np.random.default_rng(5))
    for d0, sel in ((6e-3, fine), (9e-3, ~fine)):
        rel = diam[sel] / d0 - 1.0
        assert rel.min() >= -0.4 and rel.max() <= 0.4 and rel.max() - rel.min() > 0.7  # fills the band
        assert abs(rel.mean()) < 4 * 0.4 / math.sqrt(3 * sel.sum())  # uniform: mean d within 4 sd
    assert wide.config.largest == pytest.approx(9e-3 * 1.4)


def test_beverloo_fit_recovers_constants():
    C, k, rho, L, d = 1.0, 1.5, 1500.0, 0.04, 0.006
    b = np.array([0.03, 0.04, 0.05, 0.06, 0.08])
    w = C * rho * math.sqrt(9.81) * L * (b - k * d) ** 1.5
    fit = beverloo_fit(b, w, d, rho, L)
    assert fit["C"] == pytest.approx(C, rel=1e-9) and fit["k"] == pytest.approx(k, rel=1e-9)
    t = np.linspace(0, 1, 50)
    assert mass_flow_rate(t, 2.0 - 1.5 * t)[0] == pytest.approx(1.5)


def test_monodisperse_fill_in_several_batches():
    """One size only, more spheres than one pouring batch holds: batches must not overlap."""
    res = Hopper(load(HopperConfig, "tiny", overrides=["fine_fraction=0", "particles=400"])).run(seed=4)
    assert res.info["particles"] == 400 and res.info["emptied"]
