"""Seed 001's data and its grey relational analysis: the 25 Table 1 hopper cases run at their
full particle counts, every frame centre-cropped and greyed into one HDF5 frame store
(pydem.seed001.store), each labelled with its time, remaining discharge time and NRRP; then the GRA of
the 11 Table 1 parameters against the cases' discharge times (pydem.seed001.gra), per packing and overall.

    .venv/bin/python -m pydem.seed001 frames --store data/seed001/frames.h5 [--cases A-1 B1-3] [--frame-interval 0.02]
    .venv/bin/python -m pydem.seed001 gra --store data/seed001/frames.h5
    .venv/bin/python -m pydem.seed001 hoppers --packing B1 --hoppers 12 --store data/seed001/extra_B1.h5
    .venv/bin/python -m pydem.seed001 subset --store data/seed001/frames_full.h5 --out data/seed001/frames_subset.h5 --every 25
    .venv/bin/python -m pydem.seed001 compare|point-to-point|process --store STORE --out DIR [--size 64 --epochs N]
    .venv/bin/python -m pydem.seed001 report --store STORE --results DIR --out DIR

The last three are pydem.seed001.experiments (the networks beside their physics baselines; results
as JSON in DIR). The frame campaign is resumable: a case is written whole when its run ends, and a rerun does
only the cases the store lacks."""
from __future__ import annotations

import argparse
import sys

from ..cli_inputs import seed_value
from ..rigs.table1 import TABLE1
from .gra import PARAMETERS, gra_tables, parameter_row
from .store import FrameStore


def run_frames(store_path: str, cases: list[str], frame_interval: float, workers: int, say=print):
    """The Table 1 cases the store lacks, `workers` at a time (one thread each; pydem.seed001.hoppers
    runs them); a case that fails is kept in the store with its reason and reported, and run again
    on the next call."""
    from .hoppers import run_into_store
    store = FrameStore(store_path)
    done = set(store.cases())
    for case in cases:
        if case in done:
            say(f"  {case}: in the store already")
    todo = [c for c in cases if c not in done]
    attrs = {c: {"packing": c.split("-")[0], **{f"param_{k}": v for k, v in parameter_row(c).items()},
                 "frame_interval": frame_interval} for c in todo}
    failed: dict = {}
    run_into_store(store, {c: (TABLE1[c], c.split("-")[0]) for c in todo}, frame_interval, workers, attrs, failed, say)
    return failed


def write_subset(full: str, out: str, every: int):
    """Every `every`-th frame of each case of `full` into the store `out` (labels and attributes kept)."""
    src, dst = FrameStore(full), FrameStore(out)
    for case in src.cases():
        d = src.read_case(case)
        attrs = {k: v for k, v in d.items() if k not in ("frames", "time", "remaining_time", "nrrp", "complete", "discharge_time")}
        dst.write_case(case, d["frames"][::every], d["time"][::every], d["discharge_time"], d["nrrp"][::every],
                       attrs | {"subset_every": every})


