"""What a campaign store offers the calibration, in one place: which of its runs count as
measurements of a quantity (counted_runs), its training table per quantity (with the runs of the
stores pooled with it), the conditions its preset fixes, and the seed-to-seed scatter its
replicate companions measure (<name>_replicates.h5)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..campaign import Campaign
from ..quantity_table import fraction_of_metric
from .pooled_runs import pooled_params
from .quantities import CONDITIONS, QUANTITIES, Quantity


# A hopper run that did not empty (it jammed, or flowed too slowly for the time limit) measured no
# discharge time, and no flow rate either: its 20-80 % slope mixes flow with an arch's standstill
# (a run that jammed after 1.8 kg/s reports 0.3). Such runs are neither measurements (confirm.rig_values)
# nor surrogate training rows or replicates (counted_runs): with them in, the default stores' flow-rate net
# had a cross-validated R^2 of 0.965 (RMSE 0.139 kg/s) and predicted negative flows in 5 % of the
# box; without, 0.982 (0.091 kg/s).
DISCHARGE_METRICS = ("mass_flow_rate", "discharge_time")

def counted_runs(store, column: str) -> np.ndarray:
    """(runs,) bool: the store's finished runs whose value in metric column `column` counts as a
    measurement: finite, and for a hopper's discharge metrics, from a hopper that emptied."""
    j = store.metric_names.index(column)
    ok = (store.status == 1) & np.isfinite(store.values[:, j])
    if store.spec.rig == "hopper" and column in DISCHARGE_METRICS and "discharge_time" in store.metric_names:
        ok &= np.isfinite(store.values[:, store.metric_names.index("discharge_time")])
    return ok

def fraction_columns(metric_names: list[str]) -> list[tuple[int, float]]:
    """(column, shear fraction) of each per-shear-point metric (mu_ie_s_40 -> 0.4) of a store."""
    out = []
    for j, name in enumerate(metric_names):
        fraction = fraction_of_metric(name)
        if fraction is not None:
            out.append((j, fraction))
    return out

def training_tables(store, pooled=()) -> dict[Quantity, tuple[list[str], np.ndarray, np.ndarray]]:
    """{Quantity: (input names, inputs, values)} over the store's finished runs and those of the
    stores pooled with it (pooled_runs.py: their runs mapped into this store's parameter
    columns). Ring-shear runs give one mu_ie_s row per shear point, the fraction as an extra
    input."""
    rig = store.spec.rig
    names = list(store.spec.names)
    sources = [(store, store.params)] + [(o, pooled_params(store, o)) for o in pooled]
    out = {}
    for metric in QUANTITIES[rig]:
        q = Quantity(rig, metric)
        xs, ys, fractions = [], [], set()
        for st, params in sources:
            if metric == "mu_ie_s":
                for j, frac in fraction_columns(st.metric_names):
                    ok = counted_runs(st, st.metric_names[j])
                    xs.append(np.column_stack([params[ok], np.full(ok.sum(), frac)]))
                    ys.append(st.values[ok, j])
                    fractions.add(frac)
            elif metric in st.metric_names:
                j = st.metric_names.index(metric)
                ok = counted_runs(st, metric)
                xs.append(params[ok])
                ys.append(st.values[ok, j])
        if not xs:
            continue
        if metric != "mu_ie_s":
            out[q] = (names, np.vstack(xs), np.concatenate(ys))
        elif len(fractions) > 1:
            out[q] = (names + ["shear_fraction"], np.vstack(xs), np.concatenate(ys))
        else:  # one shear point: the fraction is a fixed condition of the store, not an input
            out[q] = (names, np.vstack(xs)[:, :-1], np.concatenate(ys))
    return out

def preset_conditions(store) -> dict[str, float]:
    """The conditions the store's runs have when they do not vary them (its preset with the
    campaign's fixed settings): the defaults for rows that do not give them."""
    cfg = store.spec.config({})
    out = {}
    for cname in CONDITIONS[store.spec.rig]:
        if cname == "shear_fraction":
            points = getattr(cfg, "shear_points", None) or []
            if len(points) == 1:  # a single shear point is the store's fixed fraction
                out[cname] = float(points[0])
            continue
        v = getattr(cfg, cname, None)
        if v is not None:
            out[cname] = float(v)
    return out

