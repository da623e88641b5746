"""DEM-made sets of materials the stores were not made for, diagnosed with their `material` rows
(docs/diagnosis.md §1). One null material — set 0 of studies/results/dem_sets_default.jsonl, whose
rig values at the stores' material are in that journal — made again by the rigs as

  dense   a material at 4000 kg/m^3: every run at 4000 kg/m^3 with the tool's modulus rule (8 MPa),
          its pre-shear stresses 1.6x the programme's (a lab's stresses on the denser material);
          the file says `particle_density 4000`
  coarse  spheres 1.25x the hopper store's (7.5 / 11.25 mm, the fill's count / 1.25^3) in slots
          1.25x the programme's; the ring-shear and angle-of-repose values are the set's own (the
          model's spheres there are the stores'); the file says `particle_diameter` 1.25 x 8.1 mm

Each set gets the same lab-noise draw, is written as a measurement file and diagnosed on the
shipped default stores; the stores' version of the set beside them. The rig runs go to a journal
(resumable: a variant already run is not run again).

    .venv/bin/python studies/material_sets.py --out studies/results/material_sets.json
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pydem.calibration import synthetic  # noqa: E402
from pydem.calibration.confirm import rig_values  # noqa: E402
from pydem.calibration.diagnose import diagnose  # noqa: E402
from pydem.calibration.quantities import Observation, Quantity  # noqa: E402
from pydem.calibration.setup import DEFAULT_STORES, load_setup, observations_of  # noqa: E402
from pydem.calibration.similarity import MaterialProperties  # noqa: E402
from pydem.measurements import load as load_measurements  # noqa: E402

JOURNAL = ROOT / "studies/results/dem_sets_default.jsonl"
K, LAM = 1.6, 1.25
HOPPER_COARSE = {"d_small": 6e-3 * LAM, "d_large": 9e-3 * LAM, "particles": round(2000 / LAM ** 3)}


def rows_of(journal_row) -> list[Observation]:
    return [Observation(Quantity(r["rig"], r["metric"]), dict(r["conditions"]), float("nan"), float("nan"), r["label"])
            for r in journal_row["rows"]]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--runs", default=str(ROOT / "studies/results/material_sets.jsonl"), help="the rig runs' journal")
    ap.add_argument("--seed", type=int, default=7, help="the lab noise's seed (the same draw for every variant)")
    a = ap.parse_args()
    setup = load_setup([ROOT / s for s in DEFAULT_STORES], say=lambda *x: None)
    row0 = json.loads(JOURNAL.read_text().splitlines()[0])
    truth = synthetic.Truth(**row0["truth"])
    inputs = truth.inputs(setup.candidates)
    base = rows_of(row0)
    stores_values = {i: r["value"] for i, r in enumerate(row0["rows"]) if r["value"] is not None}
    runs = {}
    if Path(a.runs).exists():
        runs = {r["variant"]: r for r in map(json.loads, Path(a.runs).read_text().splitlines())}

    def run(variant, obs, extra, rigs):
        if variant not in runs:
            idx = [i for i, o in enumerate(obs) if o.quantity.rig in rigs]
            t0 = time.perf_counter()
            got = rig_values(setup.stores, inputs, [obs[i] for i in idx], seed=11, extra=extra)
            runs[variant] = {"variant": variant, "values": {str(idx[j]): v for j, v in got.items()},
                             "seconds": time.perf_counter() - t0}
            with open(a.runs, "a") as f:
                f.write(json.dumps(runs[variant]) + "\n")
        return {int(i): v for i, v in runs[variant]["values"].items()}

    dense_obs = [replace(o, conditions={c: v * K if c == "preshear_stress" else v for c, v in o.conditions.items()})
                 for o in base]
    dense_vals = run("dense", dense_obs, {"density": 2500.0 * K, "youngs_modulus": 5e6 * K}, {"ring-shear", "aor", "hopper"})
    coarse_obs = [replace(o, conditions={c: v * LAM if c == "slot_width" else v for c, v in o.conditions.items()})
                  for o in base]
    coarse_vals = dict(stores_values)
    for i in [i for i, o in enumerate(base) if o.quantity.rig == "hopper"]:
        coarse_vals.pop(i, None)
    coarse_vals.update(run("coarse", coarse_obs, HOPPER_COARSE, {"hopper"}))
    hopper_d = 0.3 * 6e-3 + 0.7 * 9e-3
    variants = {"stores' material": (base, stores_values, []),
                "dense (4000 kg/m^3)": (dense_obs, dense_vals, [f"particle_density,{2500 * K:g},kg/m^3,"]),
                "coarse (hopper spheres x1.25)": (coarse_obs, coarse_vals, [f"particle_diameter,{hopper_d * LAM * 1e3:g},mm,"])}
    out = {"date": time.strftime("%Y-%m-%d"), "truth": row0["truth"], "stores": list(DEFAULT_STORES), "sets": {}}
    for name, (obs, values, material_rows) in variants.items():
        keep = sorted(values)
        noisy = synthetic.with_lab_noise([obs[i] for i in keep], {k: values[i] for k, i in enumerate(keep)}, setup.nets,
                                         np.random.default_rng(a.seed))
        path = Path(a.out).resolve().with_name(f"material_sets_{name.split()[0].strip(chr(39))}.csv")
        synthetic.to_csv(path, "m", noisy, truth, f"studies/material_sets.py: {name}", material_rows)
        rows = load_measurements(path, "m")
        scaling = setup.scaling(MaterialProperties.from_rows(rows))
        s2 = setup.for_material(scaling)
        obs2, skipped = observations_of(rows, s2, str(path), "m", scaling)
        d = diagnose(name, obs2, s2.nets, s2.ranges, s2.candidates, say=lambda *x: None)
        before = d.summary_of(d.base, d.base_model)
        out["sets"][name] = {"file": str(path.relative_to(ROOT)), "rows": len(obs2), "left_out": skipped,
                             "verdict": d.verdict, "effect": d.effect, "chi2_per_dof": before["chi2_per_dof"],
                             "estimate": d.base.as_dict(), "notes": scaling.notes(s2.ranges),
                             "run_seconds": runs.get(name.split()[0], {}).get("seconds")}
        print(f"{name}: {len(obs2)} rows, {len(skipped)} left out, base chi2/dof {before['chi2_per_dof']:.2f}, "
              f"{d.verdict} {d.effect or ''}, estimate " + ", ".join(f"{k} {v:.3f}" for k, v in d.base.as_dict().items()),
              flush=True)
    Path(a.out).write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
