"""`pydem diagnose`: where the base model fails against a measurement file, which candidate
effect is missing, and the error before and after adding it (docs/diagnosis.md).

    pydem diagnose data/measurements/synthetic_cohesive.csv --material synthetic_cohesive --out build/diagnosis
"""
from __future__ import annotations

import sys
import time


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
    from .calibration.setup import load_setup, observations_from_file
    from .campaign import StoreError
    from .measurements import MeasurementError, load as load_measurements
    try:
        load_measurements(args.measurements, args.material)  # the file's own errors first: cheap, and the user's
        setup = load_setup(args.stores, say, getattr(args, "retrain", False))
        obs, skipped = observations_from_file(args.measurements, args.material, setup)
    except (MeasurementError, ObservationError, StoreError, ValueError, OSError) as exc:
        print(f"pydem {command}: {exc}", file=sys.stderr)
        return None
    for line in skipped:
        say(f"  left out: {line}")
    return setup, obs, skipped


def add_parser(sub):
    p = sub.add_parser("diagnose", help="calibrate, show where the model fails, name the missing effect, add it")
    add_common(p, "build/diagnosis", 1)
    p.set_defaults(func=main)


def main(args) -> int:
    from .calibration import report
    from .calibration.diagnose import diagnose
    t0 = time.perf_counter()
    say = lambda msg: print(msg, flush=True)  # noqa: E731
    loaded = load_inputs(args, "diagnose", say)
    if loaded is None:
        return 2
    setup, obs, skipped = loaded
    say(f"diagnosing {args.material}: {len(obs)} measurements, candidates "
        f"{', '.join(c.name for c in setup.candidates)} (stores: libdem {setup.physics})")
    try:
        d = diagnose(args.material, obs, setup.nets, setup.ranges, setup.candidates, say)
    except ValueError as exc:
        print(f"pydem diagnose: {exc}", file=sys.stderr)
        return 2
    d.notes += [f"left out: {line}" for line in skipped]
    from .provenance import provenance
    context = {"provenance": provenance(), "measurements": str(args.measurements),
               "stores": setup.store_provenance(), "libdem_of_stores": setup.physics}
    if args.confirm:
        from .calibration.confirm import confirm
        from .cli import ProgressLine
        fit = d.after if d.after is not None else d.base
        context["confirm"] = confirm(setup, fit, obs, args.threads, say, ProgressLine())
    path = report.write(d, args.out, context)
    from .calibration import material_card  # the final model: with the effect when one was added
    material_card.write(material_card.card(args.material, setup, d.after if d.after is not None else d.base,
                                           setup.candidates), args.out)
    say(f"verdict: {d.verdict}" + (f" ({d.effect})" if d.effect else "") + f" — {report.verdict_line(d)}")
    say(f"report: {path} ({time.perf_counter() - t0:.0f} s)")
    return 0
