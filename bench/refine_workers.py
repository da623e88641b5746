"""What workers buy a refinement: the same refinement runs (tiny presets: 4 hoppers, 4 heaps,
2 ring shears at one material point) run by refine.run_plan on 1 and 2 local worker processes and
on a Dask LocalCluster of 1 and 2 workers (one thread each). Prints each wall time, the runs'
summed CPU time and the speed-up over one worker; results into bench/results/refine_workers.txt.
Run on a quiet machine (the wall times are the claim):

    .venv/bin/python bench/refine_workers.py
"""
from __future__ import annotations

import os
import platform
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pydem.calibration.refine import run_plan  # noqa: E402
from pydem.calibration.setup import TINY_STORES, open_stores  # noqa: E402

POINT = {"friction": 0.5, "rolling_friction": 0.2, "restitution": 0.5, "wall_friction": 0.5, "size_spread": 0.1,
         "effects.cohesion_sjkr.cohesion_energy_density": 0.0}


def runs() -> list[dict]:
    one = lambda rig, cond, fr=(): {"rig": rig, "point": POINT, "conditions": cond, "fractions": list(fr),  # noqa: E731
                                    "why": "bench", "gain": 1.0}
    return ([one("hopper", {"slot_width": b}) for b in (0.028, 0.032, 0.036, 0.04)]
            + [one("aor", {}) for _ in range(4)]
            + [one("ring-shear", {"preshear_stress": p}, (0.5,)) for p in (1000.0, 3000.0)])


def timed(label: str, stores, plan, **kw) -> tuple[float, float]:
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        entries = run_plan(plan, stores, Path(tmp), say=lambda *a: None, **kw)
        wall = time.perf_counter() - t0
    assert all("metrics" in e for e in entries), [e.get("error") for e in entries]
    return wall, sum(e["cpu"] for e in entries)


def main() -> int:
    import distributed
    stores = open_stores([ROOT / s for s in TINY_STORES])
    plan = runs()
    lines = [f"# refine_workers ({time.strftime('%Y-%m-%d')}, {platform.machine()}, {os.cpu_count()} cores): "
             f"{len(plan)} tiny refinement runs"]
    base = None
    for label, kw in (("local, 1 worker", {"workers": 1}), ("local, 2 workers", {"workers": 2})):
        wall, cpu = timed(label, stores, plan, **kw)
        base = base or wall
        lines.append(f"{label:22s} wall {wall:6.1f} s  runs' CPU {cpu:6.1f} s  speed-up {base / wall:.2f}")
        print(lines[-1], flush=True)
    for n in (1, 2):
        with distributed.LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None) as c:
            wall, cpu = timed(f"dask {n}", stores, plan, workers=1, dask=c.scheduler_address)
        lines.append(f"{f'Dask LocalCluster, {n}':22s} wall {wall:6.1f} s  runs' CPU {cpu:6.1f} s  speed-up {base / wall:.2f}")
        print(lines[-1], flush=True)
    out = ROOT / "bench/results/refine_workers.txt"
    out.write_text("\n".join(lines) + "\n")
    print(f"written {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
