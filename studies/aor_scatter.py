"""Run-to-run scatter of the angle-of-repose rig: the same parameters (friction 0.5, rolling
friction 0.3), different seeds. The scatter bounds the hold-out R^2 any surrogate can reach:
R^2 <= 1 - sd_noise^2 / sd_campaign^2.

    .venv/bin/python studies/aor_scatter.py tiny 6       # preset, number of seeds
"""
import sys

import numpy as np

from pydem.rigs import AngleOfRepose, AorConfig, load

preset, n = sys.argv[1], int(sys.argv[2])
cfg = load(AorConfig, preset, overrides=["num_threads=1", "friction=0.5", "rolling_friction=0.3"])
a, d = [], []
for seed in range(n):
    r = AngleOfRepose(cfg).run(seed=seed)
    a.append(r.metrics["angle_of_repose"].value)
    d.append(r.metrics["bulk_density"].value)
    print(seed, a[-1], r.metrics["angle_of_repose"].uncertainty, d[-1], flush=True)
print(preset, "angle mean %.2f sd %.2f; density mean %.1f sd %.1f" % (np.mean(a), np.std(a, ddof=1), np.mean(d),
                                                                      np.std(d, ddof=1)))
