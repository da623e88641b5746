"""`pydem campaign run|status|export`: simulation campaigns from the command line.

    pydem campaign run data/campaigns/ring_shear_tiny.toml --store rs.h5   # new, or continue
    pydem campaign run --store rs.h5 --samples 512                         # extend, then run
    pydem campaign run --store rs.h5 --replicates 2                        # every point once more
    pydem campaign run --store rs.h5 --replicates 2 --points 128           # ... the first 128 points first
    pydem campaign run --store rs.h5 --dask tcp://scheduler:8786
    pydem campaign status rs.h5
    pydem campaign export rs.h5 --csv rs.csv
"""
from __future__ import annotations

import dataclasses
import json
import sys
from pathlib import Path


def add_parser(sub):
    p = sub.add_parser("campaign", help="simulation campaigns (resumable HDF5 store)")
    csub = p.add_subparsers(dest="action", required=True)
    run = csub.add_parser("run", help="create (from a TOML spec) or continue a campaign")
    run.add_argument("spec", nargs="?", help="campaign specification (TOML); not needed to continue a store")
    run.add_argument("--store", required=True, help="the campaign's HDF5 store")
    run.add_argument("--samples", type=int, help="samples of a new campaign (instead of the spec's), or grow a store to this many")
    run.add_argument("--replicates", type=int, help="runs per design point (different seeds): new, or grow a store to this many")
    run.add_argument("--workers", type=int, help="local worker processes (default: cores / threads per run)")
    run.add_argument("--dask", metavar="ADDRESS", help="run on a Dask cluster, e.g. tcp://host:8786")
    run.add_argument("--retry-failed", action="store_true", help="run the failed samples again")
    run.add_argument("--max-runs", type=int, help="stop after this many runs (the rest stay pending)")
    run.add_argument("--points", type=int, help="run only the runs of the first N design points (the rest stay pending)")
    run.add_argument("--rerun", type=int, nargs="+", metavar="RUN",
                     help="run only these runs (store indices) again, replacing their results: after a rig fix that "
                          "changes what they measure")
    run.add_argument("--quiet", action="store_true")
    st = csub.add_parser("status", help="counts, timings, failures and provenance of a store")
    st.add_argument("store")
    ex = csub.add_parser("export", help="write a store's samples and metrics as CSV")
    ex.add_argument("store")
    ex.add_argument("--csv", required=True)
    p.set_defaults(func=main)


def main(args) -> int:
    from .campaign import Campaign, CampaignSpec, SpecError, StoreError
    try:
        if args.action == "status":
            print(Campaign.open(args.store).status_text())
        elif args.action == "export":
            Campaign.open(args.store).export_csv(args.csv)
            print(f"written {args.csv}")
        else:
            target, replicates = args.samples, args.replicates
            for flag, value in (("--samples", target), ("--replicates", replicates), ("--points", args.points)):
                if value is not None and value < 1:
                    raise SpecError(f"{flag}: expected a positive count, got {value}")
            if Path(args.store).exists():
                c = Campaign.open(args.store)
                if args.spec:
                    spec = CampaignSpec.from_toml(args.spec)
                    if not _same_campaign(spec, c.store.spec):
                        raise SpecError(f"{args.spec} differs from the specification stored in {args.store}; "
                                        "use a new store for a new campaign")
                    target = target or spec.samples
                    replicates = replicates or spec.replicates
            elif args.spec:
                spec = CampaignSpec.from_toml(args.spec)
                spec.samples = args.samples or spec.samples  # --samples / --replicates override the spec's counts
                spec.replicates = args.replicates or spec.replicates
                c = Campaign.create(args.store, spec)
            else:
                raise SpecError(f"{args.store} does not exist: give a campaign spec (TOML) to create it")
            if target or replicates:
                c.grow(target, replicates)
            counts = c.run(workers=args.workers, dask=args.dask, retry_failed=args.retry_failed,
                           max_runs=args.max_runs, quiet=args.quiet, points=args.points, rerun=args.rerun)
            print(f"campaign {args.store}: done {counts['done']}, failed {counts['failed']}, pending {counts['pending']}")
    except (SpecError, StoreError) as exc:
        print(f"pydem campaign: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # e.g. an export to a directory that does not exist
        print(f"pydem campaign: {exc.filename or ''}: {exc.strerror or exc}".replace(": : ", ": "), file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("\npydem campaign: interrupted; finished runs are saved, run again to continue", file=sys.stderr)
        return 130
    return 0


def _same_campaign(a, b) -> bool:
    """Same campaign whatever the sample and replicate counts (a spec may ask for more: the store grows)."""
    da, db = dataclasses.asdict(a), dataclasses.asdict(b)
    for key in ("samples", "replicates"):
        da.pop(key), db.pop(key)
    return json.loads(json.dumps(da)) == json.loads(json.dumps(db))
