"""Ring-shear surrogate variants against the shipped form, by the same 5-fold cross-validation
(one run's rows in one fold, seed 0) the nets are sized with (nn.mlp.cross_validate):

- inputs: the pre-shear stress linear (shipped) / as its log (the design samples it log-uniformly)
  / log plus cohesion over pre-shear stress (the ratio of cohesive to applied stress that
  cohesion's effect on the friction coefficients scales with);
- the bag: 4 members of 10 units (shipped for the mu nets) / 8 of 10 / 8 of 16 / 16 of 10.

    .venv/bin/python studies/surrogate_variants.py [--stores ...]

Writes studies/results/surrogate_variants.txt. ~3 min on one core."""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import torch

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from nn.mlp import cross_validate  # noqa: E402
from pydem.calibration.setup import DEFAULT_STORES, open_store_groups  # noqa: E402
from pydem.calibration.store_data import training_tables  # noqa: E402

COHESION = "effects.cohesion_sjkr.cohesion_energy_density"


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--stores", nargs="+", default=[str(ROOT / s) for s in DEFAULT_STORES])
    args = ap.parse_args()
    torch.set_num_threads(1)
    main_store, pooled, _ = open_store_groups(args.stores)["ring-shear"]
    lines = [f"# {time.strftime('%Y-%m-%d')}, {main_store.path.name} ({(main_store.status == 1).sum()} runs) + "
             + ", ".join(f"{o.path.name} ({(o.status == 1).sum()})" for o in pooled) + "; 5-fold CV R^2 / RMSE"]
    for q, (names, x, y) in training_tables(main_store, pooled).items():
        _, groups = np.unique(x[:, :len(main_store.spec.names)], axis=0, return_inverse=True)
        j, c = names.index("preshear_stress"), names.index(COHESION)
        xl = x.copy()
        xl[:, j] = np.log(x[:, j])
        log_target = q.metric != "bulk_density"
        variants = [("sigma linear, 4 x 10", x, 4, 10), ("log sigma, 4 x 10", xl, 4, 10),
                    ("log sigma + cohesion/sigma, 4 x 10", np.column_stack([xl, x[:, c] / x[:, j]]), 4, 10),
                    ("sigma linear, 8 x 10", x, 8, 10), ("sigma linear, 8 x 16", x, 8, 16),
                    ("sigma linear, 16 x 10", x, 16, 10)]
        for label, xx, bag, hidden in variants:
            t0 = time.perf_counter()
            cv = cross_validate(xx, y, groups, hidden, bag, folds=5, seed=0, log_target=log_target)
            lines.append(f"{q.key:24s} {label:36s} R^2 {cv['r2']:.4f}  RMSE {cv['rmse']:.5g}  ({time.perf_counter() - t0:.0f} s)")
            print(lines[-1], flush=True)
    out = ROOT / "studies/results/surrogate_variants.txt"
    out.write_text("\n".join(lines) + "\n")
    print(f"-> {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
