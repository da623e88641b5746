"""`pydem compare`: a given model against a measurement file, row by row at each row's condition
— the surrogates of the campaign stores at a parameter set, or DEM rig results.

    pydem compare data/measurements/synthetic_cohesive.csv --material synthetic_cohesive \\
        --params friction=0.5,rolling_friction=0.2,restitution=0.5
    pydem compare MEAS.csv --material M --dem ring_shear_2kPa.json --dem aor.json
"""
from __future__ import annotations

import math
import sys

from .cli_inputs import add_stores, load_inputs


def add_parser(sub):
    p = sub.add_parser("compare", help="a model vs measurements, row by row at each condition: residuals, z, overall error")
    p.add_argument("measurements")
    p.add_argument("--material", required=True)
    p.add_argument("--params", help="the surrogates at this parameter set: name=value,name=value")
    add_stores(p)
    p.add_argument("--dem", action="append", default=[], help="rig result JSON (pydem rig ... --out r.json); repeatable")
    p.set_defaults(func=main)


def _params(text: str) -> dict[str, float]:
    out = {}
    for item in text.split(","):
        if "=" not in item:
            raise ValueError(f"--params: expected name=value, got {item!r}")
        k, v = item.split("=", 1)
        out[k.strip()] = float(v)
        if not math.isfinite(out[k.strip()]):
            raise ValueError(f"--params: {k.strip()} is not a finite number")
    return out


def main(args) -> int:
    from .calibration.compare import dem_rows, overall, surrogate_rows
    say = lambda msg: print(msg, flush=True)  # noqa: E731
    if bool(args.params) == bool(args.dem):
        print("pydem compare: give --params (the surrogates at a parameter set) or --dem result files", file=sys.stderr)
        return 2
    loaded = load_inputs(args, "compare", say)
    if loaded is None:
        return 2
    setup, obs, _, _ = loaded
    try:
        if args.params:
            rows, unmatched = surrogate_rows(obs, setup, _params(args.params)), []
        else:
            rows, unmatched = dem_rows(obs, args.dem)
    except (ValueError, OSError, KeyError) as exc:
        print(f"pydem compare: {exc}", file=sys.stderr)
        return 2
    print("| measurement | measured | u | model | sigma | z | relative |\n|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['label']} | {r['measured']:.4g} | {r['u_measured']:.3g} | {r['model']:.4g} | {r['sigma']:.3g} | "
              f"{r['z']:+.2f} | {100 * r['relative']:+.1f} % |")
    o = overall(rows)
    print(f"\n{o['n']} rows: RMSE of relative residuals {o['rmse_relative']:.3f}, chi^2 per row {o['chi2_per_value']:.2f}")
    for line in unmatched:
        print(f"left out: {line}")
    return 0
