"""Writes a clearly labelled synthetic material: pseudo-measurements made by our own rigs (DEM
runs at the diagnosis stores' preset) on the protocol's conditions, with one effect switched on,
plus lab noise (pydem.calibration.synthetic). The truth goes into the file's comments.

    .venv/bin/python scripts/make_synthetic_material.py --effect cohesion_sjkr --strength 6e4 \\
        --name synthetic_cohesive --out data/measurements/synthetic_cohesive.csv

or from a set that studies/diagnosis_dem_sets.py already ran (its journal keeps the rigs' raw
values and the truth; only the lab noise is drawn here):

    .venv/bin/python scripts/make_synthetic_material.py --journal studies/results/dem_sets_default.jsonl \\
        --set 1 --preset default --name synthetic_cohesive --out data/measurements/synthetic_cohesive.csv

--particle-density writes the same material at another particle density (by similarity,
calibration/similarity.py: bulk densities, flow rates and pre-shear stresses times rho / 2500) with
its `particle_density` row; --sieve adds a sieve table ("lower size mm:mass fraction,...").
"""
from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pydem.calibration import synthetic  # noqa: E402
from pydem.calibration.setup import load_setup, shipped_stores  # noqa: E402
from pydem.quantity_table import metric_spec  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--preset", default="tiny")
    ap.add_argument("--effect", help="candidate switched on (none: a null material)")
    ap.add_argument("--strength", type=float, help="its parameter value")
    ap.add_argument("--theta", default="friction=0.5,rolling_friction=0.2,restitution=0.5")
    ap.add_argument("--name", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--journal", help="take the rigs' values and the truth from this diagnosis_dem_sets.py journal")
    ap.add_argument("--set", type=int, default=0, help="the journal's line (0-based)")
    ap.add_argument("--particle-density", type=float, help="kg/m^3: the material at this particle density (similarity)")
    ap.add_argument("--sieve", help="a sieve table, 'lower sieve size in mm (or pan):mass fraction retained,...'")
    a = ap.parse_args()
    stores = [ROOT / s for s in shipped_stores(a.preset)]
    setup = load_setup([s for s in stores if s.exists()])
    rng = np.random.default_rng(a.seed)
    if a.journal:
        row = json.loads(Path(a.journal).read_text().splitlines()[a.set])
        truth, obs = synthetic.journal_set(row, setup.nets, setup.candidates, rng)
        a.effect, a.strength = truth.effect, truth.strength
    else:
        theta = {k: float(v) for k, v in (kv.split("=") for kv in a.theta.split(","))}
        cand = next((c for c in setup.candidates if c.name == a.effect), None) if a.effect else None
        truth = synthetic.Truth(theta, a.effect, cand.parameter if cand else None, a.strength)
        obs = synthetic.dem_set(setup.stores, setup.nets, setup.candidates, truth, rng, synthetic.programme(setup.nets),
                                seed=a.seed, threads=a.threads)
    note = (f"SYNTHETIC material '{a.name}': made by pydem's own rigs (preset {a.preset}) with "
            + (f"{a.effect} = {a.strength:g} switched on" if a.effect else "no hidden effect")
            + f", lab noise added (2 % friction coefficients, 1 % bulk density, 0.5 deg angle, 2 % hopper); "
              f"command: {' '.join(sys.argv)}")
    material_rows = []
    if a.particle_density:
        k = a.particle_density / next(iter(setup.stores.values())).spec.config({}).params.density
        obs = [replace(o, value=o.value * (k if metric_spec(o.quantity.metric).scales_with_density else 1.0),
                       uncertainty=o.uncertainty * (k if metric_spec(o.quantity.metric).scales_with_density else 1.0),
                       conditions={c: v * k if c == "preshear_stress" else v for c, v in o.conditions.items()})
               for o in obs]
        material_rows.append(f"particle_density,{a.particle_density:g},kg/m^3,")
        note += f"; at particle density {a.particle_density:g} kg/m^3 by similarity"
    for item in (a.sieve.split(",") if a.sieve else []):
        size, frac = item.split(":")
        material_rows.append(f"sieve_retained,{frac},,sieve_mm={size}")
    synthetic.to_csv(a.out, a.name, obs, truth, note, material_rows)
    print(f"{len(obs)} rows -> {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
