"""The table of bench/similarity_default.py's runs: each variant's metrics in the stores' terms
(density-like metrics over the density factor k; the hopper's flow rate over lambda^(3/2), the
Beverloo slot law at the same slot width over size), and its difference from the stores' material
at the same point and seed in units of one run's seed scatter (sqrt(2) sd: two runs; sd pooled
from the default replicate stores, calibration/store_data.seed_scatter). |z| < 2 is "the same
within seed scatter".

    .venv/bin/python bench/similarity_report.py bench/results/similarity_default.jsonl \\
        --out bench/results/similarity_default.md
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from pydem.calibration.quantities import Quantity  # noqa: E402
from pydem.calibration.similarity import BEVERLOO_SLOT_EXPONENT  # noqa: E402
from pydem.calibration.store_data import seed_scatter  # noqa: E402
from pydem.campaign import Campaign  # noqa: E402
from pydem.quantity_table import metric_spec  # noqa: E402
from similarity_default import VARIANTS  # noqa: E402

REPLICATES = ("data/campaigns/diag_ring_shear_default_replicates.h5", "data/campaigns/diag_aor_default_replicates.h5",
              "data/campaigns/diag_hopper_default_replicates.h5")
SHOWN = {"hopper": ("mass_flow_rate", "bulk_density"), "ring-shear": ("mu_ie_ps", "mu_ie_s_60", "bulk_density"),
         "aor": ("angle_of_repose", "bulk_density")}


def in_store_terms(rig: str, metric: str, value: float, variant: str) -> float:
    k, _, lam = VARIANTS[variant]
    if metric_spec(metric if not metric.startswith("mu_ie_s_") else "mu_ie_s").scales_with_density:
        value /= k
    if rig == "hopper" and metric == "mass_flow_rate":
        value /= lam ** BEVERLOO_SLOT_EXPONENT
    return value


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("journal")
    ap.add_argument("--out")
    a = ap.parse_args()
    runs = [json.loads(x) for x in Path(a.journal).read_text().splitlines() if x.strip()]
    sd = seed_scatter([Campaign.open(ROOT / p).store for p in REPLICATES])
    base = {(r["rig"], r["point"], r["seed"]): r for r in runs if r["variant"] == "store" and "metrics" in r}
    lines = ["| rig | point | variant | " + " | ".join(["metric", "value (stores' terms)", "stores'", "z"]) + " | run (s) |",
             "|---|---|---|---|---|---|---|---|"]
    for r in runs:
        if r["variant"] == "store":
            continue
        ref = base.get((r["rig"], r["point"], r["seed"]))
        if "error" in r or ref is None:
            lines.append(f"| {r['rig']} | {r['point']} | {r['variant']} | {r.get('error', 'no reference run')} | | | | |")
            continue
        for m in SHOWN[r["rig"]]:
            if m not in r["metrics"] or m not in ref["metrics"]:
                continue
            v = in_store_terms(r["rig"], m, r["metrics"][m], r["variant"])
            v0 = ref["metrics"][m]
            s = sd.get(Quantity(r["rig"], "mu_ie_s" if m.startswith("mu_ie_s_") else m), math.nan)
            z = (v - v0) / (math.sqrt(2) * s)
            lines.append(f"| {r['rig']} | {r['point']} | {r['variant']} | {m} | {v:.4g} | {v0:.4g} | {z:+.1f} | "
                         f"{r['seconds']:.0f} |")
    # the compact table docs/diagnosis.md shows: z per variant and metric, one value per box point
    cols = [(rig, m) for rig, ms in SHOWN.items() for m in ms]
    zs: dict = {}
    for line in lines[2:]:
        f = [x.strip() for x in line.strip("|").split("|")]
        if len(f) == 8 and f[6]:
            zs.setdefault((f[2], f[0], f[3]), []).append(f"{f[6]}")
    lines += ["", "z per variant (points: free, rough); |z| < 2: within seed scatter", "",
              "| variant | " + " | ".join(f"{rig}: {m}" for rig, m in cols) + " |", "|---" * (len(cols) + 1) + "|"]
    for v in [v for v in VARIANTS if v != "store"]:
        lines.append(f"| {v} | " + " | ".join(", ".join(zs.get((v, rig, m), ["-"])) for rig, m in cols) + " |")
    text = "\n".join(lines) + "\n"
    if a.out:
        Path(a.out).write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
