"""`pydem calibrate` and `pydem compare` on the shipped tiny diagnosis stores: a posterior that
covers the truth of surrogate-made data, seed 000's window screened natively equal to numpy's,
exported nets equal to the surrogates, rows matched by condition; and measurement files:
parsing and errors that name the line and the column."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from pydem.measurements import MeasurementError, load
from pydem.mlp import NativeMLP

ROOT = Path(__file__).resolve().parents[2]
HEADER = "material,test,quantity,value,uncertainty,unit,conditions,use,source\n"


@pytest.fixture(scope="module")
def tiny():
    """The shipped tiny diagnosis stores (their nets are cached beside them: no training)."""
    from pydem.calibration.setup import TINY_STORES, load_setup
    return load_setup([ROOT / s for s in TINY_STORES], say=lambda *_: None)


def pseudo_measurements(tmp_path, tiny, truth):
    """Rows the surrogates predict exactly at `truth` (base parameters, candidates neutral), with
    an uncertainty of 2 % (the tiny rigs' seed scatter dominates sigma anyway)."""
    from pydem.calibration.fit import Model
    from pydem.calibration.synthetic import programme
    obs = programme(tiny.nets)
    model = Model(obs, tiny.nets, tiny.ranges, tiny.candidates)
    values = model.predict(np.array([truth[n] for n in model.free]))
    rows = []
    for o, v in zip(obs, values):
        test = {"ring-shear": "ring_shear"}.get(o.quantity.rig, o.quantity.rig)
        cond = ";".join(f"{k}={x:.17g}" for k, x in o.conditions.items())
        rows.append(f"m,{test},{o.quantity.metric},{v:.17g},{0.02 * abs(v):.4g},,{cond},calibrate,test")
    f = tmp_path / "m.csv"
    f.write_text(HEADER + "\n".join(rows) + "\n")
    return f, obs, model


def test_posterior_covers_the_truth_and_the_native_window_is_numpy_s(tiny, tmp_path):
    from pydem.calibration.calibrate import calibrate, window_screen
    from pydem.calibration.setup import observations_from_file
    truth = {"friction": 0.5, "rolling_friction": 0.3, "restitution": 0.5}
    f, _, _ = pseudo_measurements(tmp_path, tiny, truth)
    obs, skipped = observations_from_file(f, "m", tiny)
    assert not skipped
    c = calibrate("m", obs, tiny.nets, tiny.ranges, tiny.candidates, samples=2 ** 14, threads=2, say=lambda *_: None)
    assert c.fit.chi2 < 1e-3 * len(obs)  # exact data: the minimum is (near) zero
    for name, v in truth.items():  # the 95 % interval holds the truth, the estimate is near it
        p = c.fit.posterior["parameters"][name]
        assert p["lo"] <= v <= p["hi"], (name, p)
    assert abs(c.fit.as_dict()["friction"] - 0.5) < 0.1
    # seed 000's window, natively, is exactly what numpy keeps on the same Sobol points
    w = window_screen(c.model, 0.05, 2 ** 12, threads=2)
    from pydem.campaign.design import design_points
    pts = design_points("sobol", dict(zip(c.model.free, zip(c.model.lo, c.model.hi))), 0, 2 ** 12, 7)
    keep = np.all(np.abs(c.model.predict(pts) - c.model.y) <= 0.05 * np.abs(c.model.y), axis=1)
    assert w["admissible"] == int(keep.sum()) > 0
    assert np.allclose(w["points"], pts[keep], rtol=0, atol=0)


def test_one_angle_for_three_parameters_gives_a_ridge_not_an_error(tiny):
    """One measured angle cannot pin three parameters: the data's information matrix is singular
    (rank 1). The posterior must still come out — the unconstrained directions as wide as the
    prior — instead of failing in the proposal's Cholesky factor (as it did for the JKU angles)."""
    from pydem.calibration.fit import Model, minimise, posterior
    from pydem.calibration.quantities import Observation
    q = next(q for q in tiny.nets if q.rig == "aor" and q.metric == "angle_of_repose")
    obs = [Observation(q, {}, 30.0, 0.5, "angle")]
    model = Model(obs, tiny.nets, tiny.ranges, tiny.candidates)
    fit = minimise(model, starts=256)
    # the angle's sensitivities as the JKU store had them: one row, every entry non-zero
    model.jacobian = lambda p: np.array([[1.0711151791612545, 11.444224318427562, -3.6374110231928567]])
    model.white = lambda v: v  # (already whitened)
    post = posterior(model, fit, samples=2 ** 12)
    widths = {n: (p["hi"] - p["lo"]) / (hi - lo) for n, p, lo, hi in
              zip(fit.names, post["parameters"].values(), model.lo, model.hi)}
    assert post["ess"] > 50
    # some direction stays wide: over half the box (the best fit sits in a corner, so each interval
    # runs one-sided from the edge it sits at; the central intervals were 0.6-0.9 of the box)
    assert max(widths.values()) > 0.5, widths
    for p in post["parameters"].values():  # and every estimate lies inside its own interval
        assert p["lo"] <= p["estimate"] <= p["hi"], p


def test_calibrate_command_writes_report_nets_and_window(tiny, tmp_path):
    from pydem.calibration.setup import TINY_STORES
    f, _, _ = pseudo_measurements(tmp_path, tiny, {"friction": 0.4, "rolling_friction": 0.2, "restitution": 0.6})
    out = tmp_path / "cal"
    r = subprocess.run([sys.executable, "-m", "pydem", "calibrate", str(f), "--material", "m", "--out", str(out),
                        "--samples", "16384", "--stores", *TINY_STORES], cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    data = json.loads((out / "calibration.json").read_text())
    assert set(data["parameters"]) == {"friction", "rolling_friction", "restitution"}
    for p in data["parameters"].values():
        assert p["lo"] <= p["estimate"] <= p["hi"] and isinstance(p["at_edge"], bool)
    assert data["admissible_window"]["samples"] == 16384 and data["admissible_window"]["admissible"] > 0
    kept = np.loadtxt(out / "admissible.csv", delimiter=",", skiprows=1, ndmin=2)
    assert kept.shape == (data["admissible_window"]["admissible"], 3)
    html = (out / "report.html").read_text()
    assert "data:image/png;base64," in html and "95 % credible interval" in html
    # the exported nets are the surrogates: libdem reads the file, the C source compiles
    from pydem.calibration.quantities import Quantity
    net = tiny.nets[Quantity("aor", "angle_of_repose")]
    native = NativeMLP(out / "nets" / "aor__angle_of_repose.mlp")
    x = np.random.default_rng(0).uniform(net.lo, net.hi, (100, len(net.lo)))
    assert np.allclose(native(x), net(x), rtol=1e-12, atol=1e-12)
    assert (out / "nets/c/mlp_aor__angle_of_repose.c").exists()
    # the material card: the estimate as JSON and as LIGGGHTS / LAMMPS input
    card = json.loads((out / "material_card.json").read_text())
    mu = data["parameters"]["friction"]["estimate"]
    assert card["parameters"]["friction"]["value"] == mu and card["parameters"]["friction"]["calibrated"]
    assert card["parameters"]["wall_friction"]["value"] == mu  # not freed: the base model's assumption
    lig = (out / "material_card.liggghts").read_text()
    assert f"coefficientFriction peratomtypepair 2 {mu:.6g} {mu:.6g}" in lig and "rolling_friction epsd2" in lig
    assert "pair_style granular" in (out / "material_card.lammps").read_text()


def test_a_row_at_another_condition_than_a_fixed_store_is_left_out(tmp_path):
    """ring_shear_cell.h5 runs at one pre-shear stress: a row measured at another is reported as
    left out, never matched to the campaign's condition; `unknown` takes the campaign's."""
    import shutil
    from pydem.calibration.setup import load_setup, observations_from_file
    shutil.copy(ROOT / "data/campaigns/ring_shear_cell.h5", tmp_path)
    shutil.copytree(ROOT / "data/campaigns/ring_shear_cell.h5.nets", tmp_path / "ring_shear_cell.h5.nets")  # cached nets
    setup = load_setup([tmp_path / "ring_shear_cell.h5"], say=lambda *_: None)
    f = tmp_path / "m.csv"
    f.write_text(HEADER + "x,ring_shear,mu_ie_ps,0.5,0.01,,preshear_stress=5000,calibrate,s\n"
                 "x,ring_shear,bulk_density,1500,20,kg/m^3,preshear_stress=unknown,calibrate,s\n")
    obs, skipped = observations_from_file(f, "x", setup)
    fixed = setup.defaults["preshear_stress"]
    assert len(obs) == 1 and obs[0].quantity.metric == "bulk_density" and obs[0].assumed == {"preshear_stress": fixed}
    assert len(skipped) == 1 and f"preshear_stress=5000 but the campaign ran at {fixed:g} only" in skipped[0]


def test_compare_matches_rows_by_condition(tiny, tmp_path):
    from pydem.calibration.setup import TINY_STORES
    from pydem.calibration.compare import dem_rows, surrogate_rows
    from pydem.calibration.setup import observations_from_file
    truth = {"friction": 0.5, "rolling_friction": 0.3, "restitution": 0.5}
    f, _, _ = pseudo_measurements(tmp_path, tiny, truth)
    obs, _ = observations_from_file(f, "m", tiny)
    rows = surrogate_rows(obs, tiny, truth)
    assert max(abs(r["z"]) for r in rows) < 1e-6  # the rows were made by the same surrogates
    # DEM results: matched by rig and condition; a row at a condition no result has is listed
    result = {"rig": "ring-shear", "metrics": {"mu_ie_ps": {"value": 0.55, "uncertainty": 0.01}},
              "provenance": {"config": {"preshear_stress": 2000.0}}}
    (tmp_path / "r.json").write_text(json.dumps(result))
    rows, unmatched = dem_rows(obs, [tmp_path / "r.json"])
    ps = [o for o in obs if o.quantity.metric == "mu_ie_ps"]
    assert [r["label"] for r in rows] == [o.label for o in ps if o.conditions["preshear_stress"] == 2000.0]
    assert rows[0]["model"] == 0.55 and len(unmatched) == len(obs) - 1
    r = subprocess.run([sys.executable, "-m", "pydem", "compare", str(f), "--material", "m", "--params",
                        ",".join(f"{k}={v}" for k, v in truth.items()), "--stores", *TINY_STORES], cwd=ROOT,
                       capture_output=True, text=True)
    assert r.returncode == 0 and "RMSE of relative residuals 0.000" in r.stdout, r.stdout + r.stderr


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


def test_shipped_measurements():
    m = load(ROOT / "data/measurements/glass_microbeads.csv", "glass_microbeads")
    assert [x.metric for x in m] == ["mu_ie_ps", "mu_ie_s_50", "bulk_density"]
    assert abs(m[0].value - np.tan(np.radians(23.45))) < 1e-4  # converted from the published angle
    jku = load(ROOT / "data/measurements/jku_angle_of_repose.csv")
    angles = [x for x in jku if x.test == "aor"]
    assert len(angles) == 8
    # each material's sieve table gives the mean diameter the JKU reduction published beside its angle
    from pydem.calibration.similarity import MaterialProperties
    for a in angles:
        mat = MaterialProperties.from_rows([x for x in jku if x.material == a.material])
        assert 1e3 * mat.mean_diameter == pytest.approx(float(a.conditions["mean_diameter_mm"]), abs=0.006), a.material


def test_command_line_errors_are_clear(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text(HEADER + "x,aor,angle_of_repose,forty,,deg,,calibrate,s\n")
    r = subprocess.run([sys.executable, "-m", "pydem", "compare", str(bad), "--material", "x", "--dem", "r.json"],
                       cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 2 and "bad.csv:2, column 'value': expected a number, got 'forty'" in r.stderr
    r = subprocess.run([sys.executable, "-m", "pydem", "calibrate", str(bad), "--material", "x",
                        "--stores", str(tmp_path / "none.h5")], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 2 and "bad.csv:2" in r.stderr
    good = tmp_path / "good.csv"
    good.write_text(HEADER + "x,aor,angle_of_repose,40,,deg,,calibrate,s\n")
    r = subprocess.run([sys.executable, "-m", "pydem", "calibrate", str(good), "--material", "x",
                        "--stores", str(tmp_path / "none.h5")], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 2 and "none.h5: no such campaign store" in r.stderr


def test_nets_cached_per_training_set(tmp_path, monkeypatch):
    """A store's nets are cached per set of runs trained on: loading it pooled with another store
    and alone again retrains neither time after the first; the least recently used of more than
    SLOTS sets goes."""
    import shutil
    from pydem.calibration import surrogates
    from pydem.campaign import Campaign
    shutil.copy(ROOT / "data/campaigns/ring_shear_cell.h5", tmp_path)
    shutil.copytree(ROOT / "data/campaigns/ring_shear_cell.h5.nets", tmp_path / "ring_shear_cell.h5.nets")
    store = Campaign.open(tmp_path / "ring_shear_cell.h5").store
    shipped = surrogates.load_or_train(store, say=lambda *_: None)
    trained = []
    monkeypatch.setattr(surrogates, "train", lambda st, say, pooled=(): trained.append(len(pooled)) or dict(shipped))
    assert surrogates.load_or_train(store, say=lambda *_: None).keys() == shipped.keys() and trained == []
    surrogates.load_or_train(store, say=lambda *_: None, pooled=(store,))
    assert trained == [1]
    surrogates.load_or_train(store, say=lambda *_: None, pooled=(store,))
    surrogates.load_or_train(store, say=lambda *_: None)
    assert trained == [1]  # both sets cached side by side; the store alone the more recently used
    for k in (2, 3):
        surrogates.load_or_train(store, say=lambda *_: None, pooled=(store,) * k)
    slots = [p for p in surrogates.cache_dir(store).iterdir() if p.is_dir()]
    assert trained == [1, 2, 3] and len(slots) == surrogates.SLOTS
    names = {p.name for p in slots}
    assert surrogates.store_hash(store) in names and surrogates.store_hash(store, (store,)) not in names


def test_the_commands_find_the_shipped_stores_from_any_directory(tmp_path):
    """The default stores are found wherever the command runs (pydem.shipped: $PYDEM_DATA, the
    package's copy, the checkout); a name none of them holds is refused naming every place
    searched and the variable that points elsewhere."""
    import os
    import subprocess
    import sys
    from pydem.shipped import shipped_path
    meas = ROOT / "data/measurements/synthetic_cohesive.csv"
    run = subprocess.run([sys.executable, "-m", "pydem", "compare", str(meas), "--material", "synthetic_cohesive",
                          "--params", "friction=0.43,rolling_friction=0.12,restitution=0.44"], cwd=tmp_path,
                         capture_output=True, text=True, env={**os.environ, "PYDEM_DATA": str(tmp_path / "none")})
    assert run.returncode == 0, run.stderr
    assert "rows: RMSE of relative residuals" in run.stdout
    assert shipped_path("data/campaigns/diag_aor_default.h5").is_file()
    with pytest.raises(FileNotFoundError, match="campaigns/nope.h5: not among the shipped data .* PYDEM_DATA"):
        shipped_path("data/campaigns/nope.h5")


def test_calibrate_screens_on_the_threads_omp_num_threads_gives():
    """Without --threads, calibrate and diagnose take OMP_NUM_THREADS (else every core), the
    native screening included; --threads 0 is refused before any work."""
    import argparse
    import os
    from pydem.calibration.setup import TINY_STORES
    from pydem.cli_inputs import add_common, load_inputs
    ap = argparse.ArgumentParser()
    add_common(ap, "out")
    old = os.environ.get("OMP_NUM_THREADS")
    os.environ["OMP_NUM_THREADS"] = "1"
    try:
        args = ap.parse_args([str(ROOT / "data/measurements/synthetic_cohesive.csv"), "--material", "synthetic_cohesive",
                              "--stores", *[str(ROOT / s) for s in TINY_STORES]])
        assert load_inputs(args, "calibrate", lambda *a: None) is not None and args.threads == 1
    finally:
        os.environ.pop("OMP_NUM_THREADS") if old is None else os.environ.__setitem__("OMP_NUM_THREADS", old)
    args = ap.parse_args(["x.csv", "--material", "m", "--threads", "0"])
    assert load_inputs(args, "calibrate", lambda *a: None) is None


def test_a_condition_is_inside_the_store_when_inside_its_declared_range(tiny, tmp_path):
    """Inside means inside the campaign's declared range, not between the design's extreme points
    (a 0.5-10 kPa box ran 500.8-9997 Pa): a row at the range's end is compared without a note; up to
    2 % of the range past it a row is compared with a note that the surrogate extrapolates; further
    out it is left out, saying the limit."""
    from pydem.calibration.calibrate import row_notes
    from pydem.calibration.setup import RANGE_TOLERANCE, declared_range, observations_of
    from pydem.measurements import load
    q = next(q for q in tiny.nets if q.rig == "ring-shear" and q.metric == "mu_ie_ps")
    net = tiny.nets[q]
    lo, hi = declared_range(tiny, "ring-shear", "preshear_stress")
    assert (lo, hi) == tuple(tiny.stores["ring-shear"].spec.ranges["preshear_stress"])
    assert net.hi[net.input_names.index("preshear_stress")] < hi  # the design's last point stops short
    f = tmp_path / "m.csv"
    f.write_text("material,test,quantity,value,uncertainty,unit,conditions\n"
                 f"m,ring_shear,mu_ie_ps,0.55,0.01,,preshear_stress={hi:.8g}\n"
                 f"m,ring_shear,mu_ie_ps,0.56,0.01,,preshear_stress={hi + 0.5 * RANGE_TOLERANCE * (hi - lo):.8g}\n"
                 f"m,ring_shear,mu_ie_ps,0.57,0.01,,preshear_stress={hi + 2 * RANGE_TOLERANCE * (hi - lo):.8g}\n")
    obs, skipped = observations_of(load(f, "m"), tiny, "m.csv", "m")
    assert len(obs) == 2 and not obs[0].extrapolated
    assert "1.0 % of the range past the campaign's" in obs[1].extrapolated["preshear_stress"]
    assert any("the surrogate extrapolates" in n for n in row_notes(obs))
    assert len(skipped) == 1 and "line 4" in skipped[0] and "2 % past it allowed" in skipped[0]
