"""A material's own particle density (calibration/similarity.py): its rows are compared with
stores made at another density by similarity — bulk densities and flow rates as solid
fractions, pre-shear stresses scaled — so a material 1.6x denser than the stores, said so in its
file, gives exactly the observations of the stores' material; the card comes back in the
material's terms. And the similarity itself, by DEM: the angle-of-repose rig at 4000 kg/m^3 with
the modulus scaled with it measures what it measures at 2500 kg/m^3."""
from pathlib import Path

import pytest

from pydem.calibration.setup import TINY_STORES, load_setup, observations_of
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
    s = tiny.scaling(rows)
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
    notes = tiny.scaling(load(tmp_path / "stiff.csv", "m")).notes()
    assert any("Young's modulus given 7e+10 Pa" in n and "unconfirmed" in n for n in notes), notes


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
