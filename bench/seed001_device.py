"""Seed 001's four-CNN comparison and AlexNet-FC at the seed's scale — 224 x 224 frames, every
stored frame — on a GPU machine, where pydem's compiled binding is usually not built (another
Python, no HDF5 headers): the image networks need only torch, h5py and numpy, and this runner
imports pydem's pure-Python modules (the frame store, Table 1) without the binding.

    python3 bench/seed001_device.py --store data/seed001/frames_full.h5 --out OUT [--epochs 30 --time-budget 90]

Writes OUT/compare.json (after every network, so a run cut short keeps what finished) and
OUT/point_to_point.json; checkpoints go to a scratch folder (a VGG's is 1.6 GB). The CPU runs
use the same code through `pydem images compare|point-to-point`; docs/seed001.md has both."""
from __future__ import annotations

import argparse
import os
import sys
import time
import types
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def import_without_binding():
    """pydem's package __init__ loads the compiled binding; where it cannot, register pydem and
    pydem.rigs as bare packages so their pure-Python modules (frames, table1) still import."""
    try:
        if os.environ.get("SEED001_NO_BINDING"):  # lets the CPU machines test this path
            raise ImportError("SEED001_NO_BINDING set")
        import pydem  # noqa: F401
    except ImportError as exc:
        print(f"pydem's binding not loaded ({exc}); using its pure-Python modules only", flush=True)
        for name, sub in (("pydem", "pydem"), ("pydem.rigs", "pydem/rigs")):
            mod = types.ModuleType(name)
            mod.__path__ = [str(ROOT / sub)]
            sys.modules[name] = mod
            if "." in name:
                setattr(sys.modules[name.rsplit(".", 1)[0]], name.rsplit(".", 1)[1], mod)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--store", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--size", type=int, default=224)
    ap.add_argument("--every", type=int, default=1)
    ap.add_argument("--epochs", type=int, default=30)
    ap.add_argument("--p2p-epochs", type=int, default=30)
    ap.add_argument("--time-budget", type=float, default=90.0, help="s of training per network (compare)")
    ap.add_argument("--models", nargs="+", default=["alexnet", "resnet50", "vgg16", "vgg19"])
    ap.add_argument("--scratch", default="/tmp/seed001_checkpoints")
    ap.add_argument("--device", default="auto")
    args = ap.parse_args(argv)
    import_without_binding()
    import torch
    from nn import seed001_experiments as ex
    if torch.cuda.is_available():
        torch.backends.cudnn.benchmark = True  # fixed input shapes: let cuDNN pick its fastest kernels
        print(f"torch {torch.__version__} on {torch.cuda.get_device_name(0)}", flush=True)
    say = lambda m: print(m, flush=True)  # noqa: E731
    t0 = time.perf_counter()
    ex.compare(args.store, args.out, size=args.size, every=args.every, epochs=args.epochs, models=args.models,
               device=args.device, time_budget=args.time_budget, checkpoints=Path(args.scratch) / "compare", say=say)
    say(f"compare done in {time.perf_counter() - t0:.0f} s")
    t0 = time.perf_counter()
    ex.point_to_point(args.store, args.out, size=args.size, every=args.every, epochs=args.p2p_epochs,
                      device=args.device, checkpoints=Path(args.scratch) / "p2p", say=say)
    say(f"point-to-point done in {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
