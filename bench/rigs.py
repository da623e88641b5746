"""Wall time of each rig's default preset on this machine (issue 4), plus the largest
seed-001 Table 1 hopper case (A-4, 14,700 spheres). Appends to bench/results/rigs.csv.

    .venv/bin/python bench/rigs.py                 # the three defaults
    .venv/bin/python bench/rigs.py --largest       # also hopper case A-4, first 0.5 s of discharge
"""
import csv
import os
import platform
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
from pydem.rigs import RIGS, load  # noqa: E402

OUT = ROOT / "bench" / "results" / "rigs.csv"


def run(rig: str, preset: str, overrides=()):
    cls, cfg_cls = RIGS[rig]
    cfg = load(cfg_cls, preset, overrides=list(overrides))
    t0 = time.perf_counter()
    res = cls(cfg).run(seed=1)
    wall = time.perf_counter() - t0
    row = {"rig": rig, "preset": preset, "overrides": " ".join(overrides), "particles": res.info["particles"],
           "steps": res.info["steps"], "simulated_s": round(res.info["simulated_time"], 4),
           "wall_s": round(wall, 1), "emptied": res.info.get("emptied", ""), "particle_steps_per_s_M": round(res.info["particles"] * res.info["steps"] / wall / 1e6, 3),
           "threads": cfg.num_threads, "cpu": platform.processor() or platform.machine(), "cores": os.cpu_count(),
           "date": time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
           "headline": "; ".join(f"{k} {m}" for k, m in list(res.metrics.items())[:3])}
    new = not OUT.exists()
    with open(OUT, "a", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(row))
        if new:
            w.writeheader()
        w.writerow(row)
    print(row, flush=True)


if __name__ == "__main__":
    for rig in ("ring-shear", "aor", "hopper"):
        run(rig, "default")
    if "--largest" in sys.argv:  # fill + the first 0.5 s of discharge: the rate per simulated second
        run("hopper", "default", ["case=A-4", "max_time=0.5"])