def metric_columns(metric: str, metric_names: list[str]) -> list[str]:
    """The store columns of a quantity's metric: itself, or mu_ie_s's shear-point columns."""
    if metric == "mu_ie_s":
        return [metric_names[j] for j, _ in fraction_columns(metric_names)]
    return [metric] if metric in metric_names else []

def replicate_store_paths(store, pooled=()) -> list[Path]:
    """Where a store's seed-scatter companions live: <name>_replicates.h5 next to it and next to
    each store pooled with it (same rig and preset), those that exist. Several: replicates over
    the whole box and on the one-effect axes, where the base model's scatter is (the box's
    replicate points are nearly all cohesive)."""
    paths = [st.path.with_name(st.path.stem + "_replicates.h5") for st in (store, *pooled)]
    return [p for p in paths if p.exists()]

def replicate_stores(store, pooled=()) -> list:
    """The store's replicate stores, opened (replicate_store_paths)."""
    return [Campaign.open(p).store for p in replicate_store_paths(store, pooled)]

def seed_scatter(reps) -> dict[Quantity, float]:
    """Pooled seed-to-seed standard deviation of one run per quantity, from replicate stores
    (the shear points of one quantity pooled together)."""
    acc: dict[Quantity, list] = {}
    for store in reps:
        rig = store.spec.rig
        for metric in QUANTITIES[rig]:
            names = [metric] if metric in store.metric_names else []
            if metric == "mu_ie_s":
                names += [store.metric_names[j] for j, _ in fraction_columns(store.metric_names)]
            a = acc.setdefault(Quantity(rig, metric), [0.0, 0])
            for m in names:
                _, _, counts, sd = store.point_table(m, rows=counted_runs(store, m))
                k = int((counts - 1).sum())
                if k > 0 and np.isfinite(sd):
                    a[0], a[1] = a[0] + sd * sd * k, a[1] + k
    return {q: float(np.sqrt(ss / dof)) for q, (ss, dof) in acc.items() if dof > 0}

def replicate_groups(store, reps, net) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(sd, dof, inputs) of every replicated point of the replicate stores `reps` (each shear
    point its own group) for the quantity of a net (surrogates.QuantityNet): the runs' sample sd at the point, its degrees of
    freedom (runs - 1), and the point's inputs in the net's columns (each replicate store's
    parameters mapped into `store`'s, as pooling does, plus the shear fraction)."""
    q = net.quantity
    sd, dof, xs = [], [], []
    for rep in reps:
        params = pooled_params(store, rep)
        if q.metric == "mu_ie_s":
            cols = list(fraction_columns(rep.metric_names))
        else:
            cols = [(rep.metric_names.index(q.metric), None)] if q.metric in rep.metric_names else []
        for j, frac in cols:
            counted = counted_runs(rep, rep.metric_names[j])
            for p in np.unique(rep.points):
                k = (rep.points == p) & counted
                if k.sum() < 2:
                    continue
                x = params[k][0] if frac is None or "shear_fraction" not in net.input_names else np.r_[params[k][0], frac]
                if len(x) != len(net.input_names):
                    continue
                sd.append(rep.values[k, j].std(ddof=1))
                dof.append(k.sum() - 1)
                xs.append(x)
    return np.array(sd), np.array(dof, dtype=float), np.array(xs).reshape(len(xs), len(net.input_names))

def replicate_deviations(reps, columns: list[str]) -> list[np.ndarray]:
    """Per replicated point of the stores `reps` that measure every metric column in `columns`:
    its runs' deviations from the point's mean, each column in units of its sd at the point
    ((runs, columns); runs counted for every column, at least 3, every sd positive)."""
    dev = []
    for rep in reps:
        if not all(c in rep.metric_names for c in columns):
            continue
        idx = [rep.metric_names.index(c) for c in columns]
        ok = np.all([counted_runs(rep, c) for c in columns], axis=0)
        for p in np.unique(rep.points):
            v = rep.values[(rep.points == p) & ok][:, idx]
            if len(v) < 3:
                continue
            sd = v.std(axis=0, ddof=1)
            if np.all(sd > 0):
                dev.append((v - v.mean(axis=0)) / sd)
    return dev
