"""Cost of one Python call of Domain.step: a 200-sphere bed stepped 2,000 times in one call,
then in 2,000 calls of one step. Prints the overhead per call (Python + cffi + the separate
opening kick of a call's first step). Rigs step in chunks of >= 2 ms of simulated time
(>= ~100 steps per call), so this is what a rig pays per ~100 steps.

    .venv/bin/python bench/python_overhead.py >> bench/results/python_overhead.txt
"""
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
import pydem  # noqa: E402

d = pydem.Domain(hi=(0.02, 0.02, 0.02))
m = d.add_material()
d.set_pair(m, m)
d.add_plane_wall(material=m)
g = np.stack(np.meshgrid(*[np.arange(0.0015, 0.019, 0.0025)] * 3, indexing="ij"), -1).reshape(-1, 3)[:200]
d.add_particles(g, 1e-3, m)
d.step(100)
best_one, best_many = float("inf"), float("inf")
for _ in range(3):
    t = time.perf_counter()
    d.step(2000)
    best_one = min(best_one, time.perf_counter() - t)
    t = time.perf_counter()
    for _ in range(2000):
        d.step(1)
    best_many = min(best_many, time.perf_counter() - t)
print(f"{time.strftime('%Y-%m-%d %H:%M', time.gmtime())}: 200 spheres, best of 3: one call of 2000 steps "
      f"{best_one * 1e3:.1f} ms, 2000 calls of one step {best_many * 1e3:.1f} ms: "
      f"{(best_many - best_one) / 2000 * 1e6:.1f} us per call, {best_one / 2000 * 1e6:.1f} us per step")
