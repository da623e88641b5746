"""Friction sensitivity and scatter of a ring-shear cell design: mu_ie-ps at mu_s 0.1 and 0.9
(mu_r 0), two seeds each, tiny preset plus the overrides given (comma-separated key=value).

    .venv/bin/python studies/ring_shear_design.py "particles=2400,bar_height=3e-3"
"""
import sys
import time

from pydem.rigs import RingShear, RingShearConfig, load
extra = sys.argv[1].split(",") if len(sys.argv) > 1 and sys.argv[1] else []
for mu in ("0.1", "0.9"):
    for seed in (1, 2):
        cfg = load(RingShearConfig, "tiny", overrides=["num_threads=1", f"friction={mu}", "rolling_friction=0"] + extra)
        t = time.time()
        try:
            r = RingShear(cfg).run(seed=seed)
            print(extra, "mu_s", mu, "seed", seed, r.metrics["mu_ie_ps"], r.metrics["mu_ie_s_50"], r.metrics["bulk_density"], round(time.time() - t), "s", flush=True)
        except Exception as e:
            print(extra, "mu_s", mu, "seed", seed, "FAIL", str(e)[:100], flush=True)