def main(argv=None, prog: str = "python -m pydem.seed001") -> int:
    ap = argparse.ArgumentParser(prog=prog)
    sub = ap.add_subparsers(dest="cmd", required=True)
    f = sub.add_parser("frames", help="run the Table 1 cases into the frame store (resumable)")
    f.add_argument("--store", required=True)
    f.add_argument("--cases", nargs="+", default=list(TABLE1), choices=list(TABLE1))
    f.add_argument("--frame-interval", type=float, default=0.02, help="s between frames (default 0.02)")
    f.add_argument("--workers", type=int, default=1, help="cases run side by side, one thread each (default 1)")
    h = sub.add_parser("hoppers", help="more hoppers of a packing, drawn like Table 1's, into a frame store of their "
                                       "own: pretraining and calibration data, never test cases (resumable)")
    h.add_argument("--packing", required=True, choices=("A", "B1", "B2", "B3", "B4"))
    h.add_argument("--hoppers", type=int, default=12, help="how many (the first k are the same for any count; default 12)")
    h.add_argument("--store", required=True, help="the packing's frame store, e.g. data/seed001/extra_B1.h5")
    h.add_argument("--seed", type=seed_value, default=1, help="the draw's seed (default 1)")
    h.add_argument("--frame-interval", type=float, default=0.001, help="s between frames (default 0.001)")
    h.add_argument("--workers", type=int, default=2)
    h.add_argument("--volume-scale", type=float, default=1.0,
                   help="the beds' solid volume over Table 1's (default 1; smaller for a quick look)")
    h.add_argument("--retry-failed", action="store_true", help="run the hoppers that failed before again")
    g = sub.add_parser("gra", help="grey relational analysis of the stored cases' discharge times")
    g.add_argument("--store", required=True)
    g.add_argument("--rho", type=float, default=0.5)
    sb = sub.add_parser("subset", help="every N-th frame of each case into a small store")
    sb.add_argument("--store", required=True)
    sb.add_argument("--out", required=True)
    sb.add_argument("--every", type=int, default=25)
    for name, what in (("compare", "AlexNet, ResNet-50, VGG-16, VGG-19 on the remaining discharge time"),
                       ("point-to-point", "AlexNet-FC, random-frame and leave-cases-out splits"),
                       ("process", "the CNN-LSTM on each case's NRRP(t) beyond its first 20 %%")):
        e = sub.add_parser(name, help=what)
        e.add_argument("--store", required=True)
        e.add_argument("--out", required=True, help="directory for the results JSON and the training checkpoints")
        e.add_argument("--size", type=int, default=64, help="frame side after area-averaging the 224 x 224 crop")
        e.add_argument("--epochs", type=int)
        e.add_argument("--every", type=int, help="use every N-th stored frame (compare, point-to-point)")
        e.add_argument("--seed", type=seed_value, default=0)
        e.add_argument("--threads", type=int, default=2, help="torch threads")
        if name != "process":
            e.add_argument("--checkpoints", help="folder of the training checkpoints (default: --out)")
        e.add_argument("--device", choices=("auto", "cpu", "cuda"), default="auto",
                       help="auto (default): a GPU when torch sees one, else the CPU")
        if name == "compare":
            e.add_argument("--models", nargs="+", help="a subset of alexnet resnet50 vgg16 vgg19")
            e.add_argument("--time-budget", type=float, help="s of training per network after which no epoch starts")
        if name != "compare":
            e.add_argument("--extra", nargs="+", default=[], metavar="STORE",
                           help="frame stores of more hoppers (pydem images hoppers): training (process: pretraining "
                                "and the gauges' calibration; point-to-point: the leave-cases-out training) only, never "
                                "tested")
            e.add_argument("--extra-per-packing", type=int, metavar="K",
                           help="the first K extra hoppers of each packing only (the curve of error against hoppers)")
        if name == "process":
            e.add_argument("--protocol", choices=("pretrained", "per-case"), default="pretrained",
                           help="pretrained: on other cases' whole discharges, fine-tuned on the case's first 20 %% "
                                "(default); per-case: seed 001's, the first 20 %% only")
            e.add_argument("--inputs", choices=("grey", "species"), default="grey",
                           help="what the network sees of a frame: grey (seed 001's) or species (fine and coarse "
                                "spheres as two channels, read from the grey levels)")
            e.add_argument("--stride", type=int, default=4, help="pretraining windows every N frames (default 4)")
            e.add_argument("--target", choices=("nrrp", "residual"), default="nrrp",
                           help="what the network learns: the NRRP (default), or its residual on the image gauge "
                                "chosen per packing from the training hoppers")
            e.add_argument("--warm-start", metavar="DIR",
                           help="the --out folder of an earlier pretrained process run (same store, inputs, size): "
                                "each fold's network starts from its pretrained weights")
    rp = sub.add_parser("report", help="HTML + Markdown report of the GRA and the experiments' results")
    rp.add_argument("--store", required=True)
    rp.add_argument("--results", required=True, help="the experiments' --out directory")
    rp.add_argument("--out", required=True)
    args = ap.parse_args(argv)
    if args.cmd == "report":
        from .report import write
        print(f"written {write(args.store, args.results, args.out)}")
        return 0
    if args.cmd == "hoppers":
        from .hoppers import run_hoppers
        try:
            got = run_hoppers(args.store, args.packing, args.hoppers, args.seed, args.frame_interval, args.workers,
                              args.volume_scale, args.retry_failed, say=lambda m: print(m, flush=True))
        except ValueError as exc:
            print(f"pydem images hoppers: {exc}", file=sys.stderr)
            return 2
        print(f"{args.store}: {len(got['stored'])} of {args.hoppers} hoppers stored, {len(got['failed'])} failed")
        return 0
    if args.cmd == "frames":
        failed = run_frames(args.store, args.cases, args.frame_interval, args.workers, say=lambda m: print(m, flush=True))
        return 1 if failed else 0
    if args.cmd == "subset":
        write_subset(args.store, args.out, args.every)
        return 0
    if args.cmd in ("compare", "point-to-point", "process"):
        import torch
        from . import experiments as ex
        torch.set_num_threads(args.threads)
        if torch.cuda.is_available():
            torch.backends.cudnn.benchmark = True  # fixed input shapes: cuDNN may pick its fastest kernels
        kw = {k: v for k, v in (("epochs", args.epochs), ("every", args.every)) if v is not None}
        kw["device"] = args.device
        if args.cmd != "process":
            kw["checkpoints"] = args.checkpoints
        if args.cmd == "compare":
            kw |= {k: v for k, v in (("models", args.models), ("time_budget", args.time_budget)) if v is not None}
        if args.cmd == "process":
            kw.pop("every", None)
            kw |= {"protocol": args.protocol, "inputs": args.inputs, "stride": args.stride, "target": args.target,
                   "warm_start": args.warm_start}
        if args.cmd != "compare":
            kw |= {"extra": args.extra, "extra_per_packing": args.extra_per_packing}
        run = {"compare": ex.compare, "point-to-point": ex.point_to_point, "process": ex.process}[args.cmd]
        try:
            run(args.store, args.out, size=args.size, seed=args.seed, **kw)
        except ValueError as exc:  # settings or stores that cannot go together, named
            print(f"pydem images {args.cmd}: {exc}", file=sys.stderr)
            return 2
        return 0
    store = FrameStore(args.store)
    discharge = {c: float(store.read_case(c)["discharge_time"]) for c in store.cases()}
    if len(discharge) < 2:
        print(f"{args.store}: {len(discharge)} case(s) stored; the GRA needs two or more", file=sys.stderr)
        return 2
    tables = gra_tables(discharge, args.rho)
    print("| parameter | " + " | ".join(tables) + " |\n|---|" + "---|" * len(tables))
    for p in PARAMETERS:
        print(f"| {p} | " + " | ".join(f"{t[p]:.2f} %" for t in tables.values()) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
