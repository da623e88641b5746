"""The pydem command line.

    pydem rig aor --preset tiny --set friction=0.6 --out result.h5 --frames frames/
    pydem rig aor --config my.toml
    pydem rig aor --list          # every key with its value, unit and meaning
"""
from __future__ import annotations

import argparse
import sys

from .cli_inputs import seed_value
from .output_dir import check_writable
from .errors import DemError
from .progress import RunProgress
from .rigs import RIGS, ConfigError, load
from .rigs.config import describe


def build_parser() -> argparse.ArgumentParser:
    from . import LIBDEM_VERSION, __version__
    ap = argparse.ArgumentParser(prog="pydem", description="libdem/pydem: DEM lab-test rigs for calibrating bulk solids")
    ap.add_argument("--version", action="version", version=f"pydem {__version__} (libdem {LIBDEM_VERSION})")
    sub = ap.add_subparsers(dest="command", required=True)
    rig = sub.add_parser("rig", help="run a lab-test rig")
    rig.add_argument("name", choices=sorted(RIGS), help="which rig")
    rig.add_argument("--preset", default="default", help="size preset: tiny, default, paper (ring shear also: cell)")
    rig.add_argument("--config", help="TOML file with keys (and [params], [effects.<name>] tables)")
    rig.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="override one key (repeatable)")
    rig.add_argument("--seed", type=seed_value, default=0)
    rig.add_argument("--out", help="result file (.h5, or JSON for any other name)")
    rig.add_argument("--frames", help="directory for PNG frames")
    rig.add_argument("--vtk", help="directory for a VTK time series at the frame times (ParaView: open particles.pvd)")
    rig.add_argument("--checkpoint", help="directory for the run's checkpoints; a rerun with it resumes, bitwise")
    rig.add_argument("--checkpoint-every", type=float, default=600.0, help="seconds of wall time between checkpoints")
    rig.add_argument("--list", action="store_true", help="list the keys of this rig and exit")
    rig.add_argument("--quiet", action="store_true", help="no progress line")
    from . import cli_calibrate, cli_campaign, cli_compare, cli_diagnose, cli_locus
    from .seed001 import command as images_command
    cli_campaign.add_parser(sub)
    cli_compare.add_parser(sub)
    cli_diagnose.add_parser(sub)
    cli_calibrate.add_parser(sub)
    cli_locus.add_parser(sub)
    images_command.add_parser(sub)
    return ap


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == ["images"]:
        from .seed001.command import forward
        return forward(argv[1:])
    args = build_parser().parse_args(argv)
    if hasattr(args, "func"):
        return args.func(args)

    cls, cfg_cls = RIGS[args.name]
    try:
        cfg = load(cfg_cls, args.preset, args.config, args.set)
    except ConfigError as exc:
        print(f"pydem: bad configuration: {exc}", file=sys.stderr)
        return 2
    if args.list:
        for key, value, unit, doc in describe(cfg):
            print(f"{key:28s} {value!s:>14} {unit:8s} {doc}")
        return 0
    try:  # before the run, not after it: a bad path must not cost a finished run
        if args.out:
            check_writable(args.out, directory=False)
        for directory in (args.frames, args.vtk):
            if directory:
                check_writable(directory, directory=True)
    except OSError as exc:
        print(f"pydem: cannot write the output: {exc}", file=sys.stderr)
        return 2
    extra = {}
    if args.checkpoint:
        extra = {"checkpoint": args.checkpoint, "checkpoint_every": args.checkpoint_every}
    progress = None if args.quiet else RunProgress()
    try:
        result = cls(cfg).run(seed=args.seed, frames_dir=args.frames, progress=progress, vtk_dir=args.vtk, **extra)
    except (DemError, ValueError) as exc:
        if progress:
            progress.done()
        print(f"pydem: the run failed: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        if progress:
            progress.done()
        print("pydem: interrupted (frames written so far are kept" +
              (f"; the same command resumes from the last checkpoint in {args.checkpoint})" if args.checkpoint else ")"),
              file=sys.stderr)
        return 130
    if progress:
        progress.done()
    from .provenance import provenance
    result.provenance = provenance() | {"rig": args.name, "preset": args.preset, "seed": args.seed,
                                        "config": {k: v if isinstance(v, (int, float, str, bool)) else str(v)
                                                   for k, v, _, _ in describe(cfg)}}
    print(result.summary())
    if args.out:
        try:
            result.save(args.out)
        except OSError as exc:
            print(f"pydem: cannot write {args.out}: {exc}", file=sys.stderr)
            return 2
        print(f"result written to {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
