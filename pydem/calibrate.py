"""The calibration job (seed 000 end to end; `pydem calibrate`, `make demo`):

  campaigns (HDF5 stores) -> one MLP per bulk property (hidden size chosen on a 15 % hold-out)
  -> export (weights files for libdem + standalone C) -> one million combinations screened
  natively against the measurements (ring-shear nets) -> narrowed by the angle-of-repose nets
  -> best estimate -> one confirming DEM run per rig -> comparison and a Markdown report."""
from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from . import compare as cmp
from . import screening
from .campaign import Campaign
from .campaign.store import check_same_physics, physics_of
from .measurements import Measurement, load
from .rigs import RIGS
from .rigs.result import strict_json

PROPERTIES = {"ring-shear": ("mu_ie_ps", "mu_ie_s_", "bulk_density"), "aor": ("angle_of_repose", "bulk_density")}
STAGE_ORDER = ("ring-shear", "aor")  # screen on the shear tester, then narrow with the heap (seed 000)


def _say(msg: str):
    print(msg, flush=True)


def property_metrics(rig: str, store) -> list[str]:
    wanted = PROPERTIES.get(rig, ())
    return [m for m in store.metric_names if any(m == w or (w.endswith("_") and m.startswith(w)) for w in wanted)]


def condition_mismatch(m: Measurement, store) -> str:
    """Why the campaign cannot represent the row's conditions ('' when it can): the campaign's
    nets take only its parameters, so its fixed test conditions (pre-shear stress, slot width)
    must be the row's; an unknown condition is taken as the campaign's and said so."""
    cfg = store.provenance.get("rig_config", {})
    for cname in ("preshear_stress", "slot_width"):
        text = m.conditions.get(cname, "unknown")
        if text.lower() == "unknown" or cname not in cfg:
            continue
        try:
            value = float(text)
        except ValueError:
            return f"condition {cname}={text!r} is not a number"
        if abs(value - float(cfg[cname])) > 1e-6 * abs(float(cfg[cname])):
            return (f"measured at {cname}={value:g}, the campaign {store.path.name} ran at {float(cfg[cname]):g} "
                    f"(use `pydem diagnose` with a campaign that varies it)")
    return ""


def noise_ceiling(store, metric: str) -> tuple[float, str]:
    """The hold-out R^2 a perfect net would get on the design points' means: 1 - their noise
    variance / their variance, and where the noise comes from: the pooled scatter between
    replicates ("replicates"), else the runs' own standard errors ("within-run": repeats or
    blocks inside a run, a lower bound on the run-to-run scatter), else nothing (nan, "")."""
    _, y, counts, replicate_sd = store.point_table(metric)
    _, _, run_se = store.table(metric)
    if np.isfinite(replicate_sd):
        noise_var, source = replicate_sd ** 2 * float(np.mean(1.0 / counts)), "replicates"
    elif run_se.size and np.all(np.isfinite(run_se)):
        noise_var, source = float(np.mean(run_se ** 2)) * float(np.mean(1.0 / counts)), "within-run"
    else:
        return float("nan"), ""
    return (1.0 - noise_var / float(np.var(y)) if np.var(y) > 0 else float("nan")), source


