"""A surrogate corrected by one material's own DEM runs (docs/diagnosis.md §8, refinement).

The global net stays the prior mean; what the runs say about its error near the material is a
Gaussian process on the residuals r_i = y_i - net(x_i). Its prior is the net's own error model,
taken as it is: the pooled net error e as the prior sd and the correlation the likelihood already
uses over conditions, exp(-d^2 / 2 l^2) with d in the net's [-1, 1]-scaled inputs and
l = fit.NET_ERROR_LENGTH, here over every input. Each run's noise is one run's seed scatter at
its inputs (the net's error model). Then, with K = e^2 R(X, X) + S and alpha = K^-1 r:

    mean     f(x) = net(x) + e^2 R(x, X) alpha
    error    v(x) = e^2 - e^2 R(x, X) K^-1 R(X, x) e^2      (what the runs leave of the net's error)

so near the runs the prediction is as good as their seed scatter allows and far from them it is
the net with its error, unchanged. The row's net-error term becomes the local error scaled by
sqrt(v / e^2) (at least FLOOR of it: the kernel's length is assumed, not fitted). Leave-one-out
residuals come in closed form, alpha_i / (K^-1)_ii: the error of the corrected prediction at a
run that it did not see, against that run (seed scatter included).

The prior is checked against the runs: under it the residuals' Mahalanobis norm r' K^-1 r is
chi^2 with n degrees of freedom. Where the net is worse near the material than its global error
model says, the norm is larger, and every variance of the process is scaled by
c^2 = (PRIOR_DOF + r' K^-1 r) / (PRIOR_DOF + n), the model's own error counted as PRIOR_DOF
degrees of freedom beside the runs' (the estimate of an overall covariance scale, tempered).
The correction's mean does not change; its error does, by c (error_scale), never below 1: the
runs may show the net worse than its error model but are too few to show it better."""
from __future__ import annotations

import numpy as np
from scipy import linalg

from .fit import NET_ERROR_LENGTH

FLOOR = 0.05  # the corrected net error is at least this fraction of the net's own there
PRIOR_DOF = 4  # the net's error model counts as this many degrees of freedom beside the runs' residuals


def correlation(net, a, b) -> np.ndarray:
    """(len a, len b): the net error's correlation between inputs a and b (the kernel above)."""
    sa, sb = net.scaled(np.atleast_2d(a)), net.scaled(np.atleast_2d(b))
    d2 = np.sum((sa[:, None, :] - sb[None, :, :]) ** 2, axis=-1)
    return np.exp(-0.5 * d2 / NET_ERROR_LENGTH ** 2)


def run_noise(net, x) -> np.ndarray:
    """One run's seed-scatter variance at each of inputs x (the net's error model, else its pooled value)."""
    x = np.atleast_2d(x)
    seed = net.errors_at(x)[0] if hasattr(net, "errors_at") else np.full(len(x), net.seed_sd)
    return np.asarray(seed, float) ** 2


def left_variance(net, runs_x, targets_x) -> np.ndarray:
    """v(x) at each target: the net-error variance left by runs at runs_x (it does not depend on
    what the runs give: refine.plan places runs by it before any runs)."""
    e2 = float(net.net_error) ** 2
    if len(runs_x) == 0:
        return np.full(len(np.atleast_2d(targets_x)), e2)
    k = e2 * correlation(net, runs_x, runs_x) + np.diag(run_noise(net, runs_x))
    kt = e2 * correlation(net, targets_x, runs_x)
    return np.clip(e2 - np.sum(kt * np.linalg.solve(k, kt.T).T, axis=1), 0.0, None)


