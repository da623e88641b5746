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
    .venv/bin/python studies/nrrp_more_hoppers.py curve --table1 data/seed001/frames_full.h5 \\
        --extra 'data/seed001/extra_{packing}.h5' --counts 0 3 6 12 24 --networks build/lstm_k0 build/lstm_k12 \\
        --out studies/results/seed001/hoppers_curve.json --figure docs/seed001/hoppers_curve.png
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def packing_data(table1_store: str, extra_store: str, packing: str, size: int, window: int = 8):
    """(the packing's Table 1 cases, its extra hoppers, the gauges' inputs, every case's NRRP, the
    frame each reader starts at, the folds)."""
    from pydem.seed001 import experiments as ex
    from pydem.seed001 import gauges
    from pydem.seed001.store import FrameStore
    t1, more = FrameStore(table1_store), FrameStore(extra_store)
    table1 = [c for c in t1.cases() if ex.packing_of(c) == packing]
    extra = [c for c in more.cases() if ex.packing_of(c) == packing]  # a store may hold other packings too
    g_in = gauges.inputs(table1_store, table1, size) | gauges.inputs(extra_store, extra, size)
    nrrp = {c: t1.read_case(c)["nrrp"] for c in table1} | {c: more.read_case(c)["nrrp"] for c in extra}
    first = {c: ex.first_part(len(v), 0.2, window) for c, v in nrrp.items()}
    return table1, extra, g_in, nrrp, first, sorted({ex.fold_of(c) for c in table1})


def pretraining_cases(case: str, table1: list[str], folds: list[str]) -> list[str]:
    """The Table 1 hoppers of the case's packing its network pretrains on (its pretraining folds)."""
    from pydem.seed001 import experiments as ex
    return [c for c in table1 if ex.fold_of(c) in ex.pretraining_folds(ex.fold_of(case), folds)]


def errors_on(case: str, train: list[str], g_in: dict, nrrp: dict, first: dict) -> dict:
    """Each gauge's relative error on the case from its first[case] frame on, calibrated on
    `train`, and the error of the gauge chosen from `train` alone (`chosen`)."""
    from pydem.seed001 import frame_data, gauges
    got = {g: frame_data.scores(nrrp[case][first[case]:], v)["relative_error"]
           for g, v in gauges.readings(case, train, g_in, nrrp, first[case]).items()}
    return got | {"chosen": got[gauges.chosen(g_in, nrrp, train, first)]}


def evaluate(args) -> int:
    from pydem.seed001 import gauges
    table1, extra, g_in, nrrp, first, folds = packing_data(args.table1, args.store, args.packing, args.size)
    out = {"packing": args.packing, "size": args.size, "extra": extra, "cases": {}}
    for case in table1:
        base = pretraining_cases(case, table1, folds)
        row = {label: errors_on(case, train, g_in, nrrp, first)
               for label, train in (("table1", base), ("table1+extra", base + extra), ("extra", extra))}
        out["cases"][case] = row
        print(f"{case}: " + "  ".join(f"{lab}: fill {r['fill_level']:.3f} species {r['species']:.3f} chosen {r['chosen']:.3f}"
                                      for lab, r in row.items()))
    out["mean"] = {lab: {g: float(np.mean([out["cases"][c][lab][g] for c in table1])) for g in gauges.GAUGES + ("chosen",)}
                   for lab in ("table1", "table1+extra", "extra")}
    for lab, v in out["mean"].items():
        print(f"mean over {args.packing}, calibrated on {lab}: " + ", ".join(f"{g} {e:.3f}" for g, e in v.items()))
    Path(args.out).write_text(json.dumps(out, indent=1))
    return 0


TARGET = 0.08  # seed 001's average relative error of the NRRP


