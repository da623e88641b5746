"""The image gauges beside a finished CNN-LSTM `process` run (pretrained protocol), without
training anything: for every case the NRRP after its first 20 % of frames as the fill-level
gauge and the species gauge read it, each calibrated on the cases in the folds the case's
network pretrained on (pydem.seed001.gauges), scored like the network — for runs
made before the gauges were part of `process`, or on another machine. Beside them, the same
gauges fitted on the case's own whole discharge (`*_own`: quintics; what no reader of a new
hopper has): how well one discharge's frames fix its own count, against how well a law carries
from other hoppers.

    .venv/bin/python studies/nrrp_gauges.py --store data/seed001/frames_full.h5 --size 224 \\
        --process studies/results/seed001_gpu/process.json --out studies/results/seed001_gpu/process_gauges.json
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
    from pydem.seed001 import experiments as ex
    from pydem.seed001 import frame_data, gauges
    from pydem.seed001.store import FrameStore
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--store", required=True)
    ap.add_argument("--size", type=int, default=64, help="frame side, as the process run used")
    ap.add_argument("--process", required=True, help="the process run's JSON (its settings and its network's scores)")
    ap.add_argument("--out", required=True)
    ap.add_argument("--figure", help="PNG: for every case, the NRRP beside what the front view shows (grey fill, "
                                     "fine and coarse fill), against the frame index")
    args = ap.parse_args()
    run = json.loads(Path(args.process).read_text())
    st = run["settings"]
    if st["protocol"] != "pretrained":
        raise SystemExit(f"{args.process}: protocol {st['protocol']!r}; the gauge is calibrated on pretraining cases")
    cases = FrameStore(args.store).cases()
    data = {c: frame_data.load_frames(args.store, cases=[c], size=args.size) for c in cases}
    g_in = gauges.inputs(args.store, cases, args.size)
    nrrp = {c: d.nrrp for c, d in data.items()}
    folds = sorted({ex.fold_of(c) for c in cases})
    out = {"store": args.store, "size": args.size, "process": args.process, "cases": {}, "per_packing": {}}
    for c in cases:
        k = ex.first_part(len(data[c].x), st["fraction"], st["window"])
        if c not in run["cases"] or run["cases"][c]["trained_on"] != k:
            raise SystemExit(f"{c}: not in {args.process} with the same first part — another frame store?")
        same = [t for t in cases if ex.packing_of(t) == ex.packing_of(c)
                and ex.fold_of(t) in ex.pretraining_folds(ex.fold_of(c), folds)]
        row = {g: v for g, v in gauges.scored(c, same, g_in, nrrp, k).items() if g in gauges.GAUGES}
        out["cases"][c] = row | own_fits(g_in[c], data[c].nrrp, k) | {"net": run["cases"][c]["net"],
                                                                       "baseline": run["cases"][c]["baseline"]}
        print(f"{c}: " + "  ".join(f"{g} {r['relative_error']:.3f}" for g, r in out["cases"][c].items()))
    for pk in ex.PACKINGS:
        rows = [r for c, r in out["cases"].items() if ex.packing_of(c) == pk]
        out["per_packing"][pk] = {key: float(np.mean([r[key]["relative_error"] for r in rows]))
                                  for key in rows[0]}
        print(f"{pk}: " + ", ".join(f"{k} {v:.3f}" for k, v in out["per_packing"][pk].items()))
    Path(args.out).write_text(json.dumps(out, indent=1))
    if args.figure:
        figure(args.figure, g_in, data)
    return 0


def own_fits(g: dict, nrrp: np.ndarray, k: int, degree: int = 5) -> dict:
    """Both gauges fitted on the case's whole discharge and scored on its frames from k on."""
    from pydem.seed001 import baselines, frame_data
    design = baselines.species_design(g["species"], g["fines_share"], degree)
    return {"fill_level_own": frame_data.scores(nrrp[k:], baselines.fill_level_nrrp(g["fill"], nrrp, g["fill"], degree)[k:]),
            "species_own": frame_data.scores(nrrp[k:], baselines.species_gauge_nrrp(design, nrrp, design)[k:])}


def figure(path: str, gauges: dict, data: dict):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from pydem.seed001.experiments import PACKINGS, packing_of
    fig, axes = plt.subplots(5, 5, figsize=(15, 13), sharey=True)
    for row, pk in zip(axes, PACKINGS):
        for ax, c in zip(row, [c for c in gauges if packing_of(c) == pk]):
            g, i = gauges[c], np.arange(len(data[c].nrrp))
            ax.plot(i, data[c].nrrp, "k-", lw=1.5, label="NRRP (DEM count)")
            ax.plot(i, g["fill"], "C2-", lw=0.8, label="grey fill")
            ax.plot(i, g["species"][:, 0], "C0-", lw=0.8, label="fine fill")
            ax.plot(i, g["species"][:, 1], "C1-", lw=0.8, label="coarse fill")
            ax.set_title(f"{c}: fines {g['fines_share']:.0%} of the count", fontsize=9)
            ax.set_ylim(0, 1.3)
    for ax in axes[-1]:
        ax.set_xlabel("frame")
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=70)
    print(f"written {path}")


if __name__ == "__main__":
    sys.exit(main())
