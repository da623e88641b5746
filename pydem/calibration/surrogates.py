"""Surrogates that know conditions and effects: one net per Quantity, f(theta, eta, x).

Trained once per campaign store (nn.mlp.select_net: tanh MLP, SCG, hidden size by the one-SE
rule on a 15 % hold-out) and cached next to the store as plain arrays (`<store>.nets/`, keyed by
a hash of the store's runs), so a diagnosis loads them in milliseconds and gets the same
numbers on every machine. Evaluation and Jacobians are numpy (one hidden layer: the Jacobian
is analytic).

Each net's error model is its hold-out RMSE against single runs: the rig's seed-to-seed
scatter and the net's own error together, which is what separates one DEM run (or one lab
repeat) from the surrogate's smooth mean; the diagnosis adds it to every row's measurement
uncertainty. A quantity measured at several points of one test (the shear points of one
ring-shear run) also carries how much those points' errors go together: one specimen, one
packing (`test_correlation`, measured on the store's runs)."""
from __future__ import annotations

import hashlib
import json
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .quantities import Quantity, fraction_columns, training_tables

NET_FORMAT = 1
SIZES = (3, 6, 10, 16, 24)
RESTARTS = 2


@dataclass
class QuantityNet:
    quantity: Quantity
    input_names: list[str]
    lo: np.ndarray          # input scaling: [lo, hi] -> [-1, 1]
    hi: np.ndarray
    y_lo: float
    y_hi: float
    w1: np.ndarray          # hidden x inputs
    b1: np.ndarray
    w2: np.ndarray          # hidden
    b2: float
    rmse: float             # hold-out RMSE against single runs (scatter + net error)
    r2: float               # hold-out R^2
    runs: int
    unit: str = ""
    scatter: float = float("nan")  # seed-to-seed sd of one run, from replicate runs (nan: unknown)
    test_correlation: float = 0.0  # correlation of one run's errors at its several points (shear points)

    @property
    def seed_sd(self) -> float:
        """One run's seed-to-seed scatter: measured from replicates, else the whole hold-out RMSE
        (a store without replicates cannot split its error; all of it counts as scatter)."""
        return self.scatter if np.isfinite(self.scatter) else self.rmse

    @property
    def net_error(self) -> float:
        """The net's own error: its hold-out RMSE less the seed scatter it contains, at least a fifth
        of the RMSE (also when the scatter is unknown)."""
        return float(np.sqrt(max(self.rmse ** 2 - self.seed_sd ** 2, (0.2 * self.rmse) ** 2)))

    def row_sigma(self, u: float) -> float:
        """Standard deviation of measured - surrogate for a row with stated uncertainty u: a measured
        value scatters at least as much as one rig run does (a lab's repeat scatter is not smaller
        than the model specimen's), so max(u, seed scatter), plus the net's error."""
        return float(np.sqrt(max(u, self.seed_sd) ** 2 + self.net_error ** 2))

    def _hidden(self, x: np.ndarray):
        s = (x - self.lo) * (2.0 / (self.hi - self.lo)) - 1.0
        return np.tanh(s @ self.w1.T + self.b1)

    def __call__(self, x: np.ndarray) -> np.ndarray:
        """x: (m, inputs) -> (m,)"""
        h = self._hidden(np.atleast_2d(x))
        return (h @ self.w2 + self.b2 + 1.0) * (0.5 * (self.y_hi - self.y_lo)) + self.y_lo

    def gradient(self, x: np.ndarray) -> np.ndarray:
        """x: (m, inputs) -> (m, inputs): d f / d x."""
        h = self._hidden(np.atleast_2d(x))
        g = ((1.0 - h * h) * self.w2) @ self.w1  # d y_s / d s
        return g * (2.0 / (self.hi - self.lo)) * (0.5 * (self.y_hi - self.y_lo))

    @property
    def name(self) -> str:
        """File and C name: ring_shear__mu_ie_s."""
        return f"{self.quantity.rig.replace('-', '_')}__{self.quantity.metric}"

    def export_arrays(self):
        """The net as nn.export.NetArrays (weights file for libdem, standalone C)."""
        from nn.export import NetArrays
        return NetArrays(self.name, self.unit, list(self.input_names), self.lo, self.hi, self.y_lo, self.y_hi,
                         self.w1, self.b1, self.w2, self.b2)

    def to_arrays(self) -> dict:
        return {"lo": self.lo, "hi": self.hi, "w1": self.w1, "b1": self.b1, "w2": self.w2,
                "meta": np.array(json.dumps({"rig": self.quantity.rig, "metric": self.quantity.metric,
                                             "inputs": self.input_names, "y_lo": self.y_lo, "y_hi": self.y_hi,
                                             "b2": self.b2, "rmse": self.rmse, "r2": self.r2, "runs": self.runs,
                                             "unit": self.unit, "scatter": self.scatter,
                                             "test_correlation": self.test_correlation, "format": NET_FORMAT}))}

    @classmethod
    def from_arrays(cls, a) -> "QuantityNet":
        meta = json.loads(str(a["meta"]))
        return cls(Quantity(meta["rig"], meta["metric"]), meta["inputs"], a["lo"], a["hi"], meta["y_lo"], meta["y_hi"],
                   a["w1"], a["b1"], a["w2"], meta["b2"], meta["rmse"], meta["r2"], meta["runs"], meta["unit"],
                   meta.get("scatter", float("nan")), meta.get("test_correlation", 0.0))


def replicate_store_path(store) -> Path:
    """Where a store's seed-scatter companion lives: <name>_replicates.h5 next to it."""
    return store.path.with_name(store.path.stem + "_replicates.h5")


