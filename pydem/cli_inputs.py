"""What the commands share of their inputs: the measurement file, the material and the campaign
stores (`pydem diagnose`, `calibrate`, `compare`), and the check that an output can be written
before any work is done."""
from __future__ import annotations

import os
import sys
from pathlib import Path


def add_common(p, out: str, threads: int):
    """The arguments `pydem diagnose` and `pydem calibrate` share."""
    from .calibration.setup import DEFAULT_STORES
    p.add_argument("measurements", help="measurement file (docs/measurements.md)")
    p.add_argument("--material", required=True)
    p.add_argument("--stores", nargs="+", default=list(DEFAULT_STORES),
                   help="campaign stores: one per rig, and others of a rig pooled into its surrogates (default: the shipped diagnosis stores)")
    p.add_argument("--out", default=out)
    p.add_argument("--confirm", action="store_true", help="confirming DEM runs at the final estimate, every condition")
    p.add_argument("--threads", type=int, default=threads, help=f"threads of the confirming runs (default {threads})")
    p.add_argument("--retrain", action="store_true", help="train the surrogates again even when cached")


def load_inputs(args, command: str, say):
    """(setup, observations, rows left out), or None after printing why not (exit status 2)."""
    from .calibration.quantities import ObservationError
    from .calibration.setup import load_setup, observations_of
    from .campaign import StoreError
    from .measurements import MeasurementError, load as load_measurements
    try:
        rows = load_measurements(args.measurements, args.material)  # the file's own errors first: cheap, and the user's
        setup = load_setup(args.stores, say, getattr(args, "retrain", False))
        obs, skipped = observations_of(rows, setup, str(args.measurements), args.material)
    except (MeasurementError, ObservationError, StoreError, ValueError, OSError) as exc:
        print(f"pydem {command}: {exc}", file=sys.stderr)
        return None
    for line in skipped:
        say(f"  left out: {line}")
    return setup, obs, skipped


def check_writable(path: str, directory: bool):
    """Raises OSError naming the path when it cannot be written (a directory is created)."""
    p = Path(path)
    d = p if directory else (p.parent if str(p.parent) else Path("."))
    if directory:
        p.mkdir(parents=True, exist_ok=True)
    if not d.is_dir():
        raise OSError(f"{d}: no such directory")
    if not os.access(d, os.W_OK) or (p.exists() and not directory and not os.access(p, os.W_OK)):
        raise OSError(f"{path}: permission denied")