def train_all(stores: dict, out: Path, sizes, restarts: int, seed: int, selection: str = "one-se") -> dict:
    from nn.export import write_c, write_weights
    from nn.mlp import select_net
    nets_dir = out / "nets"
    (nets_dir / "c").mkdir(parents=True, exist_ok=True)
    meta, tables = {}, {}
    for rig, store in stores.items():
        for metric in property_metrics(rig, store):
            # replicates averaged: the nets fit (and are judged on) each design point's mean
            x, y, counts, replicate_sd = store.point_table(metric)
            ceiling, noise_source = noise_ceiling(store, metric)
            t0 = time.perf_counter()
            net, table = select_net(metric, store.spec.names, x, y, sizes=sizes, restarts=restarts, seed=seed,
                                    unit=store.metric_units[store.metric_names.index(metric)], rule=selection)
            key = cmp.net_key(rig, metric)
            write_weights(net, nets_dir / f"{key}.mlp")
            net.name = key
            write_c(net, nets_dir / "c")
            i = net.info
            meta[key] = {"rig": rig, "metric": metric, "hidden": net.hidden, "unit": net.unit,
                         "runs": int(counts.sum()), "replicates": float(np.mean(counts)),
                         "replicate_sd": replicate_sd, "r2_noise_ceiling": ceiling, "noise_source": noise_source,
                         "seconds": time.perf_counter() - t0,
                         **{k: i[k] for k in ("holdout_r2", "train_r2", "samples", "holdout_samples", "holdout_rmse", "selection",
                                     "best_hidden", "best_holdout_r2", "holdout_r2_se")},
                         "parity": {"simulated": i["holdout_simulated"], "predicted": i["holdout_predicted"]}}
            tables[key] = table
            _say(f"  {key:32s} hidden {net.hidden:3d}   hold-out R^2 {i['holdout_r2']:.4f}   (best: {i['best_hidden']} "
                 f"units, {i['best_holdout_r2']:.4f} +- {i['holdout_r2_se']:.4f}; {i['samples']} points, {int(counts.sum())} runs, "
                 f"{time.perf_counter() - t0:.1f} s)")
    (nets_dir / "nets.json").write_text(json.dumps({k: {kk: vv for kk, vv in v.items() if kk != "parity"}
                                                    for k, v in meta.items()}, indent=1))
    with open(out / "r2_vs_hidden.csv", "w") as fh:
        fh.write("net,hidden,best_holdout_r2,holdout_r2_restarts,train_r2_restarts\n")
        for key, table in tables.items():
            for row in table:
                fh.write(f"{key},{row['hidden']},{row['best_holdout_r2']:.6f},"
                         f"{' '.join(f'{v:.6f}' for v in row['holdout_r2'])},{' '.join(f'{v:.6f}' for v in row['train_r2'])}\n")
    return {"meta": meta, "tables": tables}


