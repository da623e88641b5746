"""Schulze yield-locus outputs against a hand-worked locus: tau = 500 Pa + sigma tan 30 deg,
pre-shear at sigma_pre = 2000 Pa on the circle that touches the locus.

By hand: sin 30 = 1/2, cos 30 = sqrt(3)/2, c cos(phi) = 250 sqrt(3) = 433.013 Pa.
sigma_c = 2 c cos(phi) / (1 - sin(phi)) = 2 * 433.013 / 0.5 = 1732.05 Pa.
Take the consolidation circle with centre p = 3000 Pa: radius r = 433.013 + 1500 = 1933.013 Pa;
the pre-shear point on it at sigma_pre = 2000 Pa has tau_pre = sqrt(r^2 - 1000^2) = 1654.26 Pa.
sigma_1 = p + r = 4933.01 Pa; ffc = 4933.01 / 1732.05 = 2.84809;
phi_e = asin(r / p) = asin(0.644338) = 40.116 deg; phi_sf = atan(1654.26 / 2000) = 39.595 deg."""
import math

import numpy as np
import pytest

from pydem.rigs.yield_locus import evaluate, flowability


def test_hand_worked_locus():
    c, phi = 500.0, math.radians(30.0)
    sigma = [800.0, 1200.0, 1600.0]
    tau = [c + s * math.tan(phi) for s in sigma]
    r = 250 * math.sqrt(3) + 1500.0
    tau_pre = math.sqrt(r * r - 1000.0 ** 2)
    res = evaluate(2000.0, tau_pre, sigma, tau)
    assert res.phi_lin == pytest.approx(30.0, abs=1e-9)
    assert res.cohesion == pytest.approx(500.0, rel=1e-9)
    assert res.sigma_c == pytest.approx(1732.0508, rel=1e-6)
    assert res.centre == pytest.approx(3000.0, rel=1e-9) and res.radius == pytest.approx(1933.0127, rel=1e-6)
    assert res.sigma_1 == pytest.approx(4933.0127, rel=1e-6)
    assert res.ffc == pytest.approx(2.848076, rel=1e-5)
    assert res.phi_e == pytest.approx(math.degrees(math.asin(r / 3000.0)), rel=1e-9)
    assert res.phi_e == pytest.approx(40.116, abs=1e-3)
    assert res.phi_sf == pytest.approx(39.595, abs=1e-3)


def test_jenike_classes():
    """Jenike's classes at and between their bounds (Schulze §3.3): <1 not flowing, 1-2 very
    cohesive, 2-4 cohesive, 4-10 easy-flowing, >=10 free-flowing (a cohesionless locus: inf)."""
    got = [flowability(x) for x in (0.5, 1.0, 1.9, 2.0, 3.9, 4.0, 9.99, 10.0, math.inf)]
    assert got == ["not flowing", "very cohesive", "very cohesive", "cohesive", "cohesive", "easy-flowing",
                   "easy-flowing", "free-flowing", "free-flowing"]


def test_cohesionless_locus_and_bad_input():
    """No cohesion: sigma_c = 0, ffc unbounded, phi_e = phi_lin (the circle touches a line through
    the origin); one normal stress or a pre-shear point above the locus is refused."""
    res = evaluate(2000.0, 2000.0 * math.tan(math.radians(25)) * 0.9, [500.0, 1000.0, 1500.0],
                   [s * math.tan(math.radians(25)) for s in (500.0, 1000.0, 1500.0)])
    assert res.sigma_c == pytest.approx(0.0, abs=1e-6) and res.ffc > 1e6  # intercept 0 up to round-off
    assert res.phi_e == pytest.approx(25.0, abs=1e-9)
    with pytest.raises(ValueError, match="two or more normal stresses"):
        evaluate(2000.0, 900.0, [1000.0, 1000.0], [500.0, 510.0])
    with pytest.raises(ValueError, match="above the yield locus"):
        evaluate(2000.0, 5000.0, [500.0, 1000.0], [250.0, 500.0])


