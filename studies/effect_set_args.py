"""The command line the surrogate effect-set studies share (diagnosis_detectability.py,
diagnosis_next_test.py): --preset, --sets, --seed, and the setup of the preset's shipped stores."""
from __future__ import annotations

import argparse
from pathlib import Path

from pydem.calibration.setup import load_setup, shipped_stores

ROOT = Path(__file__).resolve().parents[1]


def parse_and_load(description: str | None = None):
    """(args, setup): the parsed options and the diagnosis setup of the preset's shipped stores."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("--preset", default="default")
    ap.add_argument("--sets", type=int, default=30, help="sets per candidate effect")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    stores = [s for s in (ROOT / p for p in shipped_stores(args.preset)) if s.exists()]
    return args, load_setup(stores, say=lambda *a: None)
