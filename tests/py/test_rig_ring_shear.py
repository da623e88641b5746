"""Schulze ring shear at the tiny preset: the servo holds sigma_pre on the lid, the shear
stress comes from the lid torque, and a dense bed gives mu_ie-s >= mu_ie-ps within the scatter;
the torque-to-stress conversion is checked against its closed form."""
import math

import numpy as np
import pytest

from pydem.rigs import RingShear, RingShearConfig, load


@pytest.fixture(scope="module")
def tiny():
    return RingShear(load(RingShearConfig, "tiny", overrides=["shear_repeats=2"])).run(seed=1)


def test_preshear_holds_the_normal_stress(tiny):
    s = tiny.metrics["sigma_preshear"]
    assert s.value == pytest.approx(2000.0, rel=0.05)  # the servo target, held while shearing


def test_friction_coefficients_are_plausible(tiny):
    ps = tiny.metrics["mu_ie_ps"]
    s50 = tiny.metrics["mu_ie_s_50"]
    assert 0.2 < ps.value < 1.0 and ps.uncertainty > 0  # mu_s = 0.5, mu_r = 0.1 spheres
    assert s50.value >= ps.value - 2 * ps.uncertainty  # dense bed: no lower than the pre-shear
    assert 0.0 < tiny.metrics["inertial_number"].value < 0.05
    rho = tiny.metrics["bulk_density"].value
    assert 0.35 * 2500 < rho < 0.7 * 2500


def test_repeated_shear_points_are_averaged(tiny):
    """Two cycles at 50 %: mu_ie-s is the mean of the two peaks, its error their standard error,
    and a single fraction gives no yield locus (a line needs two normal stresses)."""
    peaks = np.array([q["tau_peak"] / q["sigma"] for q in tiny.info["shear_points"]])
    assert [q["fraction"] for q in tiny.info["shear_points"]] == [0.5, 0.5]
    s50 = tiny.metrics["mu_ie_s_50"]
    assert s50.value == pytest.approx(peaks.mean(), rel=1e-12)
    assert s50.uncertainty == pytest.approx(abs(peaks[0] - peaks[1]) / 2, rel=1e-9)
    assert "yield_locus_slope" not in tiny.metrics


def test_shear_stress_from_torque_closed_form():
    """tau = T / integral(r dA): a uniform tau on the annulus gives back T = tau (2 pi / 3)(Ro^3 - Ri^3)."""
    ri, ro, tau = 0.02, 0.036, 700.0
    r = np.linspace(ri, ro, 200001)
    torque = np.trapezoid(tau * r * 2 * math.pi * r, r)
    assert torque / (2 * math.pi / 3 * (ro**3 - ri**3)) == pytest.approx(tau, rel=1e-9)


def test_bad_geometry_is_refused():
    cfg = load(RingShearConfig, "tiny", overrides=["outer_radius=0.025"])
    with pytest.raises(ValueError, match="at least 4 diameters"):
        RingShear(cfg).run()


def test_yield_locus_fit():
    from pydem.rigs.ring_shear import yield_locus
    (m, m_se), (c, c_se) = yield_locus([800, 1200], [500, 740])
    assert m == pytest.approx(0.6) and c == pytest.approx(20.0) and math.isnan(m_se)
    (m, m_se), (c, c_se) = yield_locus([800, 1200, 1600], [500, 740, 980])
    assert m == pytest.approx(0.6) and c == pytest.approx(20.0) and m_se == pytest.approx(0.0, abs=1e-9)


def _tester(monkeypatch, kick: bool):
    """The tiny rig's filled, settled trough under its lid; kick: a sphere thrown up (0.8 m/s) at the
    end of the settle, as a bouncy one once was. Returns the tester and the extra settling time."""
    from pydem.rigs import ring_shear as rs
    from pydem.rigs.common import Frames, params_from
    extra = []
    real = rs.settle_airborne

    def settle(d, st, diameter, **kw):
        if kick:  # the highest sphere: nothing above it
            v = d.velocities
            v[np.argmax(d.positions[:, 2] + d.radii)] = (0.0, 0.0, 0.8)
            d.velocities = v
            st.advance(0.05)  # up by ~3 cm, 10 diameters: far above the bed
        extra.append(real(d, st, diameter, **kw))
        return extra[-1]

    monkeypatch.setattr(rs, "settle_airborne", settle)
    c = load(RingShearConfig, "tiny")
    t = rs.Tester(c, params_from(c.params, None), 1, Frames(None, None), None, 1.0)
    return t, extra[0]


def test_lid_starts_above_the_bed_not_above_a_flying_sphere(monkeypatch):
    """A sphere in the air after the settle would set the lid's start far above the bed, beyond
    the servo's reach in the procedure (once in 256 default runs the lid never touched the bed):
    the rig settles on until it has landed; without one it adds no step (bitwise as before)."""
    t, extra = _tester(monkeypatch, kick=False)
    assert extra == 0.0
    tops = t.d.positions[:, 2] + t.d.radii
    clearance = t.lid_z0 - np.percentile(tops, 99)
    t, extra = _tester(monkeypatch, kick=True)
    assert extra > 0.0
    tops = t.d.positions[:, 2] + t.d.radii
    assert tops.max() <= np.percentile(tops, 99) + 5 * t.c.diameter
    # the lid starts within the margin (5 diameters) of where it starts without the thrown sphere,
    # which was 10 diameters up: within the servo's reach
    assert t.lid_z0 - np.percentile(tops, 99) <= clearance + 5 * t.c.diameter
