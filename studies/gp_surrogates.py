"""Would Gaussian-process surrogates beat the bagged MLPs? 5-fold cross-validated RMSE and R^2 of
an ARD squared-exponential GP (hyperparameters by maximum marginal likelihood, analytic gradient,
two starts) on exactly the training tables, folds and run grouping that
pydem.calibration.surrogates uses, on the raw and the log target; compare with the `rmse` and
`r2` in each cached net's meta (printed beside). A tried-and-dropped check (studies/JOURNAL.md,
"Gaussian-process surrogates"), not part of the product.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python studies/gp_surrogates.py [stores ...]
"""
import sys
import time
from pathlib import Path

import numpy as np
from scipy import linalg, optimize

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
from nn.mlp import Scaler, fold_of_rows  # noqa: E402
from pydem.calibration.store_data import training_tables  # noqa: E402
from pydem.calibration.surrogates import FOLDS  # noqa: E402
from pydem.calibration.setup import DEFAULT_STORES, load_setup, open_store_groups  # noqa: E402


def neg_log_marginal(theta, x, y):
    d = x.shape[1]
    ls, sf2, sn2 = np.exp(theta[:d]), np.exp(2 * theta[d]), np.exp(2 * theta[d + 1])
    z = x / ls
    diff2 = (z[:, None, :] - z[None, :, :]) ** 2
    kse = sf2 * np.exp(-0.5 * diff2.sum(-1))
    n = len(y)
    try:
        low = linalg.cholesky(kse + (sn2 + 1e-8) * np.eye(n), lower=True)
    except linalg.LinAlgError:
        return 1e10, np.zeros_like(theta)
    a = linalg.cho_solve((low, True), y)
    outer = np.outer(a, a) - linalg.cho_solve((low, True), np.eye(n))
    g = np.array([-0.5 * np.sum(outer * kse * diff2[:, :, j]) for j in range(d)]
                 + [-np.sum(outer * kse), -np.trace(outer) * sn2])
    return 0.5 * y @ a + np.log(np.diag(low)).sum(), g


def gp_predict(xtr, ytr, xte):
    mu, sd = ytr.mean(), ytr.std()
    yt = (ytr - mu) / sd
    d = xtr.shape[1]
    best = None
    for init in ([0.0] * d + [0.0, np.log(0.3)], [np.log(2.0)] * d + [0.0, np.log(0.5)]):
        r = optimize.minimize(neg_log_marginal, np.array(init), args=(xtr, yt), jac=True, method="L-BFGS-B",
                              bounds=[(-3, 4)] * d + [(-3, 3), (-6, 1)])
        best = r if best is None or r.fun < best.fun else best
    th = best.x
    ls, sf2, sn2 = np.exp(th[:d]), np.exp(2 * th[d]), np.exp(2 * th[d + 1])

    def k(a, b):
        a, b = a / ls, b / ls
        return sf2 * np.exp(-0.5 * np.maximum((a ** 2).sum(1)[:, None] + (b ** 2).sum(1)[None, :] - 2 * a @ b.T, 0))
    alpha = linalg.solve(k(xtr, xtr) + (sn2 + 1e-8) * np.eye(len(yt)), yt, assume_a="pos")
    return k(xte, xtr) @ alpha * sd + mu


def main() -> int:
    paths = [Path(p) for p in sys.argv[1:]] or [ROOT / s for s in DEFAULT_STORES]
    nets = load_setup(paths, say=lambda *_: None).nets
    for rig, (store, pooled, _) in open_store_groups(paths).items():
        for q, (names, x, y) in training_tables(store, pooled).items():
            xs = Scaler.fit(x).forward(x)
            _, g = np.unique(x[:, :len(store.spec.names)], axis=0, return_inverse=True)
            fold = fold_of_rows(g, FOLDS, seed=0)  # the folds the nets' cross-validation uses
            net = nets.get(q)
            mlp = f"bagged MLP R^2 {net.r2:.3f} RMSE {net.rmse:.4g}" if net is not None else "no net"
            for log in ([False, True] if np.all(y > 0) else [False]):
                t = np.log(y) if log else y
                pred, t0 = np.full(len(y), np.nan), time.perf_counter()
                for k in range(FOLDS):
                    te = fold == k
                    p = gp_predict(xs[~te], t[~te], xs[te])
                    pred[te] = np.exp(p) if log else p
                rmse = float(np.sqrt(np.mean((pred - y) ** 2)))
                r2 = 1 - np.mean((pred - y) ** 2) / np.var(y)
                print(f"{q.key:26s} {len(y):4d} rows {'log' if log else 'raw'}: GP R^2 {r2:.3f} RMSE {rmse:.4g} "
                      f"({time.perf_counter() - t0:.0f} s) | {mlp}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
