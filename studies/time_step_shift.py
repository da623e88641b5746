"""What a coarser time step would buy a rig, and what it would cost its metrics (issue 23).

The rigs take dt = min(0.2 t_Rayleigh, t_Hertz(impact speed) / 25) (pydem.rigs.common.stable_dt);
at the `default` presets the second term binds. This runs each rig at the campaign box's
centre on several seeds twice — as shipped, and with `--steps-per-contact` steps per Hertz
contact (14: dt at the Rayleigh bound) — and reports the CPU-time ratio and, per metric, the
mean paired shift (coarse - shipped) with its standard error against one run's seed sd. A
shift many standard errors from zero is a bias every store run would carry.

    .venv/bin/python studies/time_step_shift.py --rig hopper --seeds 8 [--steps-per-contact 14]
        [--out studies/results/time_step_shift_hopper.txt]
"""
from __future__ import annotations

import argparse
import json
import math
import resource
import time

import numpy as np

import pydem.rigs.common as common
from pydem.rigs import RIGS

CENTRE = {"friction": 0.5, "rolling_friction": 0.3, "restitution": 0.55}
SHIPPED = common.stable_dt


def run(rig: str, seed: int, steps_per_contact: int | None) -> tuple[dict, float, float]:
    """(metrics, CPU seconds, dt) of one `default` run, one thread; steps_per_contact None: as shipped."""
    cls, cfg_cls = RIGS[rig]
    module = __import__(cls.__module__, fromlist=["stable_dt"])  # the rig's own name for stable_dt
    if steps_per_contact is not None:
        module.stable_dt = lambda d, impact_speed=0.5, fraction=0.2, steps=25: SHIPPED(d, impact_speed, fraction,
                                                                                       steps_per_contact)
    cfg = cfg_cls.preset("default")
    cfg.num_threads = 1
    c0 = resource.getrusage(resource.RUSAGE_SELF).ru_utime
    try:
        res = cls(cfg).run(params=CENTRE, seed=seed)
    finally:
        module.stable_dt = SHIPPED
    cpu = resource.getrusage(resource.RUSAGE_SELF).ru_utime - c0
    return {k: float(getattr(m, "value", m)) for k, m in res.metrics.items()}, cpu, float(res.info["dt"])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rig", required=True, choices=sorted(RIGS))
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--steps-per-contact", type=int, default=14)
    ap.add_argument("--out")
    a = ap.parse_args()
    lines = [f"# studies/time_step_shift.py --rig {a.rig} --seeds {a.seeds} --steps-per-contact {a.steps_per_contact} "
             f"({time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}); default preset at {CENTRE}, one thread"]
    shipped, coarse, cpu = [], [], []
    for seed in range(1, a.seeds + 1):
        m0, t0, dt0 = run(a.rig, seed, None)
        m1, t1, dt1 = run(a.rig, seed, a.steps_per_contact)
        shipped.append(m0), coarse.append(m1), cpu.append(t0 / t1)
        lines.append(f"seed {seed}: dt {dt0:.3e} -> {dt1:.3e} s, CPU {t0:.1f} -> {t1:.1f} s (x{t0 / t1:.2f}); "
                     f"metrics {json.dumps(m0)} -> {json.dumps(m1)}")
        print(lines[-1], flush=True)
    summary = len(lines)
    lines.append(f"CPU time shipped / coarse: median x{np.median(cpu):.2f}")
    lines.append("metric: shipped mean, seed sd | mean shift coarse - shipped +- its standard error (shift / se)")
    for k in shipped[0]:
        if not all(k in m for m in shipped + coarse):
            lines.append(f"  {k:22s} not in every run (left out)")
            continue
        x0 = np.array([m[k] for m in shipped])
        x1 = np.array([m[k] for m in coarse])
        if not (np.all(np.isfinite(x0)) and np.all(np.isfinite(x1))):
            lines.append(f"  {k:22s} not finite in every run (left out)")
            continue
        dx = x1 - x0
        se = dx.std(ddof=1) / math.sqrt(len(dx))
        lines.append(f"  {k:22s} {x0.mean():10.4g}  sd {x0.std(ddof=1):9.3g} | shift {dx.mean():+10.3g} +- {se:9.3g}"
                     f"  ({dx.mean() / se if se > 0 else math.nan:+.1f} se; {dx.mean() / x0.std(ddof=1) if x0.std(ddof=1) > 0 else math.nan:+.2f} seed sd)")
    print("\n".join(lines[summary:]))
    if a.out:
        with open(a.out, "w") as f:
            f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
