"""Measurement files refuse what they cannot mean (issue: nothing invented, nothing silent):
units converted or refused, unknown names, duplicates, impossible values; a spreadsheet's BOM
and CRLF accepted; `pydem calibrate` stops when no measurement matches a campaign."""
import subprocess
import sys
from pathlib import Path

import pytest

from pydem.measurements import MeasurementError, load

ROOT = Path(__file__).resolve().parents[2]
HEADER = "material,test,quantity,value,uncertainty,unit,conditions,use,source\n"


def write(tmp_path, body, raw=None):
    f = tmp_path / "m.csv"
    if raw is not None:
        f.write_bytes(raw)
    else:
        f.write_text(HEADER + body)
    return f


def test_units_are_converted_or_refused(tmp_path):
    m = load(write(tmp_path, "x,poured,bulk_density,1.55,0.05,g/cm^3,,calibrate,s\n"))[0]
    assert m.value == pytest.approx(1550.0) and m.uncertainty == pytest.approx(50.0) and m.unit == "kg/m^3"
    m = load(write(tmp_path, "x,aor,angle_of_repose,0.5,,rad,,calibrate,s\n"))[0]
    assert m.value == pytest.approx(28.6479, rel=1e-5)
    with pytest.raises(MeasurementError, match=r"m.csv:2, column 'unit': bulk_density in 'lb/ft3' is not understood"):
        load(write(tmp_path, "x,poured,bulk_density,95,,lb/ft3,,calibrate,s\n"))
    with pytest.raises(MeasurementError, match=r"column 'value': bulk_density = 1.55 kg/m\^3 is outside"):
        load(write(tmp_path, "x,poured,bulk_density,1.55,,kg/m^3,,calibrate,s\n"))  # g/cm^3 given as kg/m^3


def test_names_duplicates_and_impossible_values(tmp_path):
    with pytest.raises(MeasurementError, match=r"column 'test': unknown test 'ringshear'"):
        load(write(tmp_path, "x,ringshear,mu_ie_ps,0.5,,,,calibrate,s\n"))
    with pytest.raises(MeasurementError, match=r"column 'quantity': test aor has no quantity 'mu_ie_ps'"):
        load(write(tmp_path, "x,aor,mu_ie_ps,0.5,,,,calibrate,s\n"))
    with pytest.raises(MeasurementError, match=r"column 'conditions': unknown condition 'sigma'"):
        load(write(tmp_path, "x,ring_shear,mu_ie_ps,0.5,,,sigma=2000,calibrate,s\n"))
    with pytest.raises(MeasurementError, match=r"m.csv:3: duplicate of line 2"):
        load(write(tmp_path, "x,aor,angle_of_repose,30,,deg,,calibrate,s\nx,aor,angle_of_repose,31,,deg,,calibrate,s\n"))
    with pytest.raises(MeasurementError, match=r"angle_of_repose = 120 deg is outside"):
        load(write(tmp_path, "x,aor,angle_of_repose,120,,deg,,calibrate,s\n"))
    with pytest.raises(MeasurementError, match=r"mu_ie_ps = -0.2 is outside"):
        load(write(tmp_path, "x,ring_shear,mu_ie_ps,-0.2,,,,calibrate,s\n"))


def test_spreadsheet_csv_with_bom_and_crlf(tmp_path):
    raw = ("\ufeff" + HEADER + "x,aor,angle_of_repose,30,0.5,deg,,calibrate,s\n").replace("\n", "\r\n").encode()
    m = load(write(tmp_path, None, raw))
    assert len(m) == 1 and m[0].material == "x" and m[0].value == 30.0


def test_calibrate_refuses_measurements_that_match_no_campaign(tmp_path):
    f = write(tmp_path, "x,hopper,mass_flow_rate,0.5,0.01,kg/s,slot_width=0.05,calibrate,s\n")
    r = subprocess.run([sys.executable, "-m", "pydem", "calibrate", str(f), "--material", "x",
                        "--stores", str(ROOT / "data/campaigns/diag_aor_tiny.h5"), "--out", str(tmp_path / "out")],
                       cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert r.returncode == 2, r.stdout + r.stderr
    assert "no row of 'x' can be compared with the campaigns" in r.stderr
    assert "hopper:mass_flow_rate" in r.stderr and "angle_of_repose" in r.stderr




def test_a_row_says_whether_it_is_a_labs_measurement_or_one_dem_run(tmp_path):
    """The optional origin column: lab by default (and when the column is absent), dem for one DEM
    run; anything else is refused naming the line, the column and the choices."""
    assert load(write(tmp_path, "x,aor,angle_of_repose,30,0.5,deg,,calibrate,s\n"))[0].origin == "lab"
    f = tmp_path / "o.csv"
    f.write_text(HEADER.rstrip("\n") + ",origin\nx,aor,angle_of_repose,30,0.5,deg,,calibrate,s,dem\n"
                 "x,poured,bulk_density,1500,20,,,calibrate,s,\n")
    assert [m.origin for m in load(f)] == ["dem", "lab"]
    f.write_text(HEADER.rstrip("\n") + ",origin\nx,aor,angle_of_repose,30,0.5,deg,,calibrate,s,simulation\n")
    with pytest.raises(MeasurementError, match=r"o.csv:2, column 'origin': 'simulation' is not one of lab, dem"):
        load(f)
