"""`pydem locus`: the Schulze outputs of one or more yield loci (one ring-shear result per
consolidation stress) as a table, and the loci with their Mohr circles and the flow function
as a plot.

    pydem rig ring-shear --set preshear_stress=1000 --out rs_1k.json
    pydem rig ring-shear --set preshear_stress=4000 --out rs_4k.json
    pydem locus rs_1k.json rs_4k.json --plot loci.png
"""
from __future__ import annotations

import json
import sys
from pathlib import Path


def add_parser(sub):
    p = sub.add_parser("locus", help="yield loci from ring-shear results: sigma_1, sigma_c, ffc, angles; Mohr-circle plot")
    p.add_argument("results", nargs="+", help="ring-shear result files (pydem rig ring-shear ... --out r.json)")
    p.add_argument("--plot", help="PNG of the loci with their Mohr circles and the flow function")
    p.set_defaults(func=main)


def main(args) -> int:
    from .rigs.yield_locus import Locus, flowability, plot_loci
    loci = []
    for f in args.results:
        try:
            data = json.loads(Path(f).read_text())
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            print(f"pydem locus: {f}: not a ring-shear result file (JSON from pydem rig ... --out r.json): {exc}",
                  file=sys.stderr)
            return 2
        try:
            loci.append(Locus.from_result(data, Path(f).stem))
        except (ValueError, KeyError, TypeError) as exc:
            print(f"pydem locus: {f}: {exc}", file=sys.stderr)
            return 2
    try:
        rows = [(lc, lc.evaluate()) for lc in loci]
    except ValueError as exc:
        print(f"pydem locus: {exc}", file=sys.stderr)
        return 2
    materials = list(dict.fromkeys(lc.material for lc in loci))
    print("| locus | material | sigma_pre (Pa) | sigma_1 (Pa) | sigma_c (Pa) | ffc | flowability (Jenike) | phi_e (deg) "
          "| phi_lin (deg) | phi_sf (deg) | c (Pa) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for lc, r in rows:
        print(f"| {lc.label} | {materials.index(lc.material) + 1} | {lc.sigma_pre:.0f} | {r.sigma_1:.0f} | "
              f"{r.sigma_c:.0f} | {r.ffc:.3g} | {flowability(r.ffc)} | {r.phi_e:.1f} | {r.phi_lin:.1f} | "
              f"{r.phi_sf:.1f} | {r.cohesion:.0f} |")
    if len(materials) > 1:
        print("\nmaterials (the rig's configuration but for the consolidation stress; each has its own flow function):")
        for m, material in enumerate(materials):
            print(f"  {m + 1}: {material or '(not stated in the result)'}")
    if args.plot:
        plot_loci(loci, args.plot)
        print(f"plot written to {args.plot}")
    return 0
