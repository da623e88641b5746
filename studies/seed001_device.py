"""Seed 001's image experiments on a GPU machine, where pydem's compiled binding is usually not
built (another Python, no HDF5 headers): the image networks need only torch, h5py and numpy, so
this runner imports pydem's pure-Python modules (the frame store, Table 1) without the binding
and then runs `pydem images`' own command line (pydem/seed001/cli.py) with the same arguments.
The seed-scale comparison of docs/seed001.md (224 x 224, every frame):

    python3 studies/seed001_device.py compare --store data/seed001/frames_full.h5 --out OUT \\
        --size 224 --every 1 --epochs 30 --time-budget 75 --checkpoints /tmp/seed001_checkpoints
    python3 studies/seed001_device.py point-to-point --store data/seed001/frames_full.h5 --out OUT \\
        --size 224 --every 1 --epochs 30 --checkpoints /tmp/seed001_checkpoints

(checkpoints outside OUT: a VGG's is 1.6 GB)."""
from __future__ import annotations

import os
import sys
import types
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def import_without_binding():
    """pydem's package __init__ loads the compiled binding; where it cannot, register pydem and
    pydem.rigs as bare packages so their pure-Python modules (the seed001 study, rigs.table1) still import."""
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
    import_without_binding()
    from pydem.seed001.cli import main as seed001
    return seed001(argv, prog="studies/seed001_device.py")


if __name__ == "__main__":
    sys.exit(main())