def test_ring_shear_metric_functions_by_hand():
    """The ring shear's pure metric functions on hand-made lid samples and shear points."""
    import math
    from pydem.rigs.ring_shear import locus_metrics, preshear_metrics, shear_point_metrics
    m, info = {}, {}
    steady = [(np.full(8, 1000.0), np.full(8, 2000.0), np.full(8, 0.02)),
              (np.full(4, 1100.0), np.full(4, 2000.0), np.full(4, 0.03))]
    tau_pre, sigma_pre, z = preshear_metrics(steady, m)
    assert tau_pre == pytest.approx(12400 / 12, rel=1e-14) and sigma_pre == 2000.0
    assert z == pytest.approx((8 * 0.02 + 4 * 0.03) / 12, rel=1e-14)
    assert m["mu_ie_ps"].value == pytest.approx(tau_pre / 2000.0, rel=1e-14)
    points = [(0.4, 800.0, 500.0), (0.4, 820.0, 520.0), (0.8, 1600.0, 900.0)]
    shear_point_metrics(points, m)
    mus = [500 / 800, 520 / 820]
    assert m["mu_ie_s_40"].value == pytest.approx(np.mean(mus), rel=1e-14)
    assert m["mu_ie_s_40"].uncertainty == pytest.approx(np.std(mus, ddof=1) / math.sqrt(2), rel=1e-12)
    assert m["mu_ie_s_80"].value == 900 / 1600 and math.isnan(m["mu_ie_s_80"].uncertainty)
    # a lid that carried no load is a clear error, not a division by zero
    with pytest.raises(RuntimeError, match="lid carried no load in the steady pre-shear"):
        preshear_metrics([(np.full(8, 10.0), np.zeros(8), np.full(8, 0.02))], {})
    # a pre-shear at 55 % of the requested stress is rejected, one at 95 % accepted
    with pytest.raises(RuntimeError, match="misses the requested 2000 Pa"):
        preshear_metrics([(np.full(8, 500.0), np.full(8, 1100.0), np.full(8, 0.02))], {}, target=2000.0)
    assert preshear_metrics([(np.full(8, 500.0), np.full(8, 1900.0), np.full(8, 0.02))], {}, target=2000.0)[1] == 1900.0
    with pytest.raises(RuntimeError, match="no load at the 40% shear point"):
        shear_point_metrics([(0.4, 0.0, 5.0)], {})
    line = [(0.25, 500.0, 100 + 0.5 * 500), (0.5, 1000.0, 100 + 0.5 * 1000), (0.75, 1500.0, 100 + 0.5 * 1500)]
    locus_metrics(2000.0, 100 + 0.5 * 2000 + 50, line, m, info)  # a pre-shear point above the locus: noted
    assert "above the yield locus" in info["yield_locus_note"] and "phi_lin" not in m
    info.clear()
    locus_metrics(2000.0, 100 + 0.5 * 2000, line, m, info)  # on its end, as in steady flow
    assert m["yield_locus_slope"].value == pytest.approx(0.5, rel=1e-12)
    assert m["yield_locus_intercept"].value == pytest.approx(100.0, rel=1e-10)
    assert not info and m["phi_lin"].value == pytest.approx(math.degrees(math.atan(0.5)), rel=1e-12)
    assert m["ffc"].value > 1
    one = {}
    locus_metrics(2000.0, 1000.0, [(0.5, 1000.0, 600.0)], one, {})
    assert one == {}  # one fraction: no locus


def hand_result(c, phi_deg, sigma_pre, tau_pre, sigmas):
    """A ring-shear result file's content whose shear points lie on tau = c + sigma tan(phi)."""
    t = math.tan(math.radians(phi_deg))
    return {"rig": "ring-shear", "metrics": {"sigma_preshear": {"value": sigma_pre}, "tau_preshear": {"value": tau_pre}},
            "info": {"shear_points": [{"fraction": s / sigma_pre, "sigma": s, "tau_peak": c + s * t} for s in sigmas]}}


def test_pydem_locus_reports_and_plots_several_loci(tmp_path):
    """Two consolidation stresses: the hand-worked locus of this file's docstring, and one with
    c = 800 Pa, phi 30 deg pre-sheared on its tangent circle at sigma_pre = 4000 Pa."""
    import json
    import subprocess
    import sys
    from pathlib import Path
    from pydem.rigs.yield_locus import consolidation_circle
    p, r = consolidation_circle(4000.0, 0.0, math.tan(math.radians(30)), 800.0)  # tangent circle's size
    tau_pre2 = math.sqrt(r * r - (4000.0 - p) ** 2)
    (tmp_path / "a.json").write_text(json.dumps(hand_result(500, 30, 2000.0, 1654.26, [800, 1200, 1600])))
    (tmp_path / "b.json").write_text(json.dumps(hand_result(800, 30, 4000.0, tau_pre2, [1600, 2400, 3200])))
    root = Path(__file__).resolve().parents[2]
    out = subprocess.run([sys.executable, "-m", "pydem", "locus", str(tmp_path / "a.json"), str(tmp_path / "b.json"),
                          "--plot", str(tmp_path / "loci.png")], cwd=root, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    rows = {line.split("|")[1].strip(): [x.strip() for x in line.split("|")[2:-1]] for line in out.stdout.splitlines()
            if line.startswith("| a ") or line.startswith("| b ")}
    assert float(rows["a"][2]) == pytest.approx(4933.01, abs=1.5) and rows["a"][3:5] == ["1732", "2.85"]  # by hand
    assert rows["a"][5] == "cohesive"  # Jenike: 2 <= ffc < 4
    assert rows["a"][6] == "40.1" and rows["a"][7] == "30.0" and rows["a"][9] == "500"
    assert float(rows["b"][3]) == pytest.approx(2 * 800 * math.cos(math.radians(30)) / 0.5, abs=1)  # sigma_c
    assert rows["a"][0] == rows["b"][0] == "1"  # neither result names its material: one flow function
    assert (tmp_path / "loci.png").stat().st_size > 20_000
    # two materials (different friction in the results' configurations): two flow functions, never joined
    for name, friction in (("a", 0.5), ("b", 0.3)):
        d = json.loads((tmp_path / f"{name}.json").read_text())
        d["provenance"] = {"config": {"friction": friction, "preshear_stress": d["metrics"]["sigma_preshear"]["value"]}}
        (tmp_path / f"{name}.json").write_text(json.dumps(d))
    out = subprocess.run([sys.executable, "-m", "pydem", "locus", str(tmp_path / "a.json"), str(tmp_path / "b.json")],
                         cwd=root, capture_output=True, text=True)
    assert out.returncode == 0 and "2: friction=0.3" in out.stdout and "1: friction=0.5" in out.stdout, out.stdout
    bad = subprocess.run([sys.executable, "-m", "pydem", "locus", str(tmp_path / "loci.png")], cwd=root,
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "loci.png: not a ring-shear result file" in bad.stderr
