"""The time of one diagnosis (what `make test`'s statistical tests and `pydem diagnose` repeat):
five seeded surrogate sets with a strong cohesion on the shipped tiny stores, diagnosed without
detection limits, as the tiny-store protocol test does. Prints the seconds and the verdicts (equal
across checkouts that change speed only). Run from a checkout; compare two with a paired timer:

    .venv/bin/python bench/diagnosis_speed.py             # from the checkout to time
    # A/B: the same command in OLD and NEW checkouts, alternated, medians and paired ratios
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path.cwd()
sys.path.insert(0, str(ROOT))

from pydem.calibration import diagnose as dg  # noqa: E402
from pydem.calibration import synthetic  # noqa: E402
from pydem.calibration.setup import TINY_STORES, load_setup  # noqa: E402


def main() -> int:
    setup = load_setup([ROOT / s for s in TINY_STORES], say=lambda *a: None)
    sets = []
    for seed in range(12, 17):
        rng = np.random.default_rng(seed)
        truth = synthetic.draw_truth(rng, setup.ranges, setup.candidates, "cohesion_sjkr", min_fraction=0.8)
        sets.append(synthetic.surrogate_set_and_means(setup.nets, setup.candidates, truth, rng,
                                                      synthetic.programme(setup.nets))[0])
    t0 = time.perf_counter()
    verdicts = [dg.diagnose("bench", obs, setup.nets, setup.ranges, setup.candidates, say=lambda *a: None,
                            detection_limits=False).effect for obs in sets]
    print(f"{time.perf_counter() - t0:.2f} s for {len(sets)} diagnoses; effects {verdicts}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
