"""Campaign throughput on this machine: the same rig runs (one preset, the campaign box's centre,
different seeds) done as W workers of T threads each, for every (W, T) with W x T = the core
count, in alternating rounds; runs per hour for each. Decides the campaigns' default split.

    .venv/bin/python bench/campaign_throughput.py [--rig hopper] [--preset default] [--runs 4] [--rounds 2]
        -> bench/results/campaign_throughput_<rig>_<preset>.txt
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

CENTRE = {"friction": 0.5, "rolling_friction": 0.3, "restitution": 0.55}


def one_run(rig: str, preset: str, threads: int, seed: int) -> float:
    os.environ["OMP_NUM_THREADS"] = str(threads)
    from pydem.rigs import RIGS
    cls, cfg_cls = RIGS[rig]
    cfg = cfg_cls.preset(preset)
    cfg.num_threads = threads
    t0 = time.perf_counter()
    cls(cfg).run(dict(CENTRE), seed=seed)
    return time.perf_counter() - t0


def batch(rig: str, preset: str, workers: int, threads: int, runs: int, seed0: int) -> float:
    """Runs per hour for `runs` runs on `workers` processes of `threads` threads."""
    t0 = time.perf_counter()
    with ProcessPoolExecutor(workers) as pool:
        list(pool.map(one_run, [rig] * runs, [preset] * runs, [threads] * runs, range(seed0, seed0 + runs)))
    return runs * 3600.0 / (time.perf_counter() - t0)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rig", default="hopper")
    ap.add_argument("--preset", default="default")
    ap.add_argument("--runs", type=int, default=4, help="runs per configuration and round")
    ap.add_argument("--rounds", type=int, default=2)
    args = ap.parse_args()
    cores = os.cpu_count() or 1
    splits = [(w, cores // w) for w in range(1, cores + 1) if cores % w == 0]
    lines = [f"# {args.rig} {args.preset}: {args.runs} runs per configuration, {args.rounds} alternating rounds, "
             f"{cores} cores, {time.strftime('%Y-%m-%d %H:%M')}"]
    rates = {s: [] for s in splits}
    for r in range(args.rounds):
        for w, t in (splits if r % 2 == 0 else splits[::-1]):
            rate = batch(args.rig, args.preset, w, t, args.runs, 100 * r)
            rates[(w, t)].append(rate)
            lines.append(f"round {r + 1}: {w} worker(s) x {t} thread(s): {rate:.1f} runs/h")
            print(lines[-1], flush=True)
    for (w, t), v in rates.items():
        lines.append(f"mean {w} worker(s) x {t} thread(s): {sum(v) / len(v):.1f} runs/h")
        print(lines[-1])
    out = ROOT / f"bench/results/campaign_throughput_{args.rig}_{args.preset}.txt"
    out.write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