def curve(args) -> int:
    """The error of the NRRP readers against the hoppers used per packing: the chosen gauge (and
    each gauge) calibrated on the three Table 1 hoppers of the case's pretraining folds plus the
    first K extra hoppers, for each K of --counts; the networks' points from `process` runs made
    with --extra-per-packing K (--networks). A power law err = a n^b through each reader's points
    (n = hoppers used) says where it would reach seed 001's 0.08 — an extrapolation, marked so."""
    from pydem.seed001 import experiments as ex
    from pydem.seed001 import gauges
    out = {"counts": args.counts, "size": args.size, "target": TARGET, "packings": {}}
    for pk in args.packings:
        table1, extra, g_in, nrrp, first, folds = packing_data(args.table1, args.extra.replace("{packing}", pk), pk,
                                                               args.size, args.window)
        rows = {}
        for k in [k for k in args.counts if k <= len(extra)]:
            errs = {g: [] for g in gauges.GAUGES + ("chosen",)}
            for case in table1:
                for g, e in errors_on(case, pretraining_cases(case, table1, folds) + extra[:k], g_in, nrrp, first).items():
                    errs[g].append(e)
            rows[k] = {"hoppers": len(folds) - 2 + k, **{g: float(np.mean(v)) for g, v in errs.items()}}
            print(f"{pk}, {rows[k]['hoppers']} hoppers: " + ", ".join(f"{g} {rows[k][g]:.3f}" for g in errs), flush=True)
        out["packings"][pk] = {"gauges": rows, "extra_available": len(extra)}
    for d in args.networks or []:
        run = process_run(d)
        per = {pk: sum(ex.packing_of(c) == pk for c in run["settings"].get("extra_hoppers", [])) for pk in args.packings}
        for pk in args.packings:
            if pk in run["per_packing"]:
                points = out["packings"][pk].setdefault("network", {})
                if str(per[pk]) in points:
                    raise SystemExit(f"{d} and {points[str(per[pk])]['run']}: both with {per[pk]} extra hoppers of "
                                     f"{pk}; pass one run per count")
                points[str(per[pk])] = {"hoppers": 3 + per[pk], "net": run["per_packing"][pk]["net"], "run": str(d),
                                        "training": training_of(run)}
    for pk, v in out["packings"].items():
        v["reach"] = {name: reach([(r["hoppers"], r[key]) for r in pts.values()])
                      for name, pts, key in (("chosen gauge", v["gauges"], "chosen"),
                                             ("network", comparable(v.get("network", {})), "net")) if len(pts) >= 2}
    Path(args.out).write_text(json.dumps(out, indent=1))
    if args.figure:
        curve_figure(out, args.figure)
    return 0


def training_of(run: dict) -> dict:
    """What a network point depends on besides its hoppers: inputs, target, size, window, stride, epochs."""
    keys = ("inputs", "target", "size", "window", "stride", "epochs")
    return {k: run["settings"].get(k, "nrrp" if k == "target" else None) for k in keys}


def comparable(points: dict) -> dict:
    """The network points trained like the one of most hoppers: a power law through runs with
    another stride or epoch count would read a change of step budget as the hoppers' effect."""
    if not points:
        return {}
    last = max(points.values(), key=lambda r: r["hoppers"])["training"]
    return {k: r for k, r in points.items() if r["training"] == last}


def process_run(where: str) -> dict:
    """A `process` run's results: its JSON file, or the --out folder holding process.json."""
    path = Path(where)
    return json.loads((path if path.suffix == ".json" else path / "process.json").read_text())


def reach(points: list[tuple[int, float]], tail: int = 3) -> dict:
    """Where a reader reaches TARGET. Measured when it does: the fewest hoppers whose error is at
    or below it. Otherwise extrapolated by err = a n^b, fitted by least squares in logs through
    the `tail` points of most hoppers — the curve's present slope, since a reader whose form
    limits it flattens, and a fit through all points would promise what the last ones no longer
    show (None when the error no longer falls)."""
    points = sorted((n, e) for n, e in points if np.isfinite(e) and e > 0)
    none = {"exponent": None, "a": None, "fitted_from": None, "hoppers_for_target": None, "reached": False,
            "extrapolated": False}
    if len(points) < 2:
        return none
    hit = [n for n, e in points if e <= TARGET]
    n, e = (np.array(v, float) for v in zip(*points[-tail:]))
    b, log_a = np.polyfit(np.log(n), np.log(e), 1)
    fit = {"exponent": float(b), "a": float(np.exp(log_a)), "fitted_from": int(n[0])}
    if hit:
        return none | fit | {"hoppers_for_target": hit[0], "reached": True}
    needed = float(np.exp((np.log(TARGET) - log_a) / b)) if b < 0 else None
    return none | fit | {"hoppers_for_target": needed, "extrapolated": needed is not None}