def seed_scatter(store) -> dict[Quantity, float]:
    """Pooled seed-to-seed standard deviation of one run per quantity, from a store with
    replicates (the shear points of one quantity pooled together)."""
    from .quantities import QUANTITIES
    out = {}
    rig = store.spec.rig
    for metric in QUANTITIES[rig]:
        names = [metric] if metric in store.metric_names else []
        if metric == "mu_ie_s":
            names += [store.metric_names[j] for j, _ in fraction_columns(store.metric_names)]
        ss, dof = 0.0, 0
        for m in names:
            _, means, counts, sd = store.point_table(m)
            k = int((counts - 1).sum())
            if k > 0 and np.isfinite(sd):
                ss, dof = ss + sd * sd * k, dof + k
        if dof > 0:
            out[Quantity(rig, metric)] = float(np.sqrt(ss / dof))
    return out


def test_correlation(store, net: QuantityNet) -> float:
    """How much one run's errors at its several points (the shear fractions of one ring-shear
    run) go together: the mean correlation between the net's residuals at two points of the
    same run, over the store's finished runs (in-sample residuals: seed scatter and the net's
    misfit, which is what a measurement of the same test shares); clipped to [0, 0.95]; 0 for a
    quantity measured once per run."""
    points = fraction_columns(store.metric_names)
    if "shear_fraction" not in net.input_names or len(points) < 2:
        return 0.0
    cols = np.array([store.values[:, j] - net(np.column_stack([store.params, np.full(len(store.params), frac)]))
                     for j, frac in points]).T
    r = cols[(store.status == 1) & np.all(np.isfinite(cols), axis=1)]
    if len(r) < 10:
        return 0.0
    c = np.corrcoef(r.T)
    return float(np.clip(c[np.triu_indices(len(points), 1)].mean(), 0.0, 0.95))


def store_hash(store, pooled=()) -> str:
    h = hashlib.sha256()
    rep = replicate_store_path(store)
    if rep.exists():
        h.update(rep.read_bytes())
    for st in (store, *pooled):
        h.update(st.spec.to_json().encode())
        h.update(json.dumps(st.metric_names).encode())
        for a in (st.params, st.values, st.status):
            h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()[:16]


def cache_dir(store) -> Path:
    return store.path.with_name(store.path.name + ".nets")


def train(store, say=print, pooled=()) -> dict[Quantity, QuantityNet]:
    """Trains one net per quantity of the store and the stores pooled with it (seeded,
    deterministic on one machine)."""
    from nn.mlp import select_net
    nets = {}
    for q, (names, x, y) in training_tables(store, pooled).items():
        if len(y) < 20:
            say(f"  {q.key}: {len(y)} finished runs, too few to train a surrogate; skipped")
            continue
        t0 = time.perf_counter()
        net, _ = select_net(q.key, names, x, y, sizes=SIZES, restarts=RESTARTS, seed=0)
        lin1, lin2 = net.model.hidden, net.model.out
        unit = ""
        if q.metric in store.metric_names:
            unit = store.metric_units[store.metric_names.index(q.metric)]
        nets[q] = QuantityNet(q, list(names), net.x_scaler.lo.copy(), net.x_scaler.hi.copy(), float(net.y_scaler.lo[0]),
                              float(net.y_scaler.hi[0]), lin1.weight.detach().numpy().copy(),
                              lin1.bias.detach().numpy().copy(), lin2.weight.detach().numpy()[0].copy(),
                              float(lin2.bias.detach().numpy()[0]), float(net.info["holdout_rmse"]),
                              float(net.info["holdout_r2"]), int(len(y)), unit)
        say(f"  {q.key:28s} {len(y):4d} rows  hidden {net.hidden:2d}  hold-out R^2 {net.info['holdout_r2']:.3f}  "
            f"RMSE {net.info['holdout_rmse']:.4g}  ({time.perf_counter() - t0:.0f} s)")
    return nets


def load_or_train(store, say=print, retrain: bool = False, pooled=()) -> dict[Quantity, QuantityNet]:
    """The store's nets from its cache when they were trained on exactly these runs (its own and
    those of the stores pooled with it, pooled_runs.py), else trained now and cached."""
    d = cache_dir(store)
    key = store_hash(store, pooled)
    stamp = d / "store_hash.txt"
    if not retrain and stamp.exists() and stamp.read_text().strip() == key:
        nets = {}
        for f in sorted(d.glob("*.npz")):
            with np.load(f) as a:
                n = QuantityNet.from_arrays(a)
                stale = "test_correlation" not in str(a["meta"])  # cached before it was measured
            if stale:
                n.test_correlation = test_correlation(store, n)
                np.savez(f, **n.to_arrays())
            nets[n.quantity] = n
        return nets
    extra = "".join(f" + {(o.status == 1).sum()} of {o.path.name}" for o in pooled)
    say(f"training surrogates for {store.path.name} ({(store.status == 1).sum()} finished runs{extra}; cached in {d})")
    nets = train(store, say, pooled)
    rep = replicate_store_path(store)
    if rep.exists():
        from ..campaign import Campaign
        for q, sd in seed_scatter(Campaign.open(rep).store).items():
            if q in nets:
                nets[q].scatter = sd
                say(f"  {q.key:28s} seed scatter {sd:.4g} (from {rep.name})")
    for q, n in nets.items():
        n.test_correlation = test_correlation(store, n)
        if n.test_correlation:
            say(f"  {q.key:28s} errors of one run's points correlated {n.test_correlation:.2f}")
    d.mkdir(exist_ok=True)
    for old in d.glob("*.npz"):
        old.unlink()
    for q, n in nets.items():
        np.savez(d / f"{q.metric}.npz", **n.to_arrays())
    stamp.write_text(key + "\n")
    return nets
