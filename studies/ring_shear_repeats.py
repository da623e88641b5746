"""How noisy is one shear to failure, and do repeats in one run average it like seeds do?
Runs the ring-shear `cell` preset at one parameter set with K repeats of (pre-shear + shear to
failure at 50 % of sigma_pre) for a few seeds, two processes, and prints per seed the K peak
ratios, their mean and standard error, mu_ie-ps and the wall time. Repeats are as good as
seeds when the seed means agree within their standard errors.

    .venv/bin/python studies/ring_shear_repeats.py [friction] [rolling_friction] [repeats] [preshear_m] [seeds]
"""
import sys
from multiprocessing import Pool

import numpy as np

from pydem.rigs import RingShear, RingShearConfig, load


def one(job):
    mu, mur, repeats, pre, seed = job
    cfg = load(RingShearConfig, "cell", overrides=["num_threads=1", f"friction={mu}", f"rolling_friction={mur}",
                                                   "restitution=0.55", "shear_points=[0.5]",
                                                   f"shear_repeats={repeats}", f"preshear_displacement={pre}"])
    r = RingShear(cfg).run(seed=seed)
    peaks = [q["tau_peak"] / q["sigma"] for q in r.info["shear_points"]]
    return seed, peaks, r.metrics["mu_ie_ps"], r.info["wall_seconds"]


def main():
    mu, mur = (float(a) for a in (sys.argv[1:3] if len(sys.argv) > 2 else (0.5, 0.3)))
    repeats = int(sys.argv[3]) if len(sys.argv) > 3 else 8
    pre = float(sys.argv[4]) if len(sys.argv) > 4 else 3e-3
    seeds = int(sys.argv[5]) if len(sys.argv) > 5 else 2
    print(f"# cell preset, mu_s {mu}, mu_r {mur}, e 0.55: {repeats} repeats after {1e3 * pre:.1f} mm pre-shears")
    with Pool(2) as pool:
        for seed, peaks, ps, wall in pool.map(one, [(mu, mur, repeats, pre, s) for s in range(seeds)]):
            p = np.array(peaks)
            print(f"seed {seed}: peaks {np.round(p, 3).tolist()} -> mean {p.mean():.4f} sd {p.std(ddof=1):.4f} "
                  f"se {p.std(ddof=1) / np.sqrt(p.size):.4f}; mu_ie-ps {ps.value:.4f} ± {ps.uncertainty:.4f}; {wall:.0f} s")


if __name__ == "__main__":
    main()
