"""Seed 000's own materials (JKU Linz angles of repose, data/measurements/jku_angle_of_repose.csv)
calibrated on an angle-of-repose store (default: data/campaigns/aor_jku.h5, the non-cohesive
three-parameter campaign at the slow-lift default preset): for each of the eight materials the
base model's posterior (friction, rolling friction, restitution), the angle the surrogate gives
at the estimate, whether the estimate sits on a range edge, and seed 000's ±5 % window. One
measured angle per material cannot pin three parameters: the posterior is a ridge, and the
table says how narrow each parameter still gets. Beside each estimate: what the default ring
shear surrogates predict for it (pre-shear 2 kPa, shear point 60 %, the candidate effects at
neutral), flagged where the estimate lies outside the ring-shear store's box.

    .venv/bin/python studies/jku_calibration.py [--stores S ...]  # -> studies/results/jku_calibration.{json,md}
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pydem.calibration.calibrate import calibrate  # noqa: E402
from pydem.calibration.fit import Model  # noqa: E402
from pydem.calibration.quantities import Observation  # noqa: E402
from pydem.calibration.setup import load_setup, observations_from_file  # noqa: E402
from pydem.measurements import load as load_measurements  # noqa: E402

MEAS = ROOT / "data/measurements/jku_angle_of_repose.csv"
JKU_STORES = ("data/campaigns/aor_jku_wide.h5", "data/campaigns/aor_jku.h5")
RING_SHEAR = "data/campaigns/diag_ring_shear_default.h5"
RING_SHEAR_AT = {"preshear_stress": 2000.0, "shear_fraction": 0.6}


def ring_shear_prediction(rs, theta: dict) -> dict:
    """The ring-shear surrogates at the base parameters theta, candidates at neutral (fit.Model's
    own input assembly, as a prediction-only model)."""
    obs = [Observation(q, {n: RING_SHEAR_AT[n] for n in net.input_names if n in RING_SHEAR_AT}, float("nan"), 0.0,
                       q.key) for q, net in rs.nets.items()]
    model = Model(obs, rs.nets, rs.ranges, rs.candidates)
    values = model.predict(np.array([theta[n] for n in model.free]))
    out = {o.quantity.metric: float(v) for o, v in zip(obs, values)}
    out["outside_box"] = [n for n, (lo, hi) in rs.ranges.items() if n in theta and not lo <= theta[n] <= hi]
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--stores", nargs="+", default=list(JKU_STORES), help="campaign stores (default: %(default)s)")
    stores = ap.parse_args().stores
    setup = load_setup([ROOT / s for s in stores], say=lambda *_: None)
    fits = {q.key: (n.r2, n.rmse) for q, n in setup.nets.items()}
    rs = load_setup([ROOT / RING_SHEAR], say=lambda *_: None)
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
                     "ring_shear_at_estimate": ring_shear_prediction(rs, c.fit.as_dict()),
                     "parameters": {k: {x: p[x] for x in ("estimate", "mean", "lo", "hi", "at_edge")} for k, p in post.items()}})
        print(f"{name:18s} {obs[0].value:6.2f} deg  model {model:6.2f}  admissible {c.screening['admissible']:7d}  "
              + "  ".join(f"{k} {p['mean']:.3f} [{p['lo']:.3f}, {p['hi']:.3f}]{'*' if p['at_edge'] else ''}"
                          for k, p in post.items()), flush=True)
    out = ROOT / "studies/results/jku_calibration.json"
    out.write_text(json.dumps({"stores": list(stores), "surrogates": fits, "materials": rows}, indent=1))
    lines = [f"Stores: {', '.join(stores)}; surrogates (hold-out R², RMSE): "
             + "; ".join(f"{k} {r2:.2f}, {rmse:.3g}" for k, (r2, rmse) in fits.items()), "",
             "| material | measured | surrogate at estimate | ±5 % admissible of 2^18 | friction mean [95 %] | "
             "rolling friction mean [95 %] | restitution mean [95 %] | ring shear at the estimate: μ_ie-ps, μ_ie-s (60 %), ρ_b |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        p = r["parameters"]
        cell = lambda k: f"{p[k]['mean']:.2f} [{p[k]['lo']:.2f}, {p[k]['hi']:.2f}]" + (" (edge)" if p[k]["at_edge"] else "")  # noqa: E731
        rsp = r["ring_shear_at_estimate"]
        rs_cell = (f"{rsp['mu_ie_ps']:.2f}, {rsp['mu_ie_s']:.2f}, {rsp['bulk_density']:.0f} kg/m³"
                   + (f" (extrapolated: {', '.join(rsp['outside_box'])} outside the box)" if rsp["outside_box"] else ""))
        lines.append(f"| {r['material']} | {r['measured']:.2f}° | {r['model_at_estimate']:.2f}° | {r['admissible_5pc']:,} | "
                     f"{cell('friction')} | {cell('rolling_friction')} | {cell('restitution')} | {rs_cell} |")
    out.with_suffix(".md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
