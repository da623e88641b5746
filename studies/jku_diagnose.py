"""Seed 000's eight JKU materials through the diagnosis on the shipped default stores, each with its
own sieve table and an assumed particle density (data/measurements/jku_angle_of_repose.csv): the
verdict, what the one angle decides (the base parameters' 95 % intervals: a ridge, not a point),
which parameter the box stops and the campaign that would move it.

    .venv/bin/python studies/jku_diagnose.py   # -> studies/results/jku_diagnose.{json,md}
"""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pydem.calibration.diagnose import diagnose  # noqa: E402
from pydem.calibration.reach import name_campaigns  # noqa: E402
from pydem.calibration.setup import DEFAULT_STORES, load_setup, observations_of  # noqa: E402
from pydem.calibration.similarity import MaterialProperties  # noqa: E402
from pydem.measurements import load as load_measurements  # noqa: E402

MEAS = ROOT / "data/measurements/jku_angle_of_repose.csv"
OUT = ROOT / "studies/results/jku_diagnose"
BASE = ("friction", "rolling_friction", "restitution")


def main() -> int:
    t0 = time.perf_counter()
    setup0 = load_setup([ROOT / s for s in DEFAULT_STORES], say=lambda *a: None)
    materials = sorted({m.material for m in load_measurements(MEAS)})
    rows = []
    for name in materials:
        meas = load_measurements(MEAS, name)
        scaling = setup0.scaling(MaterialProperties.from_rows(meas))
        setup = setup0.for_material(scaling)
        obs, skipped = observations_of(meas, setup, str(MEAS), name, scaling)
        d = diagnose(name, obs, setup.nets, setup.ranges, setup.candidates, say=lambda *a: None)
        edges = name_campaigns(d.reach, setup.stores, {o.quantity.rig for o in obs})
        post = d.as_dict()["base_parameters"]
        rows.append({"material": name, "measured": obs[0].value, "verdict": d.verdict,
                     "model": float(d.base_model.predict(d.base.best)[0]),
                     "mean_diameter_mm": 1e3 * scaling.material.mean_diameter, "size_spread": scaling.material.spread,
                     "particle_density": scaling.material.particle_density,
                     "intervals": {p: [post[p]["lo"], post[p]["hi"], post[p]["interval"]] for p in BASE},
                     "held_back": [f"{r['parameter']} {r['edge']}" for r in d.reach], "edges": edges,
                     "notes": scaling.notes(setup.ranges)})
        print(name, d.verdict, flush=True)
    OUT.with_suffix(".json").write_text(json.dumps({"date": time.strftime("%Y-%m-%d"), "stores": list(DEFAULT_STORES),
                                                    "seconds": time.perf_counter() - t0, "rows": rows}, indent=1))
    md = ["| material | d̄ (mm) | spread (sieve → model) | measured | model's best | verdict | friction | rolling friction | restitution |",
          "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        iv = [f"{lo:.2f}–{hi:.2f}" + ("" if kind == "central" else " (one-sided)") for lo, hi, kind in
              (r["intervals"][p] for p in BASE)]
        md.append(f"| {r['material']} | {r['mean_diameter_mm']:.2f} | {r['size_spread']:.2f} → {min(r['size_spread'], 0.5):.2f} "
                  f"| {r['measured']:.2f}° | {r['model']:.2f}° | {r['verdict']} | " + " | ".join(iv) + " |")
    OUT.with_suffix(".md").write_text("\n".join(md) + "\n")
    print("\n".join(md))
    return 0


if __name__ == "__main__":
    sys.exit(main())
