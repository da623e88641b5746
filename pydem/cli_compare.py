"""`pydem compare`: a model (the surrogate nets at a parameter set, or DEM results) against a
measurement file: residual table with z-scores, overall error, plot.

    pydem compare data/measurements/glass_microbeads.csv --material glass_microbeads \\
        --nets build/calibration/nets --params friction=0.3,rolling_friction=0.05,restitution=0.5
    pydem compare data/measurements/glass_microbeads.csv --material glass_microbeads --dem result.json
"""
from __future__ import annotations

import sys


def add_parser(sub):
    p = sub.add_parser("compare", help="model vs measurements: residuals, z-scores, overall error, plot")
    p.add_argument("measurements")
    p.add_argument("--material", required=True)
    p.add_argument("--nets", help="directory of exported nets (<rig>__<metric>.mlp)")
    p.add_argument("--params", help="parameter set for the nets: name=value,name=value")
    p.add_argument("--dem", action="append", default=[], help="rig result JSON (pydem rig ... --out r.json); repeatable")
    p.add_argument("--plot", help="PNG path for the plot")
    p.set_defaults(func=main)


def main(args) -> int:
    from . import compare as cmp
    from .measurements import MeasurementError, load
    try:
        meas = load(args.measurements, args.material)
        if args.nets:
            if not args.params:
                raise ValueError("--nets needs --params name=value,...")
            params = {}
            for item in args.params.split(","):
                if "=" not in item:
                    raise ValueError(f"--params: expected name=value, got {item!r}")
                k, v = item.split("=", 1)
                params[k.strip()] = float(v)
            model = cmp.surrogate_model(args.nets, params)
        elif args.dem:
            model = cmp.dem_model(args.dem)
        else:
            raise ValueError("give --nets with --params, or --dem result files")
    except (MeasurementError, ValueError, OSError, KeyError) as exc:
        print(f"pydem compare: {exc}", file=sys.stderr)
        return 2
    res = cmp.compare(meas, model)
    print(cmp.table_markdown(res))
    if args.plot:
        cmp.plot(res, args.plot, f"{args.material}: model vs measurements")
        print(f"plot written to {args.plot}")
    return 0