class CorrectedNet:
    """A QuantityNet plus the Gaussian-process correction learnt from runs (x: (n, inputs) in the
    net's input order, y: (n,)); every other attribute is the net's."""

    def __init__(self, net, x: np.ndarray, y: np.ndarray, seed_scale: tuple[float, int] = (1.0, 0)):
        """seed_scale: (factor, degrees of freedom) on the net's seed scatter from repeated runs
        (refine.local_seed_scale); it scales the runs' noise here and the seed scatter of errors_at."""
        self.net = net
        self.seed_scale = (float(seed_scale[0]), int(seed_scale[1]))
        self.x = np.atleast_2d(np.asarray(x, float))
        self.y = np.asarray(y, float)
        self.prior_sd = float(net.net_error)
        self.noise = run_noise(net, self.x) * self.seed_scale[0] ** 2
        self.residuals = self.y - net(self.x)
        k = self.prior_sd ** 2 * self._corr(self.x, self.x) + np.diag(self.noise)
        self._chol = linalg.cho_factor(k, lower=True)
        self.alpha = linalg.cho_solve(self._chol, self.residuals)
        kinv_diag = np.diag(linalg.cho_solve(self._chol, np.eye(len(self.y))))
        self.loo_residuals = self.alpha / kinv_diag  # y_i - (corrected prediction without run i)
        self.mahalanobis = float(self.residuals @ self.alpha)  # chi^2 with len(y) dof under the prior
        self.error_scale = float(np.sqrt(max(1.0, (PRIOR_DOF + self.mahalanobis) / (PRIOR_DOF + len(self.y)))))

    def __getattr__(self, name):  # the net's inputs, box, seed scatter, correlations
        return getattr(self.net, name)

    def _s(self, x) -> np.ndarray:
        return self.net.scaled(np.atleast_2d(x))

    def _corr(self, a, b) -> np.ndarray:
        return correlation(self.net, a, b)

    def correction(self, x) -> np.ndarray:
        return self.prior_sd ** 2 * self._corr(x, self.x) @ self.alpha

    def __call__(self, x):
        return self.net(x) + self.correction(x)

    def gradient(self, x):
        x = np.atleast_2d(x)
        r = self.prior_sd ** 2 * self._corr(x, self.x) * self.alpha[None, :]            # (m, n)
        ds = self._s(x)[:, None, :] - self._s(self.x)[None, :, :]                        # (m, n, inputs)
        scale = 2.0 / (self.net.hi - self.net.lo)
        return self.net.gradient(x) - np.einsum("mn,mni->mi", r, ds) / NET_ERROR_LENGTH ** 2 * scale

    def variance_fraction(self, x) -> np.ndarray:
        """v(x) / e^2: the share of the net's error variance the runs leave at x, in [0, 1]."""
        kx = self.prior_sd ** 2 * self._corr(x, self.x)
        v = self.prior_sd ** 2 - np.sum(kx * linalg.cho_solve(self._chol, kx.T).T, axis=1)
        return np.clip(v / self.prior_sd ** 2, 0.0, 1.0) if self.prior_sd > 0 else np.ones(len(kx))

    def errors_at(self, x) -> tuple[np.ndarray, np.ndarray]:
        """(seed scatter, net error) at x: the net's, its error scaled by what the runs leave."""
        if hasattr(self.net, "errors_at"):
            seed, err = self.net.errors_at(x)
        else:
            m = len(np.atleast_2d(x))
            seed, err = np.full(m, self.net.seed_sd), np.full(m, self.net.net_error)
        return (seed * self.seed_scale[0],
                err * self.error_scale * np.sqrt(np.maximum(self.variance_fraction(x), FLOOR ** 2)))

    @property
    def seed_sd(self) -> float:
        return float(self.net.seed_sd) * self.seed_scale[0]

    @property
    def net_error(self) -> float:
        """Pooled: the error at the runs' own inputs (where the refinement put them)."""
        return float(np.sqrt(np.mean(self.errors_at(self.x)[1] ** 2)))

    def loo_rmse(self) -> float:
        return float(np.sqrt(np.mean(self.loo_residuals ** 2)))

    def raw_rmse(self) -> float:
        """The global net's RMSE at the runs (before the correction)."""
        return float(np.sqrt(np.mean(self.residuals ** 2)))
