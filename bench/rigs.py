"""Wall time of each rig's default preset on this machine (issue 4), plus the largest
seed-001 Table 1 hopper case (A-4, 14,700 spheres). Appends to bench/results/rigs.csv.

    .venv/bin/python bench/rigs.py                 # the three defaults
    .venv/bin/python bench/rigs.py --largest       # also hopper case A-4, first 0.5 s of discharge
    .venv/bin/python bench/rigs.py --threads 1     # as a campaign runs each sample

Each row also carries the engine's profile: the share of the time spent in neighbour-list
builds and the steps per build.
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


def run(rig: str, preset: str, overrides=(), threads: int = 2):
    cls, cfg_cls = RIGS[rig]
    cfg = load(cfg_cls, preset, overrides=[f"num_threads={threads}", *overrides])
    t0 = time.perf_counter()
    res = cls(cfg).run(seed=1)
    wall = time.perf_counter() - t0
    prof = res.info["engine_profile"]
    row = {"rig": rig, "preset": preset, "overrides": " ".join(overrides), "particles": res.info["particles"],
           "steps": res.info["steps"], "simulated_s": round(res.info["simulated_time"], 4),
           "wall_s": round(wall, 1), "emptied": res.info.get("emptied", ""), "particle_steps_per_s_M": round(res.info["particles"] * res.info["steps"] / wall / 1e6, 3),
           "threads": cfg.num_threads, "cpu": platform.processor() or platform.machine(), "cores": os.cpu_count(),
           "neighbor_share": round(prof["neighbor_s"] / max(prof["neighbor_s"] + prof["contact_s"] + prof["integrate_s"], 1e-12), 3),
           "steps_per_build": round(prof["steps"] / max(prof["neighbor_builds"], 1), 1),
           "date": time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
           "headline": "; ".join(f"{k} {m}" for k, m in list(res.metrics.items())[:3])}
    rows = list(csv.DictReader(open(OUT, newline=""))) if OUT.exists() else []
    fields = list(rows[0]) if rows else []
    fields += [k for k in row if k not in fields]  # rows from before a column existed leave it blank
    with open(OUT, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        w.writerows(rows + [row])
    print(row, flush=True)


if __name__ == "__main__":
    threads = int(sys.argv[sys.argv.index("--threads") + 1]) if "--threads" in sys.argv else 2
    for rig in ("ring-shear", "aor", "hopper"):
        run(rig, "default", threads=threads)
    if "--largest" in sys.argv:  # fill + the first 0.5 s of discharge: the rate per simulated second
        run("hopper", "default", ["case=A-4", "max_time=0.5"], threads=threads)
