"""Surrogates that know conditions and effects: one net per Quantity, f(theta, eta, x).

Trained once per campaign store (nn.mlp.bagged_net: the mean of BAG tanh MLPs trained with SCG
on all runs, itself one wider net; the members' hidden size the one of SIZES with the lowest
FOLDS-fold cross-validated RMSE; a positive quantity learnt as its log where that RMSE is lower)
and cached next to the store as plain arrays (`<store>.nets/<hash>/`, keyed by
a hash of the runs trained on), so a diagnosis loads them in milliseconds and gets the same
numbers on every machine. Evaluation and Jacobians are numpy (one hidden layer: the Jacobian
is analytic).

Each net's error model is its cross-validated RMSE against single runs (FOLDS folds, one run's
rows in one fold): the rig's seed-to-seed
scatter and the net's own error together, which is what separates one DEM run (or one lab
repeat) from the surrogate's smooth mean; the diagnosis adds it to every row's measurement
uncertainty. A quantity measured at several points of one test (the shear points of one
ring-shear run) also carries how much those points' errors go together: one specimen, one
packing (`test_correlation`); and the different quantities one run measures share its scatter
too (`run_correlation`: a hopper run that flows slowly also empties late), both measured on the
replicate runs. The error model (`fit_error_model`)
says where the error is; the replicate runs say which part of it is seed scatter — one pooled sd,
or a fixed fraction of the error model's sd where the replicates vary with it (`fit_scatter_ratio`)."""
from __future__ import annotations

import hashlib
import json
import os
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from nn.export import NetArrays, arrays_of

from .fit import scatter_correlations
from .quantities import Observation, Quantity
from .store_data import (fraction_columns, metric_columns, replicate_deviations, replicate_groups,
                         replicate_store_paths, replicate_stores, seed_scatter, training_tables)

NET_FORMAT = 3  # 3: bagged nets with an error model, log target where it fits better (older caches are retrained)
SIZES = (3, 6, 10, 16)  # hidden units per bagged member, chosen by the cross-validated RMSE
BAG = 4     # nets averaged per quantity (nn.mlp.bagged_net)
FOLDS = 5   # cross-validation folds for the error model
ERROR_SPAN = 5.0  # the error model's sd stays within [RMSE / 5, RMSE * 5]


