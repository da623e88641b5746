"""Screening throughput (DESIGN section 10): the same nets and the same 2^20 inputs through
libdem (dem_mlp_eval_many / dem_mlp_screen, 1 and 2 threads) and through torch on the CPU
(float64, the PropertyNet forward incl. scaling, 1 and 2 threads). Best of `--repeats` each.

    .venv/bin/python bench/screening.py [--nets build/calibration/nets] [--csv bench/results/screening.csv]

The nets are those `make demo` trains (build/calibration/nets/*.mlp)."""
from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np
import torch

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from nn.export import read_weights  # noqa: E402
from pydem.mlp import NativeMLP, screen  # noqa: E402
from pydem.campaign.design import design_points  # noqa: E402


def best_of(fn, repeats):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--nets", default=str(ROOT / "build/calibration/nets"))
    ap.add_argument("--samples", type=int, default=2 ** 20)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--csv", default=str(ROOT / "bench/results/screening.csv"))
    a = ap.parse_args()
    files = sorted(Path(a.nets).glob("*.mlp"))
    if not files:
        sys.exit(f"no nets in {a.nets}: run `make demo` first (it trains and exports them)")
    native = [NativeMLP(f) for f in files]
    # one screening evaluates nets over the same inputs: the largest group of nets sharing them
    groups = {}
    for f, n in zip(files, native):
        groups.setdefault(tuple(n.input_names), []).append(f)
    files = max(groups.values(), key=len)
    native = [NativeMLP(f) for f in files]
    torch_nets = [read_weights(f) for f in files]
    names = native[0].input_names
    box = {n: (float(torch_nets[0].x_scaler.lo[j]), float(torch_nets[0].x_scaler.hi[j])) for j, n in enumerate(names)}
    x = design_points("sobol", box, 0, a.samples, 7)
    hidden = [n.hidden for n in native]
    print(f"{len(native)} nets (hidden {hidden}), {a.samples:,} inputs of {len(names)} parameters")
    # agreement first: a fast wrong answer is worth nothing
    worst = max(float(np.max(np.abs(n(x[:20000]) - t.predict(x[:20000])) / np.abs(t.predict(x[:20000]))))
                for n, t in zip(native, torch_nets))
    rows = []
    for threads in (1, 2):
        t_native = best_of(lambda: [n(x, threads) for n in native], a.repeats)
        targets = [float(np.median(n(x[:1000]))) for n in native]
        t_screen = best_of(lambda: screen(native, targets, 0.05, x, threads, with_predictions=False), a.repeats)
        torch.set_num_threads(threads)
        xt = torch.from_numpy(x)

        def run_torch():
            with torch.no_grad():
                for t in torch_nets:
                    xs = (xt - torch.from_numpy(t.x_scaler.lo)) * torch.from_numpy(2.0 / (t.x_scaler.hi - t.x_scaler.lo)) - 1.0
                    ys = t.model(xs)
                    _ = (ys + 1.0) * float((t.y_scaler.hi[0] - t.y_scaler.lo[0]) / 2.0) + float(t.y_scaler.lo[0])

        t_torch = best_of(run_torch, a.repeats)
        rows.append((threads, t_native, t_screen, t_torch))
        print(f"threads {threads}: libdem eval {1e3 * t_native:7.1f} ms   libdem screen {1e3 * t_screen:7.1f} ms   "
              f"torch {1e3 * t_torch:7.1f} ms   speed-up {t_torch / t_native:5.1f}x   "
              f"({len(native) * a.samples / t_native / 1e6:.0f} M net evaluations/s native)")
    print(f"max relative difference native vs torch: {worst:.2e}")
    new = not Path(a.csv).exists()
    with open(a.csv, "a") as fh:
        if new:
            fh.write("date,machine,cores,nets,hidden,samples,threads,libdem_eval_ms,libdem_screen_ms,torch_ms,speedup,"
                     "max_rel_diff\n")
        for threads, tn, ts, tt in rows:
            fh.write(f"{time.strftime('%Y-%m-%d %H:%M')},{platform.machine()},{os.cpu_count()},{len(native)},"
                     f"{' '.join(map(str, hidden))},{a.samples},{threads},{1e3 * tn:.2f},{1e3 * ts:.2f},{1e3 * tt:.2f},"
                     f"{tt / tn:.2f},{worst:.2e}\n")
    print(f"appended to {a.csv}")


if __name__ == "__main__":
    main()