def table(args) -> int:
    """A Markdown table per packing of `process` runs (--networks): each run's network, fine-tuned
    and zero-shot, and its two gauges calibrated on the same training hoppers; the last column the
    better of the last run's gauges per packing — chosen on the test cases, so the strictest bar."""
    from pydem.seed001 import gauges
    runs = [(Path(d).stem if d.endswith(".json") else Path(d).name, process_run(d)) for d in args.networks]
    head = ["packing"] + [f"{name}: net / zero-shot / {' / '.join(gauges.GAUGES)}" for name, _ in runs] + ["better gauge"]
    print("| " + " | ".join(head) + " |\n|" + "---|" * len(head))
    for pk in args.packings:
        cells = []
        for _, run in runs:
            v = run["per_packing"].get(pk, {})
            cells.append(" / ".join(f"{v[k]:.3f}" if k in v else "—" for k in ("net", "zero_shot") + gauges.GAUGES))
        last = runs[-1][1]["per_packing"].get(pk, {})
        better = min((last[g], g) for g in gauges.GAUGES if g in last) if last else None
        last_cell = f"{better[0]:.3f} ({better[1].replace('_', ' ')})" if better else "—"
        print(f"| {pk} | " + " | ".join(cells) + f" | {last_cell} |")
    return 0


def curve_figure(res: dict, path: str):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(res["packings"]), figsize=(3.2 * len(res["packings"]), 3.2), sharey=True, squeeze=False)
    for ax, (pk, v) in zip(axes[0], res["packings"].items()):
        net = v.get("network", {})
        same = comparable(net)
        others = sorted((r["hoppers"], r["net"]) for k, r in net.items() if k not in same)
        for name, pts, key, style in (("chosen gauge", v["gauges"], "chosen", "o-"), ("network", same, "net", "s-")):
            if not pts:
                continue
            n = sorted((r["hoppers"], r[key]) for r in pts.values())
            ax.plot(*zip(*n), style, label=name)
            if name == "network" and others:
                ax.plot(*zip(*others), "s", mfc="none", color=ax.lines[-1].get_color(), label="network, other budget")
            fit = v["reach"].get(name)
            if fit and fit["extrapolated"]:
                xs = np.geomspace(fit["fitted_from"], min(fit["hoppers_for_target"], 1000), 50)
                ax.plot(xs, fit["a"] * xs ** fit["exponent"], ":", color=ax.lines[-1].get_color())
        ax.axhline(res["target"], color="k", lw=0.8, ls="--")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(2.5, 400)
        ax.set_xticks([3, 6, 12, 24, 48, 96, 192], labels=["3", "6", "12", "24", "48", "96", "192"])
        ax.set_yticks([0.05, 0.08, 0.1, 0.2, 0.5, 1, 2], labels=["0.05", "0.08", "0.1", "0.2", "0.5", "1", "2"])
        ax.minorticks_off()
        ax.set_title(pk)
        ax.set_xlabel("hoppers used per packing")
    axes[0][0].set_ylabel("mean relative error of the NRRP")
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    e = sub.add_parser("evaluate")
    e.add_argument("--packing", required=True, choices=("A", "B1", "B2", "B3", "B4"))
    e.add_argument("--store", required=True)
    e.add_argument("--table1", required=True, help="the frame store of the 25 Table 1 cases")
    e.add_argument("--size", type=int, default=224, help="frame side of the fill-level gauge")
    e.add_argument("--out", required=True)
    c = sub.add_parser("curve", help="error against hoppers used, per packing, with the extrapolation to 0.08")
    c.add_argument("--table1", required=True, help="the frame store of the 25 Table 1 cases")
    c.add_argument("--extra", required=True, help="the extra hoppers' store, {packing} in its name "
                                                   "(e.g. data/seed001/extra_{packing}.h5)")
    c.add_argument("--packings", nargs="+", default=["A", "B1", "B2", "B3", "B4"])
    c.add_argument("--counts", nargs="+", type=int, default=[0, 3, 6, 12, 24], help="extra hoppers per packing")
    c.add_argument("--size", type=int, default=224, help="frame side of the fill-level gauge")
    c.add_argument("--window", type=int, default=8, help="the process runs' window: the readers start after "
                                                         "max(window + 2, 20 %% of the frames)")
    c.add_argument("--networks", nargs="*", help="process runs (--out folders or their JSON) made with --extra-per-packing K")
    c.add_argument("--out", required=True)
    c.add_argument("--figure")
    t = sub.add_parser("table", help="Markdown per packing of process runs: network, zero-shot, gauges")
    t.add_argument("--networks", nargs="+", required=True, help="process runs: --out folders or their JSON")
    t.add_argument("--packings", nargs="+", default=["A", "B1", "B2", "B3", "B4"])
    args = ap.parse_args()
    return {"evaluate": evaluate, "curve": curve, "table": table}[args.cmd](args)


if __name__ == "__main__":
    sys.exit(main())
