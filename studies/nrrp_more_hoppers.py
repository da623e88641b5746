"""Would more hoppers carry the image-to-count law? The image gauges of `process`
(pydem.seed001.gauges) read the five Table 1 cases of a packing after calibrating on
its three pretraining-fold cases; here they are calibrated again with M more hoppers of the same
packing added, drawn like Table 1's, and the errors compared — of each gauge, and of the one a
user would pick by leave-one-hopper-out on the training hoppers (`chosen`).

The hoppers are made by `pydem images hoppers` (pydem/seed001/hoppers.py: drawn like Table 1's,
full size, a frame every 1 ms, one resumable store per packing):

    .venv/bin/pydem images hoppers --packing B1 --hoppers 12 --store data/seed001/extra_B1.h5
    .venv/bin/python studies/nrrp_more_hoppers.py evaluate --packing B1 --store data/seed001/extra_B1.h5 \\
        --table1 data/seed001/frames_full.h5 --out studies/results/seed001/nrrp_more_hoppers_B1.json
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def evaluate(args) -> int:
    from pydem.seed001 import experiments as ex
    from pydem.seed001 import frame_data, gauges
    from pydem.seed001.store import FrameStore
    table1 = [c for c in FrameStore(args.table1).cases() if ex.packing_of(c) == args.packing]
    extra = FrameStore(args.store).cases()
    g_in = gauges.inputs(args.table1, table1, args.size) | gauges.inputs(args.store, extra, args.size)
    nrrp = {c: FrameStore(args.table1).read_case(c)["nrrp"] for c in table1} | \
        {c: FrameStore(args.store).read_case(c)["nrrp"] for c in extra}
    first = {c: ex.first_part(len(v), 0.2, 8) for c, v in nrrp.items()}
    folds = sorted({ex.fold_of(c) for c in table1})
    out = {"packing": args.packing, "size": args.size, "extra": extra, "cases": {}}
    for case in table1:
        k = first[case]
        base = [c for c in table1 if ex.fold_of(c) in ex.pretraining_folds(ex.fold_of(case), folds)]
        row = {}
        for label, train in (("table1", base), ("table1+extra", base + extra), ("extra", extra)):
            row[label] = {g: frame_data.scores(nrrp[case][k:], v)["relative_error"]
                          for g, v in gauges.readings(case, train, g_in, nrrp, k).items()}
            row[label]["chosen"] = row[label][gauges.chosen(g_in, nrrp, train, first)]
        out["cases"][case] = row
        print(f"{case}: " + "  ".join(f"{lab}: fill {r['fill_level']:.3f} species {r['species']:.3f} chosen {r['chosen']:.3f}"
                                      for lab, r in row.items()))
    out["mean"] = {lab: {g: float(np.mean([out["cases"][c][lab][g] for c in table1])) for g in gauges.GAUGES + ("chosen",)}
                   for lab in ("table1", "table1+extra", "extra")}
    for lab, v in out["mean"].items():
        print(f"mean over {args.packing}, calibrated on {lab}: " + ", ".join(f"{g} {e:.3f}" for g, e in v.items()))
    Path(args.out).write_text(json.dumps(out, indent=1))
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    e = sub.add_parser("evaluate")
    e.add_argument("--packing", required=True, choices=("A", "B1", "B2", "B3", "B4"))
    e.add_argument("--store", required=True)
    e.add_argument("--table1", required=True, help="the frame store of the 25 Table 1 cases")
    e.add_argument("--size", type=int, default=224, help="frame side of the fill-level gauge")
    e.add_argument("--out", required=True)
    args = ap.parse_args()
    return evaluate(args)


if __name__ == "__main__":
    sys.exit(main())
