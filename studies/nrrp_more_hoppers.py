"""Would more hoppers carry the image-to-count law? The image gauges of `process`
(pydem.seed001.experiments.gauge_rows) read the five Table 1 cases of a packing after calibrating on
its three pretraining-fold cases; here they are calibrated again with M more hoppers of the same
packing added, drawn like Table 1's, and the errors compared — of each gauge, and of the one a
user would pick by leave-one-hopper-out on the training hoppers (`chosen`).

The hoppers are drawn by pydem.rigs.table1.draw_like_table1. Each runs
at full size with a frame every `--frame-interval` into its own store (resumable: hoppers
already stored are skipped), two at a time.

    .venv/bin/python studies/nrrp_more_hoppers.py run --packing B1 --hoppers 12 --store data/seed001/extra_B1.h5
    .venv/bin/python studies/nrrp_more_hoppers.py evaluate --packing B1 --store data/seed001/extra_B1.h5 \\
        --table1 data/seed001/frames_full.h5 --out studies/results/seed001/nrrp_more_hoppers_B1.json
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def run_one(name: str, row: tuple, packing: str, frame_interval: float):
    from pydem.rigs import RIGS, load
    from pydem.rigs.hopper import apply_row
    cls, cfg_cls = RIGS["hopper"]
    cfg = load(cfg_cls, "default", None, [f"frame_interval={frame_interval}", "num_threads=1"])
    apply_row(cfg, row, packing)
    t0 = time.perf_counter()
    try:
        res = cls(cfg).run(seed=0, images=True)
    except Exception as exc:  # one hopper that fails does not stop the others
        return name, None, f"failed ({exc})"
    t_dis = res.metrics["discharge_time"].value
    if not np.isfinite(t_dis):
        return name, None, f"did not empty ({res.metrics['discharge_time'].note})"
    return name, (res.images, res.series["frame_time"], t_dis, res.series["frame_nrrp"]), time.perf_counter() - t0


def run(args) -> int:
    from pydem.seed001.store import FrameStore
    from pydem.rigs.table1 import draw_like_table1
    store = FrameStore(args.store)
    rows = draw_like_table1(args.packing, args.hoppers, args.seed)
    todo = {k: v for k, v in rows.items() if k not in set(store.cases())}
    print(f"{len(rows) - len(todo)} of {len(rows)} hoppers stored; running {len(todo)}, {args.workers} at a time")
    with ProcessPoolExecutor(args.workers) as pool:
        jobs = [pool.submit(run_one, k, v, args.packing, args.frame_interval) for k, v in todo.items()]
        for job in as_completed(jobs):  # stored as each finishes: a killed run keeps what it made
            name, got, info = job.result()
            if got is None:
                print(f"  {name}: {info}; not stored")
                continue
            frames, t, t_dis, nrrp = got
            store.write_case(name, frames, t, t_dis, nrrp, {"packing": args.packing, "row": json.dumps(rows[name]),
                                                             "frame_interval": args.frame_interval, "dem_seconds": info})
            print(f"  {name}: N {rows[name][0]}, {len(frames)} frames, discharge {t_dis:.3f} s, {info:.0f} s", flush=True)
    return 0


def evaluate(args) -> int:
    from pydem.seed001 import experiments as ex
    from pydem.seed001.store import FrameStore
    table1 = [c for c in FrameStore(args.table1).cases() if ex.packing_of(c) == args.packing]
    extra_store = FrameStore(args.store)
    extra = extra_store.cases()
    inputs = ex.gauge_inputs(args.table1, table1, args.size)
    nrrp = {c: FrameStore(args.table1).read_case(c)["nrrp"] for c in table1}
    rows = {}
    for c in extra:
        d = extra_store.read_case(c)
        row = json.loads(d["row"])
        rows[c], nrrp[c] = tuple(row[:9]) + (tuple(row[9]),) + tuple(row[10:]), d["nrrp"]
    inputs |= ex.gauge_inputs(args.store, extra, args.size, rows)
    folds = sorted({ex.fold_of(c) for c in table1})
    out = {"packing": args.packing, "size": args.size, "extra": extra, "cases": {}}
    for case in table1:
        k = ex.first_part(len(nrrp[case]), 0.2, 8)
        base = [c for c in table1 if ex.fold_of(c) in ex.pretraining_folds(ex.fold_of(case), folds)]
        row = {}
        for label, train in (("table1", base), ("table1+extra", base + extra), ("extra", extra)):
            row[label] = calibrated(case, inputs, nrrp, train, k)
            row[label]["chosen"] = row[label][chosen_gauge(inputs, nrrp, train)]
        out["cases"][case] = row
        print(f"{case}: " + "  ".join(f"{lab}: fill {r['fill_level']:.3f} species {r['species']:.3f} chosen {r['chosen']:.3f}"
                                      for lab, r in row.items()))
    out["mean"] = {lab: {g: float(np.mean([out["cases"][c][lab][g] for c in table1])) for g in ex.GAUGES + ("chosen",)}
                   for lab in ("table1", "table1+extra", "extra")}
    for lab, v in out["mean"].items():
        print(f"mean over {args.packing}, calibrated on {lab}: " + ", ".join(f"{g} {e:.3f}" for g, e in v.items()))
    Path(args.out).write_text(json.dumps(out, indent=1))
    return 0


def chosen_gauge(inputs: dict, nrrp: dict, train: list[str]) -> str:
    """The gauge a user would pick from the training hoppers alone: the one whose error, each
    hopper read by a gauge calibrated on the others (from its first 20 % on), is smaller."""
    from pydem.seed001 import experiments as ex
    errs = [calibrated(c, inputs, nrrp, [t for t in train if t != c], ex.first_part(len(nrrp[c]), 0.2, 8))
            for c in train]
    return min(ex.GAUGES, key=lambda g: np.mean([e[g] for e in errs]))


def calibrated(case: str, inputs: dict, nrrp: dict, train: list[str], k: int) -> dict:
    """Relative errors of both gauges on the case from frame k, calibrated on `train`
    (pydem.seed001.experiments.gauge_readings)."""
    from pydem.seed001 import frame_data
    from pydem.seed001 import experiments as ex
    return {g: frame_data.scores(nrrp[case][k:], v)["relative_error"]
            for g, v in ex.gauge_readings(case, train, inputs, nrrp, k).items()}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--packing", required=True, choices=("A", "B1", "B2", "B3", "B4"))
    r.add_argument("--hoppers", type=int, default=12)
    r.add_argument("--seed", type=int, default=1)
    r.add_argument("--store", required=True)
    r.add_argument("--frame-interval", type=float, default=0.001)
    r.add_argument("--workers", type=int, default=2)
    e = sub.add_parser("evaluate")
    e.add_argument("--packing", required=True, choices=("A", "B1", "B2", "B3", "B4"))
    e.add_argument("--store", required=True)
    e.add_argument("--table1", required=True, help="the frame store of the 25 Table 1 cases")
    e.add_argument("--size", type=int, default=224, help="frame side of the fill-level gauge")
    e.add_argument("--out", required=True)
    args = ap.parse_args()
    return run(args) if args.cmd == "run" else evaluate(args)


if __name__ == "__main__":
    sys.exit(main())
