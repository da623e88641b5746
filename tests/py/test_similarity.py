"""A material's own particle density (calibration/similarity.py): its rows are compared with
stores made at another density by similarity — bulk densities and flow rates as solid
fractions, pre-shear stresses scaled — so a material 1.6x denser than the stores, said so in its
file, gives exactly the observations of the stores' material; the card comes back in the
material's terms. And the similarity itself, by DEM: the angle-of-repose rig at 4000 kg/m^3 with
the modulus scaled with it measures what it measures at 2500 kg/m^3."""
from pathlib import Path

import pytest

from pydem.calibration.setup import TINY_STORES, load_setup, observations_of
from pydem.calibration.similarity import MaterialProperties
from pydem.measurements import MeasurementError, load

ROOT = Path(__file__).resolve().parents[2]
HEADER = "material,test,quantity,value,uncertainty,unit,conditions,use,source\n"
ROWS = [("ring_shear", "mu_ie_ps", 0.62, 0.01, "preshear_stress={p}"), ("ring_shear", "bulk_density", 1400, 14,
        "preshear_stress={p}"), ("aor", "angle_of_repose", 31.0, 0.5, ""), ("aor", "bulk_density", 1350, 13, ""),
        ("hopper", "mass_flow_rate", 0.9, 0.02, ""), ("hopper", "discharge_time", 1.5, 0.05,
                                                                      "")]


def write(path: Path, k: float, density_row: str | None):
    from pydem.quantity_table import metric_spec
    lines = [HEADER]
    for test, q, v, u, cond in ROWS:
        s = k if metric_spec(q).scales_with_density else 1.0
        lines.append(f"m,{test},{q},{v * s:.10g},{u * s:.10g},,{cond.format(p=2000 * k)},calibrate,x\n")
    if density_row:
        lines.append(density_row)
    path.write_text("".join(lines))


@pytest.fixture(scope="module")
def tiny():
    return load_setup([ROOT / s for s in TINY_STORES], say=lambda *_: None)


def test_a_denser_material_said_so_gives_the_stores_observations(tiny, tmp_path):
    write(tmp_path / "stores.csv", 1.0, None)
    write(tmp_path / "dense.csv", 1.6, "m,material,particle_density,4.0,,g/cm^3,,,pycnometer\n")
    ref, _ = observations_of(load(tmp_path / "stores.csv", "m"), tiny, "stores", "m")
    rows = load(tmp_path / "dense.csv", "m")
    got, skipped = observations_of(rows, tiny, "dense", "m")
    assert len(got) == len(ref) == len(ROWS) and not skipped
    for a, b in zip(ref, got):
        assert b.value == pytest.approx(a.value, rel=1e-12) and b.uncertainty == pytest.approx(a.uncertainty, rel=1e-12)
        assert b.conditions == pytest.approx(a.conditions, rel=1e-12)
    s = tiny.scaling(MaterialProperties.from_rows(rows))
    assert s.factor == pytest.approx(2500 / 4000) and s.model_modulus == pytest.approx(5e6 * 1.6)
    assert s.cohesion_to_material(1e4) == pytest.approx(1.6e4)
    assert any("particle density 4000 kg/m^3" in n for n in s.notes())
    # without the row the same file is a different material, 1.6x too dense for the stores' model
    write(tmp_path / "unsaid.csv", 1.6, None)
    unsaid, _ = observations_of(load(tmp_path / "unsaid.csv", "m"), tiny, "unsaid", "m")
    assert unsaid[1].value == pytest.approx(1.6 * ref[1].value)


def test_material_rows_are_checked_like_any_row(tiny, tmp_path):
    write(tmp_path / "bad.csv", 1.0, "m,material,particle_density,0.05,,kg/m^3,,,x\n")
    with pytest.raises(MeasurementError, match="particle_density = 0.05 kg/m\\^3 is outside the physically possible"):
        load(tmp_path / "bad.csv", "m")
    write(tmp_path / "stiff.csv", 1.0, "m,material,youngs_modulus,70,,GPa,,,x\n")
    notes = tiny.scaling(MaterialProperties.from_rows(load(tmp_path / "stiff.csv", "m"))).notes()
    assert any("Young's modulus given 7e+10 Pa" in n and "unconfirmed" in n for n in notes), notes


SIEVE = "".join(f"m,material,sieve_retained,{w},,,sieve_mm={d},,jku_psd.csv\n" for d, w in
                (("6.3", 0.0857), ("5.6", 0.136285), ("3.55", 0.625096), ("2", 0.087021), ("1", 0.065898), ("pan", 0.0)))


def test_a_sieve_table_gives_the_mean_size_and_the_spread(tiny, tmp_path):
    """Seed 000's reduction of JKU's coarse coke sieve table (each class at its lower sieve size):
    mean 3.76 mm (generatorCompleteAOR's mean_diameter_mm = 3.76); the spread is the uniform
    distribution's of the same relative sd, sqrt(3) sd / mean = 0.620; it becomes the base model's
    size spread, held at the stores' widest (0.5) with a note."""
    (tmp_path / "s.csv").write_text(HEADER + "m,aor,angle_of_repose,40.9,0.5,deg,,calibrate,x\n" + SIEVE)
    mat = MaterialProperties.from_rows(load(tmp_path / "s.csv", "m"))
    assert mat.mean_diameter == pytest.approx(3.762e-3, rel=1e-3) and mat.spread == pytest.approx(0.620, abs=2e-3)
    s = tiny.scaling(mat)
    cands = {c.parameter: c for c in s.candidates(tiny.candidates, tiny.ranges)}
    assert cands["size_spread"].neutral_value({}) == tiny.ranges["size_spread"][1] == 0.5
    assert any("size spread 0.62 of the sieve table" in n and "the model's is 0.5" in n for n in s.notes(tiny.ranges))
    # a table that does not sum to 1, a size that disagrees with it, a class without its sieve: named
    (tmp_path / "b.csv").write_text(HEADER + SIEVE.replace("0.625096", "0.5"))
    with pytest.raises(MeasurementError, match="sieve table \\(lines 2-7\\) sums to 0.8749"):
        MaterialProperties.from_rows(load(tmp_path / "b.csv", "m"))
    (tmp_path / "d.csv").write_text(HEADER + SIEVE + "m,material,particle_diameter,5,,mm,,,x\n")
    with pytest.raises(MeasurementError, match="disagrees with the sieve table's mean 3.762 mm"):
        MaterialProperties.from_rows(load(tmp_path / "d.csv", "m"))
    (tmp_path / "n.csv").write_text(HEADER + "m,material,sieve_retained,1,,,,,x\n")
    with pytest.raises(MeasurementError, match="line 2: sieve_retained needs the class's lower sieve size"):
        MaterialProperties.from_rows(load(tmp_path / "n.csv", "m"))


