"""Evidence for the density similarity of calibration/similarity.py: each rig at its tiny preset,
run at the stores' particle density and Young's modulus (2500 kg/m^3, 5 MPa), at 4000 kg/m^3
with the modulus scaled with it (8 MPa: the same stiffness number, exact similarity), and at
4000 kg/m^3 with the modulus kept (5 MPa: the stiffness number 1.6x the stores'); same seeds.
Density-like metrics are divided by 1.6 (solid fraction terms) and the ring shear's pre-shear
stress is scaled with the density (similarity), so every column should match the first within
seed scatter where the similarity holds.

    .venv/bin/python studies/similarity.py --out studies/results/similarity_tiny.json
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pydem.quantity_table import metric_spec  # noqa: E402
from pydem.rigs import RIGS, load  # noqa: E402

CASES = {"stores (2500 kg/m^3, 5 MPa)": (2500.0, 5e6), "similar (4000, 8 MPa)": (4000.0, 8e6),
         "density only (4000, 5 MPa)": (4000.0, 5e6)}
METRICS = {"aor": ("angle_of_repose", "bulk_density"), "hopper": ("mass_flow_rate", "discharge_time", "bulk_density"),
           "ring-shear": ("mu_ie_ps", "bulk_density")}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    args = ap.parse_args()
    out = {"date": time.strftime("%Y-%m-%d"), "machine": "x86_64, 2 cores", "rows": []}
    for rig, metrics in METRICS.items():
        cls, cfg_cls = RIGS[rig]
        for case, (rho, E) in CASES.items():
            k = rho / 2500.0
            over = [f"density={rho}", f"youngs_modulus={E}"]
            if rig == "ring-shear":
                base = load(cfg_cls, "tiny", None, [])
                over.append(f"preshear_stress={base.preshear_stress * k}")
            for seed in args.seeds:
                t0 = time.perf_counter()
                r = cls(load(cfg_cls, "tiny", None, over)).run(seed=seed)
                row = {"rig": rig, "case": case, "seed": seed, "seconds": time.perf_counter() - t0}
                for m in metrics:
                    v = r.metrics[m].value if m in r.metrics else None
                    row[m] = None if v is None else v / (k if metric_spec(m).scales_with_density else 1.0)
                out["rows"].append(row)
                print(json.dumps(row), flush=True)
    Path(args.out).write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
