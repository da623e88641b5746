"""The calibration job end to end on a real (tiny) campaign, the two-stage screening logic on
nets trained on closed-form properties, and measurement files: parsing and errors that name
the line and the column."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from nn.export import write_weights
from nn.mlp import select_net
from pydem import screening
from pydem.calibrate import calibrate
from pydem.campaign import Campaign, CampaignSpec
from pydem.compare import compare, overall
from pydem.measurements import MeasurementError, load
from pydem.mlp import NativeMLP

ROOT = Path(__file__).resolve().parents[2]
HEADER = "material,test,quantity,value,uncertainty,unit,conditions,use,source\n"


@pytest.fixture(scope="module")
def aor_campaign(tmp_path_factory):
    d = tmp_path_factory.mktemp("camp")
    spec = CampaignSpec(rig="aor", preset="tiny", fixed={"particles": 150, "num_threads": 1, "max_time": 1.5}, samples=14,
                        seed=1, ranges={"friction": (0.2, 0.9), "rolling_friction": (0.0, 0.5)})
    c = Campaign.create(d / "aor.h5", spec)
    assert c.run(workers=2, quiet=True)["done"] == 14
    return d / "aor.h5"


def test_calibration_job_end_to_end(aor_campaign, tmp_path):
    s = Campaign.open(aor_campaign).store
    _, angles, _ = s.table("angle_of_repose")
    meas = tmp_path / "m.csv"
    meas.write_text(HEADER + f"beads,aor,angle_of_repose,{np.median(angles):.4f},1.0,deg,,calibrate,test\n"
                    "beads,poured,bulk_density,1500,50,kg/m^3,,compare,test\n")
    out = tmp_path / "cal"
    summary = calibrate(meas, "beads", [aor_campaign], out, samples=2 ** 14, sizes=[2, 3], restarts=1, threads=2)
    assert set(summary["nets"]) == {"aor__angle_of_repose", "aor__bulk_density"}
    for f in ("report.md", "summary.json", "r2_vs_hidden.csv", "admissible.png", "comparison.png", "parity_holdout.png",
              "nets/aor__angle_of_repose.mlp", "nets/c/mlp_aor__angle_of_repose.c", "confirm_aor.json", "admissible.csv"):
        assert (out / f).exists(), f
    st = summary["stages"][-1]
    assert st["rows"] == 2 ** 14 and 0 < st["admissible"] < 2 ** 14  # the median angle is inside the data
    net = NativeMLP(out / "nets" / "aor__angle_of_repose.mlp")
    pred = net(np.array([list(summary["best"].values())]))[0]
    assert abs(pred - np.median(angles)) <= 0.05 * np.median(angles)  # the best estimate is admissible
    kept = np.loadtxt(out / "admissible.csv", delimiter=",", skiprows=1, ndmin=2)
    assert kept.shape == (st["admissible"], 3)  # friction, rolling_friction, the predicted angle
    report = (out / "report.md").read_text()
    assert "Confirming DEM runs" in report and "hold-out R²" in report
    for key, meta in summary["nets"].items():  # every net below the target is named, with why
        assert (f"- {key}: " in report and "noise ceiling" in report) == (meta["holdout_r2"] < 0.95), key
    r = subprocess.run([sys.executable, "-m", "pydem", "compare", str(meas), "--material", "beads", "--nets",
                        str(out / "nets"), "--params", ",".join(f"{k}={v}" for k, v in summary["best"].items())],
                       cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0 and "Overall: RMSE" in r.stdout, r.stderr


def test_two_stage_screening_narrows(tmp_path):
    """Closed-form 'properties' p1 = a + b (stage 1) and p2 = a - b (stage 2): the admissible
    set after both is the intersection of two bands, and each stage keeps what numpy keeps."""
    rng = np.random.default_rng(0)
    x = rng.uniform(0, 1, size=(200, 2))
    nets = []
    for name, y in (("p1", 1 + x[:, 0] + x[:, 1]), ("p2", 2 + x[:, 0] - x[:, 1])):
        net, _ = select_net(name, ["a", "b"], x, y, sizes=[3], restarts=1)
        nets.append(NativeMLP(write_weights(net, tmp_path / f"{name}.mlp")))
    from pydem.measurements import Measurement
    m1, m2 = Measurement("m", "ring_shear", "p1", 2.0, 0.01), Measurement("m", "aor", "p2", 2.0, 0.01)
    sc = screening.run(["a", "b"], {"a": (0, 1), "b": (0, 1)},
                       [screening.Stage("ring-shear", [nets[0]], [m1], 0.02), screening.Stage("aor", [nets[1]], [m2], 0.02)],
                       n=2 ** 14, threads=2)
    first, final = sc.admissible
    assert 0 < len(final) < len(first) < 2 ** 14
    p1, p2 = nets[0](sc.points), nets[1](sc.points)
    assert np.array_equal(first, np.flatnonzero(np.abs(p1 - 2.0) <= 0.04))
    assert np.array_equal(final, np.flatnonzero((np.abs(p1 - 2.0) <= 0.04) & (np.abs(p2 - 2.0) <= 0.04)))
    # a + b = 1 and a = b meet at (0.5, 0.5): the final set is a small patch around it
    r = sc.ranges_of(final)
    assert abs(np.mean(sc.points[final, 0]) - 0.5) < 0.03 and abs(np.mean(sc.points[final, 1]) - 0.5) < 0.03
    assert r["a"][0] > 0.4 and r["a"][1] < 0.6


def test_measurement_file_errors_name_line_and_column(tmp_path):
    f = tmp_path / "m.csv"
    f.write_text("# comment\n" + HEADER + "x,aor,angle_of_repose,40.1,,deg,,calibrate,s\nx,aor,bulk_density,12a,,,,,s\n")
    with pytest.raises(MeasurementError, match=r"m.csv:4, column 'value': expected a number, got '12a'"):
        load(f)
    f.write_text(HEADER + "x,ring_shear,mu_ie_s,0.5,-1,,shear_fraction=0.5,calibrate,s\n")
    with pytest.raises(MeasurementError, match=r":2, column 'uncertainty': must be positive"):
        load(f)
    f.write_text(HEADER + "x,ring_shear,mu_ie_s,0.5,0.01,,shear_fraction=1.5,calibrate,s\n")
    with pytest.raises(MeasurementError, match=r"shear_fraction 1.5 must lie in"):
        load(f)
    f.write_text(HEADER + "x,aor,angle_of_repose,40\n")
    with pytest.raises(MeasurementError, match=r":2: 4 fields, the header has 9"):
        load(f)
    f.write_text("material,test,value\n")
    with pytest.raises(MeasurementError, match="header lacks column"):
        load(f)
    with pytest.raises(MeasurementError, match="no rows for material 'glass'"):
        load(ROOT / "data/measurements/jku_angle_of_repose.csv", "glass")


def test_shipped_measurements_and_residuals():
    m = load(ROOT / "data/measurements/glass_microbeads.csv", "glass_microbeads")
    assert [x.metric for x in m] == ["mu_ie_ps", "mu_ie_s_50", "bulk_density"]
    assert abs(m[0].value - np.tan(np.radians(23.45))) < 1e-4  # converted from the published angle
    res = compare(m, {"ring-shear:mu_ie_ps": (m[0].value + 2 * m[0].uncertainty, 0.0)})
    assert abs(res[0].z - 2.0) < 1e-9 and np.isnan(res[1].model)
    assert overall(res)["modelled"] == 1
    assert len(load(ROOT / "data/measurements/jku_angle_of_repose.csv")) == 8


def test_surrogate_model_keys_match_measurement_rigs(tmp_path):
    """Net files are named ring_shear__<metric>.mlp; measurements name the rig ring-shear."""
    from pydem.compare import surrogate_model
    from pydem.measurements import Measurement
    rng = np.random.default_rng(0)
    x = rng.uniform(0, 1, size=(40, 2))
    net, _ = select_net("mu_ie_ps", ["a", "b"], x, 0.4 + 0.2 * x[:, 0], sizes=[2], restarts=1)
    write_weights(net, tmp_path / "ring_shear__mu_ie_ps.mlp")
    model = surrogate_model(tmp_path, {"a": 0.5, "b": 0.5})
    res = compare([Measurement("m", "ring_shear", "mu_ie_ps", 0.5, 0.01)], model)
    assert abs(res[0].model - 0.5) < 0.02


def test_command_line_errors_are_clear(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text(HEADER + "x,aor,angle_of_repose,forty,,deg,,calibrate,s\n")
    r = subprocess.run([sys.executable, "-m", "pydem", "compare", str(bad), "--material", "x", "--dem", "r.json"],
                       cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 2 and "bad.csv:2, column 'value': expected a number, got 'forty'" in r.stderr
    r = subprocess.run([sys.executable, "-m", "pydem", "calibrate", "--measurements", str(bad), "--material", "x",
                        "--campaign", str(tmp_path / "none.h5")], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 2 and "bad.csv:2" in r.stderr
    good = tmp_path / "good.csv"
    good.write_text(HEADER + "x,aor,angle_of_repose,40,,deg,,calibrate,s\n")
    r = subprocess.run([sys.executable, "-m", "pydem", "calibrate", "--measurements", str(good), "--material", "x",
                        "--campaign", str(tmp_path / "none.h5")], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 2 and "none.h5: no such campaign store" in r.stderr
