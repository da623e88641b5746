"""Seed 000's own materials (JKU Linz angles of repose, data/measurements/jku_angle_of_repose.csv)
calibrated on an angle-of-repose store (default: data/campaigns/aor_jku.h5, the non-cohesive
three-parameter campaign at the slow-lift default preset): for each of the eight materials the
base model's posterior (friction, rolling friction, restitution), the angle the surrogate gives
at the estimate, whether the estimate sits on a range edge, and seed 000's ±5 % window. One
measured angle per material cannot pin three parameters: the posterior is a ridge, and the
table says how narrow each parameter still gets.

    .venv/bin/python bench/jku_calibration.py [--stores S ...]  # -> bench/results/jku_calibration.{json,md}
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pydem.calibration.calibrate import calibrate  # noqa: E402
from pydem.calibration.setup import load_setup, observations_from_file  # noqa: E402
from pydem.measurements import load as load_measurements  # noqa: E402

MEAS = ROOT / "data/measurements/jku_angle_of_repose.csv"
JKU_STORES = ("data/campaigns/aor_jku.h5",)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--stores", nargs="+", default=list(JKU_STORES), help="campaign stores (default: %(default)s)")
    stores = ap.parse_args().stores
    setup = load_setup([ROOT / s for s in stores], say=lambda *_: None)
    fits = {q.key: (n.r2, n.rmse) for q, n in setup.nets.items()}
    materials = sorted({m.material for m in load_measurements(MEAS, None)})
    rows = []
    for name in materials:
        obs, _ = observations_from_file(MEAS, name, setup)
        c = calibrate(name, obs, setup.nets, setup.ranges, setup.candidates, samples=2 ** 18, threads=1,
                      say=lambda *_: None)
        post = c.fit.posterior["parameters"]
        model = float(c.model.predict(c.fit.best)[0])
        rows.append({"material": name, "measured": obs[0].value, "model_at_estimate": model,
                     "chi2": c.fit.chi2, "admissible_5pc": c.screening["admissible"],
                     "screened": c.screening["samples"],
                     "parameters": {k: {x: p[x] for x in ("estimate", "mean", "lo", "hi", "at_edge")} for k, p in post.items()}})
        print(f"{name:18s} {obs[0].value:6.2f} deg  model {model:6.2f}  admissible {c.screening['admissible']:7d}  "
              + "  ".join(f"{k} {p['mean']:.3f} [{p['lo']:.3f}, {p['hi']:.3f}]{'*' if p['at_edge'] else ''}"
                          for k, p in post.items()), flush=True)
    out = ROOT / "bench/results/jku_calibration.json"
    out.write_text(json.dumps({"stores": list(stores), "surrogates": fits, "materials": rows}, indent=1))
    lines = [f"Stores: {', '.join(stores)}; surrogates (hold-out R², RMSE): "
             + "; ".join(f"{k} {r2:.2f}, {rmse:.3g}" for k, (r2, rmse) in fits.items()), "",
             "| material | measured | surrogate at estimate | ±5 % admissible of 2^18 | friction mean [95 %] | "
             "rolling friction mean [95 %] | restitution mean [95 %] |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        p = r["parameters"]
        cell = lambda k: f"{p[k]['mean']:.2f} [{p[k]['lo']:.2f}, {p[k]['hi']:.2f}]" + (" (edge)" if p[k]["at_edge"] else "")  # noqa: E731
        lines.append(f"| {r['material']} | {r['measured']:.2f}° | {r['model_at_estimate']:.2f}° | {r['admissible_5pc']:,} | "
                     f"{cell('friction')} | {cell('rolling_friction')} | {cell('restitution')} |")
    out.with_suffix(".md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
