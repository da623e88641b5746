"""How good can any surrogate be on a campaign, and how close do the MLPs get?

    .venv/bin/python studies/surrogate_training.py data/campaigns/ring_shear_cell.h5 --runs 105
    .venv/bin/python studies/surrogate_training.py data/campaigns/aor_default.h5 --metrics angle_of_repose

Per metric, on the design points' means (replicates averaged):
1. a Gaussian process (ARD squared-exponential kernel + a noise term, maximum marginal
   likelihood): its noise sd estimates the run-to-run scatter, 1 - noise^2 / var the R^2 a
   perfect model gets on these targets, and its leave-one-out R^2 what a smooth interpolator
   reaches; length scales are in units of each parameter's range;
2. a cubic polynomial, leave-one-out R^2 (a simple reference);
3. the MLPs as `nn.mlp.train_net` trains them, against the early-stopping patience: single
   nets of 4 and 8 tanh units, 5 hold-out draws (15 %) x 4 restarts, mean hold-out R^2.
`--runs N` uses only the first N rows of the store (a growing store then gives the same
answer). Results: studies/results/surrogate_training.txt. ~1-2 min per metric on one core."""
import argparse
import itertools

import numpy as np
import torch
from scipy.optimize import minimize

from nn.mlp import PropertyNet, Scaler, holdout_split, r2_score, train_net
from pydem.campaign.store import DONE, PENDING, CampaignStore


def gp_fit(X: np.ndarray, y: np.ndarray):
    """(length scales, noise sd, leave-one-out R^2) of a GP on X in [0, 1]^d."""
    yy = y - y.mean()

    def kernel(p):
        ls, sf2, sn2 = np.exp(p[:-2]), np.exp(p[-2]), np.exp(p[-1])
        d2 = (((X[:, None, :] - X[None, :, :]) / ls) ** 2).sum(-1)
        return sf2 * np.exp(-0.5 * d2) + sn2 * np.eye(len(y))

    def nll(p):
        try:
            L = np.linalg.cholesky(kernel(p))
        except np.linalg.LinAlgError:
            return 1e10
        a = np.linalg.solve(L.T, np.linalg.solve(L, yy))
        return 0.5 * yy @ a + np.log(np.diag(L)).sum()

    best = None
    for ls0 in (0.3, 0.6, 1.0):  # a few starts: the likelihood has local optima
        p0 = [np.log(ls0)] * X.shape[1] + [np.log(yy.var()), np.log(0.05 * yy.var())]
        r = minimize(nll, p0, method="Nelder-Mead", options={"maxiter": 4000, "xatol": 1e-4, "fatol": 1e-6})
        if best is None or r.fun < best.fun:
            best = r
    Ki = np.linalg.inv(kernel(best.x))
    loo = (Ki @ yy) / np.diag(Ki)  # closed-form leave-one-out residuals
    return np.exp(best.x[:-2]), float(np.sqrt(np.exp(best.x[-1]))), 1 - np.mean(loo ** 2) / y.var()


def cubic_loo_r2(X: np.ndarray, y: np.ndarray) -> float:
    Xs = 2 * X - 1
    cols = [np.ones(len(y))] + [np.prod(Xs[:, c], axis=1) for deg in (1, 2, 3)
                                for c in itertools.combinations_with_replacement(range(X.shape[1]), deg)]
    A = np.array(cols).T
    H = A @ np.linalg.solve(A.T @ A + 1e-6 * np.eye(A.shape[1]), A.T)
    r = (y - H @ y) / (1 - np.diag(H))
    return 1 - np.mean(r ** 2) / y.var()


def mlp_holdout_r2(x, y, hidden: int, patience: int, draws: int = 5, restarts: int = 4) -> float:
    r2 = []
    for draw in range(draws):
        fit, hold = holdout_split(len(y), 0.15, draw)
        xsc, ysc = Scaler.fit(x[fit]), Scaler.fit(y[fit, None])
        xs, ys = xsc.forward(x), ysc.forward(y[:, None])[:, 0]
        for k in range(restarts):
            model, _ = train_net(xs[fit], ys[fit], hidden, seed=1000 * hidden + k + 10 * draw, max_fail=patience,
                                 max_epochs=3000)
            r2.append(r2_score(y[hold], PropertyNet("p", [], xsc, ysc, model).predict(x[hold])))
    return float(np.mean(r2))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("store")
    ap.add_argument("--metrics", help="comma-separated (default: the calibration's properties)")
    ap.add_argument("--runs", type=int, help="use only the first N rows of the store")
    ap.add_argument("--patience", default="6,20,50,100,300")
    a = ap.parse_args()
    torch.set_num_threads(1)
    s = CampaignStore.open(a.store)
    if a.runs:
        s.status[a.runs:] = PENDING
    if a.metrics:
        metrics = a.metrics.split(",")
    else:
        from pydem.calibration.quantities import QUANTITIES
        metrics = [m for m in s.metric_names if m in QUANTITIES[s.spec.rig] or m.startswith("mu_ie_s_")]
    lo = np.array([s.spec.ranges[n][0] for n in s.spec.names])
    hi = np.array([s.spec.ranges[n][1] for n in s.spec.names])
    print(f"{a.store}: {int((s.status == DONE).sum())} runs used; parameters {', '.join(s.spec.names)}")
    for m in metrics:
        x, y, counts, _ = s.point_table(m)
        ok = np.isfinite(y)
        x, y, counts = x[ok], y[ok], counts[ok]
        X = (x - lo) / (hi - lo)
        ls, noise, gp_r2 = gp_fit(X, y)
        print(f"{m}: {len(y)} points ({int(counts.sum())} runs), sd over the box {y.std():.4g}")
        print(f"  GP: length scales {' '.join(f'{v:.3g}' for v in ls)}; noise sd {noise:.4g} "
              f"-> ceiling {1 - noise ** 2 / y.var():.3f}; LOO R^2 {gp_r2:.3f}")
        print(f"  cubic polynomial: LOO R^2 {cubic_loo_r2(X, y):.3f}")
        for patience in map(int, a.patience.split(",")):
            r = [mlp_holdout_r2(x, y, h, patience) for h in (4, 8)]
            print(f"  MLP, patience {patience:3d}: mean hold-out R^2 {r[0]:.3f} (4 units), {r[1]:.3f} (8 units)", flush=True)


if __name__ == "__main__":
    main()
