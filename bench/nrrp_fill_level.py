"""The fill-level gauge beside a finished CNN-LSTM `process` run (pretrained protocol), without
training anything: for every case the NRRP after its first 20 % of frames read from each
frame's fill fraction through a cubic fitted on the same packing's cases in the folds its
network pretrained on (nn.seed001_experiments.fill_level_baseline), scored like the network.

    .venv/bin/python bench/nrrp_fill_level.py --store data/seed001/frames_full.h5 --size 224 \\
        --process bench/results/seed001_gpu/process.json --out bench/results/seed001_gpu/process_fill_level.json
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def main() -> int:
    from nn import images
    from nn import seed001_experiments as ex
    from pydem.frames import FrameStore
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--store", required=True)
    ap.add_argument("--size", type=int, default=64, help="frame side, as the process run used")
    ap.add_argument("--process", required=True, help="the process run's JSON (its settings and its network's scores)")
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    run = json.loads(Path(args.process).read_text())
    st = run["settings"]
    if st["protocol"] != "pretrained":
        raise SystemExit(f"{args.process}: protocol {st['protocol']!r}; the gauge is calibrated on pretraining cases")
    cases = FrameStore(args.store).cases()
    data = {c: images.load_frames(args.store, cases=[c], size=args.size) for c in cases}
    fills = {c: images.fill_fraction(data[c].x, data[c].x[0]) for c in cases}
    folds = sorted({ex._fold(c) for c in cases})
    out = {"store": args.store, "size": args.size, "process": args.process, "cases": {}, "per_packing": {}}
    for c in cases:
        k = ex.first_part(len(data[c].x), st["fraction"], st["window"])
        if c not in run["cases"] or run["cases"][c]["trained_on"] != k:
            raise SystemExit(f"{c}: not in {args.process} with the same first part — another frame store?")
        gauge = ex.fill_level_baseline(c, fills, data, folds, k)
        out["cases"][c] = {"fill_level": images.scores(data[c].nrrp[k:], gauge),
                           "net": run["cases"][c]["net"], "baseline": run["cases"][c]["baseline"]}
        print(f"{c}: fill-level gauge {out['cases'][c]['fill_level']['relative_error']:.3f}  "
              f"network {out['cases'][c]['net']['relative_error']:.3f}")
    for pk in ex.PACKINGS:
        rows = [r for c, r in out["cases"].items() if ex._packing(c) == pk]
        out["per_packing"][pk] = {key: float(np.mean([r[key]["relative_error"] for r in rows]))
                                  for key in ("fill_level", "net", "baseline")}
        print(f"{pk}: " + ", ".join(f"{k} {v:.3f}" for k, v in out["per_packing"][pk].items()))
    Path(args.out).write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