def calibrate(measurements: str | Path, material: str, campaigns: list[str | Path], out: str | Path,
              window: float = 0.05, samples: int = 2 ** 20, sizes=range(2, 41, 2), restarts: int = 3,
              threads: int = 2, seed: int = 0, confirm: bool = True, selection: str = "one-se") -> dict:
    from .mlp import NativeMLP
    from . import report
    if samples < 1:
        raise ValueError(f"--samples must be a positive number of combinations, got {samples}")
    t_start = time.perf_counter()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    meas = load(measurements, material)
    stores = {}
    for path in campaigns:
        store = Campaign.open(path).store
        stores[store.spec.rig] = store
    physics = check_same_physics(stores.values())
    from . import LIBDEM_VERSION
    if physics != physics_of(LIBDEM_VERSION):
        _say(f"  note: the campaigns were run with libdem {physics}, this is libdem {LIBDEM_VERSION} (another contact "
             f"law): the confirming DEM runs use the new one")
    names = next(iter(stores.values())).spec.names
    for rig, st in stores.items():
        if st.spec.names != names:
            raise ValueError(f"campaign {st.path} varies {st.spec.names}, another varies {names}: the nets must share inputs")
    # screening box: where every campaign has data (the nets do not extrapolate)
    ranges = {n: (max(st.spec.ranges[n][0] for st in stores.values()), min(st.spec.ranges[n][1] for st in stores.values()))
              for n in names}
    matched = [m for m in meas if m.use == "calibrate" and m.rig in stores
               and m.metric in property_metrics(m.rig, stores[m.rig]) and not condition_mismatch(m, stores[m.rig])]
    if not matched:  # before any training: nothing to calibrate against
        offered = ", ".join(f"{rig}: {', '.join(property_metrics(rig, st))}" for rig, st in stores.items())
        rows = ", ".join(m.label for m in meas if m.use == "calibrate") or "none marked use=calibrate"
        raise ValueError(f"{measurements}: no measurement of {material!r} matches a quantity of the given campaigns "
                         f"(measurements: {rows}; campaigns offer {offered})")
    _say(f"[1/6] campaigns: " + ", ".join(f"{rig} {st.counts()['done']} runs ({st.path.name})" for rig, st in stores.items()))
    _say(f"[2/6] training one MLP per property (hidden sizes {min(sizes)}-{max(sizes)}, {restarts} restarts, 15 % hold-out, "
         f"selection {selection})")
    trained = train_all(stores, out, list(sizes), restarts, seed, selection)
    nets_dir = out / "nets"

    def net_for(m: Measurement):
        key = cmp.net_key(m.rig or "", m.metric)
        return NativeMLP(nets_dir / f"{key}.mlp") if (nets_dir / f"{key}.mlp").exists() else None

    stages, skipped = [], []
    for rig in STAGE_ORDER:
        rows = [m for m in meas if m.use == "calibrate" and m.rig == rig]
        if rig in stores:  # a row measured at another condition than the campaign's is reported, not matched
            other = [(m, why) for m in rows for why in [condition_mismatch(m, stores[rig])] if why]
            for m, why in other:
                _say(f"  left out: {m.label}: {why}")
            skipped += [m for m, _ in other]
            rows = [m for m in rows if not condition_mismatch(m, stores[rig])]
        usable = [(m, net_for(m)) for m in rows]
        skipped += [m for m, n in usable if n is None]
        usable = [(m, n) for m, n in usable if n is not None]
        stages.append(screening.Stage(rig, [n for _, n in usable], [m for m, _ in usable], window))
    _say(f"[3/6] screening {samples:,} combinations (scrambled Sobol) natively, {threads} threads, window ±{100 * window:g} %")
    sc = screening.run(names, ranges, stages, samples, seed=7, threads=threads)
    for st, idx in zip(sc.stages, sc.admissible):
        _say(f"  {st.name:10s} {len(st.measurements)} measured values -> {len(idx):,} admissible "
             f"({st.seconds * 1e3:.1f} ms for {st.rows:,} rows x {len(st.nets)} nets)")
    final = sc.admissible[-1]
    calib = [m for st in sc.stages for m in st.measurements]
    cnets = [n for st in sc.stages for n in st.nets]
    pool = final if len(final) else np.arange(len(sc.points))
    pred = np.column_stack([n(sc.points[pool], threads) for n in cnets]) if cnets else np.zeros((len(pool), 0))
    best_i = int(pool[int(np.argmin(screening.misfit(pred, calib, window)))]) if cnets else int(len(sc.points) // 2)
    best = dict(zip(names, map(float, sc.points[best_i])))
    _say(f"  best estimate: " + ", ".join(f"{k} {v:.4g}" for k, v in best.items())
         + ("" if len(final) else "   (no admissible combination: the least misfit shown)"))
    _say("[4/6] predictions of every net at the best estimate and over the admissible set")
    surrogate = cmp.surrogate_model(nets_dir, best)
    dem_files, protocol_notes = [], []
    for rig, st in stores.items():
        made_with, now = st.rig_protocol, RIGS[rig][0].protocol
        if made_with != now:
            protocol_notes.append(f"{rig}: the campaign was measured with rig protocol {made_with}, the confirming run "
                                  f"with protocol {now} (the metric definitions changed since; see the rig's notes)")
            _say(f"  note: {protocol_notes[-1]}")
    if confirm:
        _say("[5/6] confirming DEM runs at the best estimate")
        for rig, st in stores.items():
            cfg = st.spec.config(best)
            cfg.num_threads = threads
            t0 = time.perf_counter()
            res = RIGS[rig][0](cfg).run(seed=12345)
            f = out / f"confirm_{rig.replace('-', '_')}.json"
            res.save(f)
            dem_files.append(f)
            _say(f"  {rig}: {time.perf_counter() - t0:.0f} s: " + "; ".join(f"{k} {m}" for k, m in res.metrics.items()
                                                                            if k in property_metrics(rig, st)))
    else:
        _say("[5/6] confirming DEM runs skipped (--no-confirm)")
    res_sur = cmp.compare(meas, surrogate)
    res_dem = cmp.compare(meas, cmp.dem_model(dem_files)) if dem_files else None
    from .provenance import provenance
    summary = {"provenance": provenance() | {"campaign_provenance": {r: s.provenance.get("git_commit") for r, s in stores.items()},
                                              "seed": seed, "samples": samples, "window": window},
               "material": material, "measurements": str(measurements), "campaigns": {r: str(s.path) for r, s in stores.items()},
               "names": names, "ranges": ranges, "window": window, "samples": len(sc.points), "best": best,
               "stages": [{"name": st.name, "measured": [m.label for m in st.measurements], "rows": st.rows,
                           "admissible": int(len(idx)), "seconds": st.seconds, "ranges": sc.ranges_of(idx)}
                          for st, idx in zip(sc.stages, sc.admissible)],
               "skipped_measurements": [m.label for m in skipped], "protocol_notes": protocol_notes, "selection": selection,
               "nets": {k: {kk: v[kk] for kk in ("hidden", "holdout_r2", "train_r2", "samples", "holdout_rmse")}
                        for k, v in trained["meta"].items()},
               "surrogate_at_best": {k: v[0] for k, v in surrogate.items()},
               "overall_surrogate": cmp.overall(res_sur), "overall_dem": cmp.overall(res_dem) if res_dem else None}
    if len(final):  # the admissible set itself, with the predictions of the screening nets
        header = ",".join(names + [f"{st.name}:{m.metric}" for st in sc.stages for m in st.measurements])
        np.savetxt(out / "admissible.csv", np.column_stack([sc.points[final], pred]), delimiter=",", header=header,
                   comments="", fmt="%.10g")
    _say("[6/6] report")
    path = report.write(out, summary, trained, sc, cnets, res_sur, res_dem, meas, stores)
    (out / "summary.json").write_text(json.dumps(strict_json(summary), indent=1, default=float))
    _say(f"done in {time.perf_counter() - t_start:.0f} s: {path}")
    return summary


def main_cli(args) -> int:
    from .measurements import MeasurementError
    from .campaign import StoreError
    try:
        calibrate(args.measurements, args.material, args.campaign, args.out, window=args.window, samples=args.samples,
                  restarts=args.restarts, threads=args.threads, confirm=not args.no_confirm, selection=args.selection)
    except (MeasurementError, StoreError, ValueError) as exc:
        print(f"pydem calibrate: {exc}", file=sys.stderr)
        return 2
    return 0


def add_parser(sub):
    p = sub.add_parser("calibrate", help="campaigns -> MLPs -> native screening -> confirming DEM run -> report")
    p.add_argument("--measurements", required=True, help="measurement file (docs/measurements.md)")
    p.add_argument("--material", required=True)
    p.add_argument("--campaign", action="append", required=True, help="campaign store (repeat: ring shear, angle of repose)")
    p.add_argument("--out", default="build/calibration")
    p.add_argument("--window", type=float, default=0.05, help="relative acceptance window (default 0.05 = 5 %%)")
    p.add_argument("--samples", type=int, default=2 ** 20, help="combinations screened (default 2^20)")
    p.add_argument("--restarts", type=int, default=3)
    p.add_argument("--selection", choices=("one-se", "best"), default="one-se",
                   help="hidden size: smallest within one standard error of the best hold-out R^2 (default), or the best")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--no-confirm", action="store_true", help="skip the confirming DEM runs")
    p.set_defaults(func=main_cli)
