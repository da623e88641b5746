"""Validation of the diagnosis loop on hidden-effect data (docs/diagnosis.md, "Proof"):
top-1 accuracy per candidate effect, false alarms on null sets, the error after adding the chosen
effect as a fraction of before, and what an effect that is not a candidate (a solid-density
mismatch) gets called.

    .venv/bin/python studies/diagnosis_validation.py --source surrogate --sets 40 --null 200
    .venv/bin/python studies/diagnosis_validation.py --source dem --sets 3 --null 3

Writes studies/results/diagnosis_validation_<preset>_<source>.json (every set and the scores)."""
from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pydem.calibration import synthetic  # noqa: E402
from pydem.calibration.setup import load_setup, shipped_stores  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--preset", default="tiny", help="which diagnosis stores: setup.shipped_stores(preset)")
    ap.add_argument("--source", choices=("surrogate", "dem"), default="surrogate")
    ap.add_argument("--sets", type=int, default=40, help="sets per candidate effect")
    ap.add_argument("--null", type=int, default=200, help="null sets (no hidden effect)")
    ap.add_argument("--unexplained", type=int, default=20, help="sets with a non-candidate discrepancy")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--stores", nargs="+", help="store paths instead of diag_<rig>_<preset>.h5 (a mix of presets)")
    ap.add_argument("--label", help="results name (default: the preset)")
    ap.add_argument("--exact-nets", action="store_true",
                    help="surrogate sets without the nets' own error (the nets taken as the rigs' exact mean; before 2026-11-25)")
    args = ap.parse_args()
    stores = [ROOT / s for s in (args.stores or shipped_stores(args.preset))]
    args.preset = args.label or args.preset
    setup = load_setup([s for s in stores if s.exists()])
    kinds = {"null": args.null, **{c.name: args.sets for c in setup.candidates}, "unexplained": args.unexplained}
    t0 = time.perf_counter()
    journal = ROOT / f"studies/results/diagnosis_validation_{args.preset}_{args.source}.jsonl"  # resumable
    rows = synthetic.validate(setup, kinds, seed=args.seed, source=args.source, threads=args.threads, journal=journal,
                              net_error=not args.exact_nets)
    scores = synthetic.score_sets(rows)
    out = ROOT / f"studies/results/diagnosis_validation_{args.preset}_{args.source}.json"
    out.parent.mkdir(exist_ok=True)
    meta = {"date": time.strftime("%Y-%m-%d"), "machine": f"{platform.machine()}, {len(__import__('os').sched_getaffinity(0))} cores",
            "seconds": time.perf_counter() - t0, "stores": [str(s.relative_to(ROOT)) if s.is_relative_to(ROOT) else str(s) for s in stores if s.exists()],
            "nets": {q.key: {"r2": n.r2, "rmse": n.rmse, "scatter": n.scatter, "runs": n.runs} for q, n in setup.nets.items()},
            "command": " ".join(sys.argv)}
    out.write_text(json.dumps({"meta": meta, "scores": scores, "sets": rows}, indent=1, default=float))
    print(json.dumps(scores, indent=1))
    print(f"{len(rows)} sets in {meta['seconds']:.0f} s -> {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
