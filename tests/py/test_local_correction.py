"""The local correction of a surrogate by one material's runs (calibration/local_correction.py):
a Gaussian process on the net's residuals whose prior is the net's own error model. Checked
against closed forms: the leave-one-out residuals equal refits without each run (to 1e-9), the
gradient equals finite differences (1e-6), far from the runs the net and its error come back
unchanged, and near them a known smooth error of the net is taken out to the runs' scatter."""
import numpy as np
import pytest

from pydem.calibration.local_correction import CorrectedNet


class SmoothNet:
    """f(x) = x0 + 2 x1 on [0, 1]^2, in the nets' interface; its error model: sd 0.05, seed sd 0.01."""
    input_names = ["a", "b"]
    lo, hi = np.zeros(2), np.ones(2)
    seed_sd, net_error = 0.01, 0.05

    def scaled(self, x, clip=False):
        return np.atleast_2d(x) * 2.0 - 1.0

    def __call__(self, x):
        x = np.atleast_2d(x)
        return x[:, 0] + 2.0 * x[:, 1]

    def gradient(self, x):
        return np.tile([1.0, 2.0], (len(np.atleast_2d(x)), 1))

    def errors_at(self, x):
        m = len(np.atleast_2d(x))
        return np.full(m, self.seed_sd), np.full(m, self.net_error)


def truth(x):  # what the DEM runs give: the net plus a smooth error of 0.04 near (0.5, 0.5)
    x = np.atleast_2d(x)
    return x[:, 0] + 2.0 * x[:, 1] + 0.04 * np.exp(-np.sum((x - 0.5) ** 2, axis=1) / 0.1)


def runs(n=12, seed=0):
    rng = np.random.default_rng(seed)
    x = 0.5 + 0.15 * rng.standard_normal((n, 2))
    return x, truth(x) + rng.normal(0.0, 0.01, n)


def test_leave_one_out_residuals_are_refits_without_the_run():
    x, y = runs()
    c = CorrectedNet(SmoothNet(), x, y)
    for i in range(len(y)):
        keep = np.arange(len(y)) != i
        without = CorrectedNet(SmoothNet(), x[keep], y[keep])
        assert c.loo_residuals[i] == pytest.approx(y[i] - without(x[i:i + 1])[0], abs=1e-9)


def test_gradient_is_the_derivative_of_the_corrected_prediction():
    x, y = runs()
    c = CorrectedNet(SmoothNet(), x, y)
    p = np.array([[0.42, 0.61]])
    h = 1e-6
    fd = [(c(p + h * e) - c(p - h * e))[0] / (2 * h) for e in np.eye(2)]
    assert c.gradient(p)[0] == pytest.approx(fd, abs=1e-6)


def test_near_the_runs_the_error_is_taken_out_and_far_away_the_net_comes_back():
    x, y = runs(n=40)
    net, c = SmoothNet(), CorrectedNet(SmoothNet(), x, y)
    near = np.array([[0.5, 0.5], [0.55, 0.45]])
    # the net misses by 0.04 there; corrected, within a few seed scatters' worth (0.01 / sqrt(40) per run)
    assert np.all(np.abs(net(near) - truth(near)) > 0.03)
    assert np.all(np.abs(c(near) - truth(near)) < 0.006)
    assert np.all(c.errors_at(near)[1] < 0.3 * net.net_error)
    far = np.array([[40.0, -40.0]])  # scaled distance ~110 kernel lengths: nothing learnt there
    assert c(far)[0] == pytest.approx(net(far)[0], abs=1e-12)
    assert c.errors_at(far)[1][0] == pytest.approx(net.net_error, rel=1e-9)
    # the leave-one-out error of the corrected net is near the runs' scatter; the raw net's is the bump
    assert c.loo_rmse() < 0.02 < c.raw_rmse()


def test_repeated_runs_measure_the_seed_scatter_with_the_nets_as_prior():
    """Repeats at two points with sample variances known in closed form: the scale on the net's
    seed scatter (0.01) is sqrt((SS + 4 * 0.01^2) / (dof + 4)) / 0.01, and it scales the runs' noise."""
    from pydem.calibration.refine import PRIOR_DOF, local_seed_scale
    x = np.array([[0.5, 0.5]] * 3 + [[0.2, 0.7]] * 2 + [[0.9, 0.1]])
    y = np.array([1.0, 1.03, 0.97, 2.0, 2.04, 5.0])  # SS = 0.0018 + 0.0008, dof 2 + 1
    keys = ["a", "a", "a", "b", "b", "c"]
    scale, dof = local_seed_scale(SmoothNet(), x, y, keys)
    assert dof == 3 and scale == pytest.approx(np.sqrt((0.0026 + PRIOR_DOF * 1e-4) / (3 + PRIOR_DOF)) / 0.01, rel=1e-12)
    assert local_seed_scale(SmoothNet(), x[:1], y[:1], ["a"]) == (1.0, 0)
    c = CorrectedNet(SmoothNet(), x, y, seed_scale=(scale, dof))
    assert c.noise == pytest.approx(np.full(6, (0.01 * scale) ** 2)) and c.errors_at(x[:1])[0][0] == pytest.approx(0.01 * scale)


def test_residuals_larger_than_the_error_model_scale_the_error_up():
    """Under the prior the residuals' Mahalanobis norm r' K^-1 r is chi^2 with n dof. Residuals three
    times as large have nine times the norm, and the corrected error grows by
    c = sqrt((4 + r' K^-1 r) / (4 + n)) everywhere (the mean's correction is as before); residuals the
    model expects leave it at 1: the runs never make the error smaller than the model says."""
    from pydem.calibration.local_correction import PRIOR_DOF
    x, y = runs(n=12)
    net = SmoothNet()
    c1 = CorrectedNet(net, x, y)
    assert c1.error_scale == 1.0 and c1.mahalanobis < len(y)
    big = CorrectedNet(net, x, net(x) + 3.0 * (y - net(x)))
    assert big.mahalanobis == pytest.approx(9.0 * c1.mahalanobis, rel=1e-12)
    c = np.sqrt((PRIOR_DOF + big.mahalanobis) / (PRIOR_DOF + len(y)))
    assert c > 1.5 and big.error_scale == pytest.approx(c, rel=1e-12)
    p = np.array([[0.5, 0.5], [40.0, -40.0]])
    assert big.errors_at(p)[1] == pytest.approx(c * c1.errors_at(p)[1], rel=1e-12)
    assert big.errors_at(p)[1][1] == pytest.approx(c * net.net_error, rel=1e-9)  # far away too: the region's model
    assert big.correction(p) == pytest.approx(3.0 * c1.correction(p), rel=1e-12)  # the mean: unchanged by c
