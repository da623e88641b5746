"""Is a ring-shear cell design a friction meter? One long pre-shear (no shear points) per run,
at mu_s 0.2 and 0.8 (mu_r 0.1, e 0.5), a few seeds, two processes; then mu_ie-ps = mean tau /
mean sigma over windows of the shear displacement, with the seed-to-seed scatter per window.
A usable design: the mean rises with mu_s, and the scatter falls with the window length.

    .venv/bin/python studies/ring_shear_window.py PRESET "key=value,..." [seeds] [displacement_m]
"""
import sys
from multiprocessing import Pool

import numpy as np

from pydem.rigs import RingShear, RingShearConfig, load

FRICTIONS = (0.2, 0.8)


def one(job):
    preset, extra, seed, mu, length = job
    cfg = load(RingShearConfig, preset, overrides=["num_threads=1", f"friction={mu}", "rolling_friction=0.1",
                                                   "restitution=0.5", "shear_points=[]",
                                                   f"first_preshear_displacement={length}", f"max_preshear={length}",
                                                   "steady_tolerance=1e-4"] + extra)
    r = RingShear(cfg).run(seed=seed)
    s = r.series
    pre = np.array([str(p) for p in s["phase"]]) == "preshear"
    t = s["time"][pre]
    return mu, seed, (t - t[0]) * cfg.shear_speed, s["tau"][pre], s["sigma"][pre], r.info["wall_seconds"], \
        r.metrics["bulk_density"].value, cfg.diameter


def main():
    preset = sys.argv[1]
    extra = [e for e in sys.argv[2].split(",") if e] if len(sys.argv) > 2 else []
    seeds = int(sys.argv[3]) if len(sys.argv) > 3 else 2
    length = float(sys.argv[4]) if len(sys.argv) > 4 else 0.03
    with Pool(2) as pool:
        out = pool.map(one, [(preset, extra, s, mu, length) for mu in FRICTIONS for s in range(seeds)])
    d = out[0][7]
    print(f"# preset {preset} {extra}: {seeds} seeds, pre-shear {1e3 * length:.0f} mm ({length / d:.1f} d)")
    for mu in FRICTIONS:
        rows = [o for o in out if o[0] == mu]
        print(f"mu_s {mu}: wall {[round(o[5]) for o in rows]} s, bulk density {[round(o[6]) for o in rows]} kg/m^3")
        for a, b in [(0.0, 0.25), (0.25, 0.5), (0.25, 0.75), (0.25, 1.0), (0.5, 1.0)]:
            est = []
            for _, _, x, tau, sig, *_ in rows:
                sel = (x >= a * length) & (x < b * length + 1e-12)
                est.append(tau[sel].mean() / sig[sel].mean())
            print(f"  window {1e3 * a * length:5.1f}-{1e3 * b * length:5.1f} mm: mean {np.mean(est):.4f} "
                  f"sd {np.std(est, ddof=1):.4f}  {np.round(est, 3).tolist()}", flush=True)


if __name__ == "__main__":
    main()
