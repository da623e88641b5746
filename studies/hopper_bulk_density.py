"""The hopper's two bulk-density measures (`density_boxes`) on the same settled beds: boxes ending
two diameters below the *highest* sphere (`below_highest`, the tiny preset's) and below the free
surface's *lowest* point (`below_surface`, the default preset's and its diagnosis stores' since
2026-11-27). Why: a frictional fill leaves a sloped surface (0.146 m at one wall, 0.182 m at the
other in a DEM null set), so the first's top box is part empty and one run reads 280 kg/m^3 low
(docs/diagnosis.md §5, "One outlying row"). Runs the replicate store's points and seeds, each run measured both ways (the
stored value, in the store's own measure, printed beside: the run reproduces it); prints each
run's two values and the pooled seed-to-seed sd of each measure.

    .venv/bin/python studies/hopper_bulk_density.py [--runs N] [--workers 2] > studies/results/hopper_bulk_density.txt
"""
import argparse
import math
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
REPLICATES = ROOT / "data/campaigns/diag_hopper_default_replicates.h5"


def one_run(args):
    point, seed, params = args
    from pydem.campaign import Campaign
    from pydem.rigs import RIGS
    store = Campaign.open(REPLICATES).store
    cfg = store.spec.config(dict(zip(store.spec.names, params)))
    cfg.num_threads = 1
    cfg.density_boxes = "below_highest"  # the run's own metric: the other measure is taken beside it
    cls = RIGS["hopper"][0]
    rig = cls(cfg)
    seen = {}
    measured = cls._bulk_density

    def both(self, d, p, h_wedge):  # the rig's two measures on the same settled bed
        self.config.density_boxes = "below_surface"
        seen["surface"] = measured(self, d, p, h_wedge)[0]
        self.config.density_boxes = "below_highest"
        out = measured(self, d, p, h_wedge)
        seen["highest"], seen["highest_block_sd"] = out
        return out

    rig._bulk_density = both.__get__(rig, cls)
    rig.run(seed=int(seed))
    return point, int(seed), seen["highest"], seen["highest_block_sd"], seen["surface"]


def pooled_sd(rows, j):
    ss, dof = 0.0, 0
    for p in sorted({r[0] for r in rows}):
        v = np.array([r[j] for r in rows if r[0] == p])
        v = v[np.isfinite(v)]
        if len(v) > 1:
            ss, dof = ss + v.var(ddof=1) * (len(v) - 1), dof + len(v) - 1
    return math.sqrt(ss / dof) if dof else math.nan


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=32, help="the replicate store's first N runs")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    from pydem.campaign import Campaign
    st = Campaign.open(REPLICATES).store
    n = min(args.runs, len(st.points))
    jobs = [(int(st.points[i]), int(st.seeds[i]), st.params[i].tolist()) for i in range(n)]
    stored = st.values[:n, st.metric_names.index("bulk_density")]
    with ProcessPoolExecutor(args.workers) as ex:
        rows = list(ex.map(one_run, jobs))
    print(f"{len(rows)} hopper runs of {REPLICATES.name} (default preset), bulk density in kg/m^3:")
    print(f"point       seed   stored ({st.spec.config({}).density_boxes})   below the highest sphere (block sd)   "
          "below the surface")
    for r, v in zip(rows, stored):
        print(f"{r[0]:5d} {r[1]:10d}  {v:9.1f}  {r[2]:9.1f} ({r[3]:6.1f})   {r[4]:9.1f}")
    print(f"pooled seed-to-seed sd: below the highest sphere {pooled_sd(rows, 2):.1f}, below the surface "
          f"{pooled_sd(rows, 4):.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