@dataclass
class QuantityNet:
    quantity: Quantity
    mlp: NetArrays          # the net itself: inputs, their scaling box, weights (what libdem's routine loads)
    rmse: float             # cross-validated RMSE against single runs (scatter + net error)
    r2: float               # cross-validated R^2
    runs: int
    scatter: float = float("nan")  # seed-to-seed sd of one run, from replicate runs (nan: unknown)
    test_correlation: float = 0.0  # correlation of one run's errors at its several points (shear points)
    # where the error is: log sd of one run about the net = err_c0 + err_c . (scaled inputs), fitted
    # to the cross-validated residuals (fit_error_model); None: the RMSE everywhere
    err_c0: float = float("nan")
    err_c: np.ndarray | None = None
    # the seed scatter where the error model is: a fixed fraction of the total sd at a point, when the
    # replicates say so (fit_scatter_ratio); nan: the pooled `scatter` everywhere
    scatter_ratio: float = float("nan")
    # correlation of one run's seed scatter with the other quantities the same run measures
    # ({metric: rho}, run_correlations); measured from the replicates when the nets are loaded
    run_correlation: dict = field(default_factory=dict)

    @property
    def seed_sd(self) -> float:
        """One run's seed-to-seed scatter: measured from replicates, else the whole cross-validated RMSE
        (a store without replicates cannot split its error; all of it counts as scatter)."""
        return self.scatter if np.isfinite(self.scatter) else self.rmse

    @property
    def net_error(self) -> float:
        """The net's own error: its cross-validated RMSE less the seed scatter it contains, at least a fifth
        of the RMSE (also when the scatter is unknown)."""
        return float(np.sqrt(max(self.rmse ** 2 - self.seed_sd ** 2, (0.2 * self.rmse) ** 2)))

    def total_sd(self, x: np.ndarray) -> np.ndarray:
        """(m,): sd of one run about the net at inputs x (m, inputs): the error model where there is
        one (inputs clipped to the campaign box, the sd to [RMSE / ERROR_SPAN, RMSE * ERROR_SPAN]),
        else the RMSE."""
        x = np.atleast_2d(x)
        if self.err_c is None:
            return np.full(len(x), self.rmse)
        return np.clip(np.exp(self.err_c0 + self.scaled(x, clip=True) @ self.err_c), self.rmse / ERROR_SPAN, self.rmse * ERROR_SPAN)

    def errors_at(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(seed scatter, net error), each (m,), at inputs x: the seed scatter a fixed fraction of the
        total sd there where the replicates scatter in step with the error model (scatter_ratio),
        else their pooled scatter, at most the total sd (the pooled value comes from a few points;
        where the net's runs scatter less, so does a repeat); the rest the net's, at least a fifth
        of the total."""
        t = self.total_sd(x)
        if np.isfinite(self.scatter_ratio):
            seed = np.minimum(self.scatter_ratio, 1.0) * t
        else:
            seed = np.minimum(self.scatter, t) if np.isfinite(self.scatter) else t
        return seed, np.sqrt(np.maximum(t * t - seed * seed, (0.2 * t) ** 2))

    # the net's inputs and output as the rest of the chain asks for them
    input_names = property(lambda self: self.mlp.input_names)
    lo = property(lambda self: self.mlp.lo)
    hi = property(lambda self: self.mlp.hi)
    unit = property(lambda self: self.mlp.unit)
    log_output = property(lambda self: self.mlp.log_output)  # learnt log(value): f = exp(scaled output)

    def scaled(self, x: np.ndarray, clip: bool = False) -> np.ndarray:
        return self.mlp.scaled(x, clip)

    def __call__(self, x: np.ndarray) -> np.ndarray:
        """x: (m, inputs) -> (m,)"""
        return self.mlp(x)

    def gradient(self, x: np.ndarray) -> np.ndarray:
        """x: (m, inputs) -> (m, inputs): d f / d x."""
        return self.mlp.gradient(x)

    @property
    def name(self) -> str:
        """File and C name: ring_shear__mu_ie_s."""
        return net_name(self.quantity)

    def to_arrays(self) -> dict:
        m = self.mlp
        return {"lo": m.lo, "hi": m.hi, "w1": m.w1, "b1": m.b1, "w2": m.w2,
                "meta": np.array(json.dumps({"rig": self.quantity.rig, "metric": self.quantity.metric,
                                             "inputs": m.input_names, "y_lo": m.y_lo, "y_hi": m.y_hi,
                                             "b2": m.b2, "rmse": self.rmse, "r2": self.r2, "runs": self.runs,
                                             "unit": self.unit, "scatter": self.scatter,
                                             "test_correlation": self.test_correlation, "err_c0": self.err_c0,
                                             "log_output": self.log_output, "scatter_ratio": self.scatter_ratio,
                                             "format": NET_FORMAT})),
                **({"err_c": self.err_c} if self.err_c is not None else {})}

    @classmethod
    def from_arrays(cls, a) -> "QuantityNet":
        meta = json.loads(str(a["meta"]))
        q = Quantity(meta["rig"], meta["metric"])
        mlp = NetArrays(net_name(q), meta["unit"], meta["inputs"], a["lo"], a["hi"], meta["y_lo"], meta["y_hi"],
                        a["w1"], a["b1"], a["w2"], meta["b2"], meta.get("log_output", False))
        return cls(q, mlp, meta["rmse"], meta["r2"], meta["runs"],
                   meta.get("scatter", float("nan")), meta.get("test_correlation", 0.0), meta.get("err_c0", float("nan")),
                   np.array(a["err_c"]) if "err_c" in getattr(a, "files", a) else None,
                   meta.get("scatter_ratio", float("nan")))


def net_name(q: Quantity) -> str:
    """A quantity's net as a file and C name: ring_shear__mu_ie_s."""
    return f"{q.rig.replace('-', '_')}__{q.metric}"


def fit_error_model(net: QuantityNet, x: np.ndarray, residuals: np.ndarray, prior_sd: float = 0.5):
    """log sd(x) = c0 + c . s(x) (s: the net's scaled inputs) by maximum a posteriori on the
    cross-validated residuals r_i ~ N(0, sd(x_i)^2), each c_j with a N(0, prior_sd^2) prior (a
    one-unit step of a scaled input changes the sd by ~exp(0.5) at most, unless the residuals
    insist). Why: a net's error is not one number over the box — on the default stores the
    ring-shear bulk density's sd is 67 kg/m^3 at the top cohesion and lowest pre-shear against 15
    at a free-flowing mid-box point, the angle of repose's 8.6 against 3.0 deg — and one pooled
    RMSE makes a free-flowing material's rows look 2-4x less certain than they are
    (docs/diagnosis.md §3). The objective is convex."""
    from scipy import optimize
    s = net.scaled(x, clip=True)
    r2 = np.asarray(residuals, dtype=float) ** 2
    ok = np.isfinite(r2) & np.all(np.isfinite(s), axis=1)
    s, r2 = s[ok], r2[ok]
    a = np.column_stack([np.ones(len(s)), s])
    scale = np.r_[0.0, np.full(s.shape[1], 1.0 / prior_sd ** 2)]

    def f(c):
        eta = a @ c
        w = r2 * np.exp(-2.0 * eta)
        return float(np.sum(eta + 0.5 * w) + 0.5 * np.sum(scale * c * c)), a.T @ (1.0 - w) + scale * c

    c0 = np.r_[0.5 * np.log(np.mean(r2) + 1e-300), np.zeros(s.shape[1])]
    res = optimize.minimize(f, c0, jac=True, method="L-BFGS-B")
    net.err_c0, net.err_c = float(res.x[0]), res.x[1:].copy()


def fit_scatter_ratio(net: QuantityNet, sd: np.ndarray, dof: np.ndarray, x: np.ndarray) -> float:
    """The seed scatter's shape over the campaign box, from the replicated points: one pooled sd
    everywhere, or a fixed fraction r of the error model's total sd at each point (a rig scatters
    more where its runs are hard to predict: on the default ring shear, at low particle and high
    wall friction, one shear point's runs spread by 0.17 in mu_ie_s, at others by 0.02). Both have
    one parameter (its maximum-likelihood value from the points' sample variances); the one whose
    Gaussian likelihood of those variances is higher is kept. Returns r, or nan for the pooled sd
    (also without replicates or an error model)."""
    if len(sd) < 3 or net.err_c is None or dof.sum() <= 0:
        return float("nan")
    t = net.total_sd(x)
    v = sd * sd

    def loglik(s2):  # each point's sample variance: dof * v / s2 ~ chi^2(dof)
        return float(np.sum(-0.5 * dof * (np.log(s2) + v / s2)))

    pooled = np.sum(dof * v) / dof.sum()
    r2 = np.sum(dof * v / (t * t)) / dof.sum()
    if pooled <= 0 or loglik(r2 * t * t) <= loglik(np.full(len(v), pooled)):
        return float("nan")
    return float(np.sqrt(r2))


def test_correlation(store, net: QuantityNet, reps=()) -> float:
    """How much one run's seed scatter at its several points (the shear fractions of one ring-
    shear run) goes together, clipped to [0, 0.95]; 0 for a quantity measured once per run. From
    the replicate stores `reps` where they have at least 5 points with 3 or more runs: the mean
    correlation, between two shear points, of the runs' deviations from their point's mean (each
    point's and shear point's deviations in units of their sd). Else from the store's runs: the
    mean correlation of the net's in-sample residuals at two points of one run — an upper bound,
    as those residuals also carry the net's misfit, smooth over the fraction, which the
    likelihood already shares between the points (fit.Model)."""
    points = fraction_columns(store.metric_names)
    if "shear_fraction" not in net.input_names or len(points) < 2:
        return 0.0
    cols = [store.metric_names[j] for j, _ in points]
    dev = replicate_deviations(reps, cols)
    if len(dev) >= 5:
        c = np.corrcoef(np.vstack(dev).T)
        return float(np.clip(c[np.triu_indices(len(cols), 1)].mean(), 0.0, 0.95))
    cols = np.array([store.values[:, j] - net(np.column_stack([store.params, np.full(len(store.params), frac)]))
                     for j, frac in points]).T
    r = cols[(store.status == 1) & np.all(np.isfinite(cols), axis=1)]
    if len(r) < 10:
        return 0.0
    c = np.corrcoef(r.T)
    return float(np.clip(c[np.triu_indices(len(points), 1)].mean(), 0.0, 0.95))


def run_correlations(reps, metrics: list[str]) -> dict[tuple[str, str], float]:
    """{(a, b): rho} for every pair of different metrics that one run of the rig measures: the
    correlation of the runs' seed deviations (replicate_deviations, pooled over the stores'
    points; for mu_ie_s the mean over its shear points), where at least 5 points with 3 or more
    runs measure both; else absent (0). On the shipped default stores: a hopper
    run's flow rate and discharge time -0.5 / -0.74 (whole box / one-effect axes), a ring-shear
    run's mu_ie_ps and bulk density 0.41 / 0.16 (same point, same packing)."""
    out = {}
    names = reps[0].metric_names if reps else []
    for i, a in enumerate(metrics):
        for b in metrics[i + 1:]:
            ca, cb = metric_columns(a, names), metric_columns(b, names)
            if not ca or not cb:
                continue
            dev = replicate_deviations(reps, ca + cb)
            if len(dev) < 5:
                continue
            c = np.corrcoef(np.vstack(dev).T)[:len(ca), len(ca):]
            out[(a, b)] = out[(b, a)] = float(np.clip(c.mean(), -0.95, 0.95))
    return out


def one_run_correlation(nets: list[QuantityNet], rho: dict[tuple[str, str], float]) -> np.ndarray:
    """The seed scatter's correlation matrix over the rows of one run (each quantity once, a
    quantity with a shear fraction at three points), with the cross-quantity terms `rho`."""
    row_nets = [n for n in nets for _ in range(3 if "shear_fraction" in n.input_names else 1)]
    rows, seen = [], {}
    for n in row_nets:  # one test: no condition but the shear fraction, which tells its points apart
        k = seen[id(n)] = seen.get(id(n), -1) + 1
        rows.append(Observation(n.quantity, {"shear_fraction": 0.3 * (k + 1)} if "shear_fraction" in n.input_names else {},
                                1.0, 0.0, n.quantity.key))
    return scatter_correlations(rows, row_nets, rho)


def attach_run_correlations(nets: list[QuantityNet], reps, say=print) -> None:
    """Sets each net's `run_correlation` from the replicate stores `reps` of its rig. Pairwise
    estimates need not make a valid correlation matrix together: the cross-quantity terms are
    scaled down (by 10 % steps) until one run's matrix is positive definite."""
    rho = run_correlations(reps, [n.quantity.metric for n in nets])
    for shrink in np.linspace(1.0, 0.0, 11):
        scaled = {k: float(v * shrink) for k, v in rho.items()}
        if np.linalg.eigvalsh(one_run_correlation(nets, scaled)).min() > 1e-3:
            break
    for n in nets:
        n.run_correlation = {b: v for (a, b), v in scaled.items() if a == n.quantity.metric}
    for (a, b), v in scaled.items():
        if a < b:
            say(f"  {nets[0].quantity.rig}: seed scatter of one run's {a} and {b} correlated {v:+.2f}")


def store_hash(store, pooled=()) -> str:
    h = hashlib.sha256()
    h.update(f"nets {NET_FORMAT} bag {BAG} folds {FOLDS} sizes {SIZES} error span {ERROR_SPAN}".encode())
    for rep in replicate_store_paths(store, pooled):
        h.update(rep.read_bytes())
    for st in (store, *pooled):
        h.update(st.spec.to_json().encode())
        h.update(json.dumps(st.metric_names).encode())
        for a in (st.params, st.values, st.status):
            h.update(np.ascontiguousarray(a).tobytes())
    for q, (names, x, y) in sorted(training_tables(store, pooled).items(), key=lambda kv: kv[0].key):
        h.update(f"{q.key} {names}".encode())  # the rows trained on: a change of which runs count retrains
        h.update(np.ascontiguousarray(x).tobytes() + np.ascontiguousarray(y).tobytes())
    return h.hexdigest()[:16]


SLOTS = 3  # trained sets kept per store: its own runs, with and without the stores pooled with it, ...


def cache_dir(store) -> Path:
    """Where a store's trained nets live: one sub-folder per training set (store_hash), so that the
    same store loaded alone and pooled with another does not retrain over the other's nets."""
    return store.path.with_name(store.path.name + ".nets")


def _mark_used(stamp: Path):
    """The slot's last use as its stamp's mtime, from the nanosecond clock: the file system's own
    timestamp (touch) is as coarse as a kernel tick, so two loads a few ms apart tied and the
    least recently used slot was a coin toss."""
    now = time.time_ns()
    os.utime(stamp, ns=(now, now))


def _prune_slots(d: Path, keep: Path):
    """The SLOTS most recently used training sets stay; older ones and the older flat layout that kept
    one set per store go."""
    for old in list(d.glob("*.npz")) + [d / "store_hash.txt"]:
        old.unlink(missing_ok=True)
    slots = sorted((p for p in d.iterdir() if p.is_dir() and (p / "store_hash.txt").exists()),
                   key=lambda p: (p != keep, -(p / "store_hash.txt").stat().st_mtime))
    for old in slots[SLOTS:]:
        for f in old.iterdir():
            f.unlink()
        old.rmdir()


def train(store, say=print, pooled=()) -> dict[Quantity, QuantityNet]:
    """Trains one net per quantity of the store and the stores pooled with it (seeded,
    deterministic on one machine). Training needs torch, an optional dependency: without it a
    ValueError says which store lacks cached nets and how to install it."""
    try:
        from nn.mlp import bagged_net, cross_validate  # torch: only where nets are trained
    except ImportError as exc:
        raise ValueError(f"{store.path}: no cached surrogate nets for these runs, and training them needs torch "
                         f"(pip install 'pydem[nn]'; {exc})") from None
    nets = {}
    for q, (names, x, y) in training_tables(store, pooled).items():
        if len(y) < 20:
            say(f"  {q.key}: {len(y)} finished runs, too few to train a surrogate; skipped")
            continue
        t0 = time.perf_counter()
        unit = ""
        if q.metric in store.metric_names:
            unit = store.metric_units[store.metric_names.index(q.metric)]
        # one run's rows (its shear points) are one group: they leave the fit together
        _, groups = np.unique(x[:, :len(store.spec.names)], axis=0, return_inverse=True)
        scores = {h: cross_validate(x, y, groups, h, BAG, folds=FOLDS, seed=0) for h in SIZES}
        h = min(SIZES, key=lambda k: (scores[k]["rmse"], k))
        cv, log_target = scores[h], False
        if np.all(y > 0):  # a positive quantity may be learnt as its log: kept where the CV RMSE says so
            cv_log = cross_validate(x, y, groups, h, BAG, folds=FOLDS, seed=0, log_target=True)
            if cv_log["rmse"] < cv["rmse"]:
                cv, log_target = cv_log, True
        net = bagged_net(q.key, names, x, y, h, BAG, seed=0, unit=unit, log_target=log_target)
        mlp = replace(arrays_of(net), name=net_name(q), input_names=list(names))
        nets[q] = QuantityNet(q, mlp, cv["rmse"], cv["r2"], int(len(y)))
        fit_error_model(nets[q], x, y - cv["predicted"])
        sd = nets[q].total_sd(x)
        say(f"  {q.key:28s} {len(y):4d} rows  {BAG} x {h:2d} hidden{' log' if log_target else ''}  {FOLDS}-fold CV R^2 {cv['r2']:.3f}  "
            f"RMSE {cv['rmse']:.4g}  (sizes " + ", ".join(f"{k}: {scores[k]['r2']:.3f}" for k in SIZES) +
            f"; {time.perf_counter() - t0:.0f} s); error model: sd {np.percentile(sd, 10):.3g}-{np.percentile(sd, 90):.3g} "
            f"(10-90 % of the runs)")
    return nets


def replicate_shape(store, reps, net: QuantityNet) -> tuple[float, float]:
    """(scatter_ratio, test_correlation) of a net from the replicate stores `reps` (without any:
    nan, and the correlation from the store's own runs)."""
    if not reps:
        return float("nan"), test_correlation(store, net)
    return fit_scatter_ratio(net, *replicate_groups(store, reps, net)), test_correlation(store, net, reps)


def load_or_train(store, say=print, retrain: bool = False, pooled=()) -> dict[Quantity, QuantityNet]:
    """The store's nets from its cache when they were trained on exactly these runs (its own and
    those of the stores pooled with it, pooled_runs.py), else trained now and cached."""
    key = store_hash(store, pooled)
    d = cache_dir(store) / key
    stamp = d / "store_hash.txt"
    if not retrain and stamp.exists() and stamp.read_text().strip() == key:
        try:
            _mark_used(stamp)  # recently used: the last set _prune_slots lets go
        except OSError:
            pass  # a read-only checkout
        nets, stale = {}, []
        for f in sorted(d.glob("*.npz")):
            with np.load(f) as a:
                n = QuantityNet.from_arrays(a)
                if "scatter_ratio" not in str(a["meta"]):  # cached before the replicates gave the scatter's shape and correlation
                    stale.append((f, n))
            nets[n.quantity] = n
        reps = replicate_stores(store, pooled) if stale else []
        for f, n in stale:
            n.scatter_ratio, n.test_correlation = replicate_shape(store, reps, n)
            try:
                np.savez(f, **n.to_arrays())
            except OSError:
                pass  # a read-only checkout: measured again on the next load
        return nets
    extra = "".join(f" + {(o.status == 1).sum()} of {o.path.name}" for o in pooled)
    say(f"training surrogates for {store.path.name} ({(store.status == 1).sum()} finished runs{extra}; cached in {d})")
    nets = train(store, say, pooled)
    reps = replicate_stores(store, pooled)
    for q, sd in seed_scatter(reps).items():
        if q in nets:
            nets[q].scatter = sd
            say(f"  {q.key:28s} seed scatter {sd:.4g} (from {', '.join(r.path.name for r in reps)})")
    for q, n in nets.items():
        n.scatter_ratio, n.test_correlation = replicate_shape(store, reps, n)
        if np.isfinite(n.scatter_ratio):
            say(f"  {q.key:28s} seed scatter {n.scatter_ratio:.2f} of the error model's sd (the replicates vary with it)")
        if n.test_correlation:
            say(f"  {q.key:28s} errors of one run's points correlated {n.test_correlation:.2f}")
    d.mkdir(parents=True, exist_ok=True)
    for old in d.glob("*.npz"):
        old.unlink()
    for q, n in nets.items():
        np.savez(d / f"{q.metric}.npz", **n.to_arrays())
    stamp.write_text(key + "\n")
    _mark_used(stamp)
    _prune_slots(d.parent, d)
    return nets