def test_another_particle_size_scales_the_hopper_slot_and_flow_rate(tiny, tmp_path):
    """Coarse-graining: spheres twice the tiny hopper store's size in a slot of 2 b are the store's
    slot b (the same b/d), their flow rate the store's times 2^(3/2) (Beverloo, a slot of fixed
    length); a discharge time is left out (it depends on the fill's mass), and so is a bulk density
    (a cell a few spheres wide packs by the size); angles as they are."""
    ds = tiny.scaling(MaterialProperties()).store_diameters
    hopper_d = ds["hopper"]
    assert ds["aor"] == ds["ring-shear"] == 3e-3 and hopper_d == pytest.approx(0.3 * 4e-3 + 0.7 * 6e-3)
    b = 0.04
    (tmp_path / "ref.csv").write_text(HEADER + f"m,hopper,mass_flow_rate,0.3,0.006,,slot_width={b},calibrate,x\n"
                                      + "m,aor,angle_of_repose,31,0.5,,,calibrate,x\n")
    (tmp_path / "big.csv").write_text(HEADER + f"m,hopper,mass_flow_rate,{0.3 * 2 ** 1.5},{0.006 * 2 ** 1.5},,"
                                      f"slot_width={2 * b},calibrate,x\n" + "m,aor,angle_of_repose,31,0.5,,,calibrate,x\n"
                                      + f"m,hopper,discharge_time,2.0,0.05,,slot_width={2 * b},calibrate,x\n"
                                      + f"m,hopper,bulk_density,1300,13,,slot_width={2 * b},calibrate,x\n"
                                      + f"m,material,particle_diameter,{2 * hopper_d * 1e3},,mm,,,x\n")
    ref, _ = observations_of(load(tmp_path / "ref.csv", "m"), tiny, "ref", "m")
    got, skipped = observations_of(load(tmp_path / "big.csv", "m"), tiny, "big", "m")
    assert len(got) == 2 and len(skipped) == 2 and "line 4" in skipped[0] and "fill's mass" in skipped[0]
    # a bulk density of spheres twice the store's: the cell's solid fraction depends on the size
    assert "line 5" in skipped[1] and "packs to a solid fraction that depends on the size" in skipped[1]
    for a, c in zip(ref, got):
        assert c.value == pytest.approx(a.value, rel=1e-12) and c.conditions == pytest.approx(a.conditions, rel=1e-12)
    # the slot scaled past the store's declared range is left out as any condition is
    (tmp_path / "tiny.csv").write_text(HEADER + f"m,hopper,mass_flow_rate,0.3,0.006,,slot_width={b},calibrate,x\n"
                                       + "m,aor,angle_of_repose,31,0.5,,,calibrate,x\n"
                                       + "m,material,particle_diameter,0.5,,mm,,,x\n")
    got, skipped = observations_of(load(tmp_path / "tiny.csv", "m"), tiny, "tiny", "m")
    assert len(got) == 1 and "slot_width=0.4" in skipped[0] and "outside" in skipped[0]


def test_the_bond_number_is_unchanged_by_the_density_similarity(tiny):
    a = tiny.scaling(MaterialProperties())
    b = tiny.scaling(MaterialProperties(particle_density=4000.0))
    kc = 3e4
    assert a.bond_number(kc) == pytest.approx(kc / (2500 * 9.81 * 3e-3))
    assert b.bond_number(kc) == pytest.approx(b.cohesion_to_material(kc) / (4000 * 9.81 * 3e-3))


@pytest.mark.slow
def test_the_similarity_holds_in_the_rig():
    """Same seed, the tiny angle-of-repose rig: at 2500 kg/m^3 and 5 MPa, and at 4000 kg/m^3 and 8
    MPa (every force x1.6, so the same motion in exact arithmetic). Rounding makes the runs
    diverge chaotically, so they agree within one run's seed scatter, not bitwise: the bulk
    density over 1.6 within 1 % (its scatter: ~1 %), the angle within 2.5 deg (~2 sd)."""
    from pydem.rigs import AngleOfRepose, AorConfig, load as load_cfg
    a = AngleOfRepose(load_cfg(AorConfig, "tiny", overrides=[])).run(seed=3)
    b = AngleOfRepose(load_cfg(AorConfig, "tiny", overrides=["density=4000", "youngs_modulus=8e6"])).run(seed=3)
    assert b.metrics["bulk_density"].value / 1.6 == pytest.approx(a.metrics["bulk_density"].value, rel=0.01)
    assert abs(b.metrics["angle_of_repose"].value - a.metrics["angle_of_repose"].value) < 2.5
