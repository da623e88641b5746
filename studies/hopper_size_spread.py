"""Does the hopper see a size spread? The `default` hopper at the campaign box's centre
(friction 0.5, rolling friction 0.3, restitution 0.55), its two species exact (size_spread 0)
and each widened to d (1 +- 0.5), three seeds each; max_overlap_ratio 0.6 as the size-spread
campaign sets it (at 0.5 a coarse sphere landing on a fine one while filling passes 0.3).

    .venv/bin/python studies/hopper_size_spread.py > studies/results/hopper_size_spread.txt
"""
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from pydem.rigs import RIGS  # noqa: E402

cls, cfg_cls = RIGS["hopper"]
for seed in (1, 2, 3):
    for spread in (0.0, 0.5):
        cfg = cfg_cls.preset("default")
        cfg.num_threads, cfg.size_spread, cfg.max_overlap_ratio = 1, spread, 0.6
        t0 = time.perf_counter()
        m = cls(cfg).run({"friction": 0.5, "rolling_friction": 0.3, "restitution": 0.55}, seed=seed).metrics
        print(f"seed {seed} size_spread {spread}: {time.perf_counter() - t0:.0f} s  " +
              "  ".join(f"{k} {m[k]}" for k in ("mass_flow_rate", "discharge_time", "bulk_density")), flush=True)
