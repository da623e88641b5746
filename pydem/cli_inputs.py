"""What the commands share of their inputs: the measurement file, the material and the campaign
stores (`pydem diagnose`, `calibrate`, `compare`), the seeds, and the output checked before any
work is done (pydem.output_dir)."""
from __future__ import annotations

import sys

from . import output_dir


def add_common(p, out: str):
    """The arguments `pydem diagnose` and `pydem calibrate` share. `out`: the default output
    directory; with "{material}" in it, a folder per material (output_of)."""
    p.add_argument("measurements", help="measurement file (docs/measurements.md)")
    p.add_argument("--material", required=True)
    add_stores(p)
    p.add_argument("--out", default=out, help=f"output directory (default {out})")
    p.add_argument("--confirm", action="store_true", help="confirming DEM runs at the final estimate, every condition")
    p.add_argument("--threads", type=int, help="threads of the native screening and the confirming runs (default: "
                                               "OMP_NUM_THREADS when set, else the cores this process may use)")
    p.add_argument("--retrain", action="store_true", help="train the surrogates again even when cached")


def output_of(args) -> str:
    """--out as given, or its default with the material's name in place of "{material}" (one folder
    per material, so diagnosing a second material never meets the first one's output); a name that
    is not a plain file name gives "material"."""
    import re
    if "{material}" not in args.out:
        return args.out
    name = args.material if re.fullmatch(r"[\w.+-]{1,100}", args.material) and args.material not in (".", "..") else "material"
    return args.out.replace("{material}", name)


def add_stores(p):
    p.add_argument("--stores", nargs="+",
                   help="campaign stores: one per rig, and others of a rig pooled into its surrogates (default: the "
                        "shipped diagnosis stores, found from any directory: pydem.shipped)")


def store_paths(args) -> list:
    """The --stores given, else the shipped diagnosis stores wherever they are installed."""
    from .calibration.setup import DEFAULT_STORES
    from .shipped import shipped_path
    return args.stores or [shipped_path(s) for s in DEFAULT_STORES]


def load_inputs(args, command: str, say):
    """(setup, observations, rows left out, the material's Scaling), or None after printing why not
    (exit status 2)."""
    from .calibration.quantities import ObservationError
    from .calibration.setup import load_setup, observations_of
    from .calibration.similarity import MaterialProperties
    from .campaign import StoreError
    from .measurements import MeasurementError, load as load_measurements
    from .rigs.config import default_threads
    if hasattr(args, "threads"):  # calibrate and diagnose: OMP_NUM_THREADS honoured, screening included
        args.threads = default_threads() if args.threads is None else args.threads
        if args.threads < 1:
            print(f"pydem {command}: --threads must be at least 1, got {args.threads}", file=sys.stderr)
            return None
    try:
        rows = load_measurements(args.measurements, args.material)  # the file's own errors first: cheap, and the user's
        material = MaterialProperties.from_rows(rows)
        setup = load_setup(store_paths(args), say, getattr(args, "retrain", False))
        scaling = setup.scaling(material)
        setup = setup.for_material(scaling)
        obs, skipped = observations_of(rows, setup, str(args.measurements), args.material, scaling)
    except (MeasurementError, ObservationError, StoreError, ValueError, OSError) as exc:
        print(f"pydem {command}: {exc}", file=sys.stderr)
        return None
    for line in skipped:
        say(f"  left out: {line}")
    for line in scaling.notes(setup.ranges):
        say(f"  material: {line}")
    return setup, obs, skipped, scaling


def seed_value(text: str) -> int:
    """argparse type of every --seed: an integer in 0..MAX_SEED, else a usage error naming the range."""
    import argparse
    from .domain import MAX_SEED
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
    if not 0 <= v <= MAX_SEED:
        raise argparse.ArgumentTypeError(f"{text} is outside 0..{MAX_SEED}")
    return v


def output_checked(out: str, command: str) -> bool:
    """`--out` of diagnose and calibrate checked before any work (output_dir.check); False after
    printing why not (exit status 2)."""
    try:
        output_dir.check(out)
    except output_dir.OutputError as exc:
        print(f"pydem {command}: {exc}", file=sys.stderr)
        return False
    return True
