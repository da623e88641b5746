"""Seed 001's image networks on this machine's CPU: training throughput (frames per second
through a forward and backward pass with Adam, as nn.training.fit trains them) and inference
latency per frame (one frame alone, and per frame in batches), on 1 and 2 torch threads, at the
2-core runs' 64 x 64 input and the seed's 224 x 224.

    .venv/bin/python bench/image_nets.py [--sizes 64 224] [--threads 1 2] [--out bench/results/image_nets.txt]

Frames are random grey images: a network's cost does not depend on what the frames show. The
CNN-LSTM counts a frame of a window as one frame (a window of 8 is 8 frames). Each figure is the
median of `--repeats` timings after one warm-up. Run on a quiet machine (campaign workers
paused): other processes on the two cores take their share."""
from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
from pathlib import Path

import torch

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from nn.cnn import CNNLSTM, AlexNetFC, BACKBONES, parameter_count  # noqa: E402

WINDOW = 8  # frames per CNN-LSTM window, as `pydem images process` reads them


def networks():
    out = {name: make for name, make in BACKBONES.items()}
    out["alexnet_fc"] = lambda: AlexNetFC()
    out["cnn_lstm"] = lambda: CNNLSTM()
    return out


def frames(name: str, batch: int, size: int) -> torch.Tensor:
    g = torch.Generator().manual_seed(0)
    if name == "cnn_lstm":  # batch of windows
        return torch.rand(max(1, batch // WINDOW), WINDOW, 1, size, size, generator=g)
    return torch.rand(batch, 1, size, size, generator=g)


def per_frame(x: torch.Tensor, name: str) -> int:
    return x.shape[0] * (x.shape[1] if name == "cnn_lstm" else 1)


def timed(fn, repeats: int) -> float:
    fn()  # warm-up: allocations, kernel choice
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts)


def measure(name: str, size: int, batch: int, repeats: int) -> dict:
    torch.manual_seed(0)
    model = networks()[name]()
    opt = torch.optim.Adam(model.parameters(), lr=1e-4)
    x = frames(name, batch, size)
    y = torch.zeros(x.shape[:2] if name == "cnn_lstm" else (x.shape[0],))

    def train_step():
        model.train()
        opt.zero_grad()
        loss = torch.mean((model(x).reshape(y.shape) - y) ** 2)
        loss.backward()
        opt.step()

    t_train = timed(train_step, repeats)
    model.eval()
    one = frames(name, WINDOW if name == "cnn_lstm" else 1, size)
    with torch.no_grad():
        t_one = timed(lambda: model(one), repeats)
        t_batch = timed(lambda: model(x), repeats)
    return {"parameters": parameter_count(model), "train_frames_per_s": per_frame(x, name) / t_train,
            "latency_ms": 1e3 * t_one / per_frame(one, name), "batched_ms_per_frame": 1e3 * t_batch / per_frame(x, name)}


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", type=int, nargs="+", default=[64, 224])
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--batch", type=int, default=32, help="training and batched-inference batch (frames)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--nets", nargs="+", default=list(networks()))
    ap.add_argument("--out", default=str(ROOT / "bench/results/image_nets.txt"))
    args = ap.parse_args()
    lines = [f"# {time.strftime('%Y-%m-%d %H:%M')} {platform.machine()}, {len(os.sched_getaffinity(0))} cores, "
             f"torch {torch.__version__}; batch {args.batch} frames (CNN-LSTM: windows of {WINDOW}), median of {args.repeats}",
             f"{'network':11s} {'size':>4s} {'thr':>3s} {'params':>11s} {'train frames/s':>14s} {'latency ms/frame':>16s} "
             f"{'batched ms/frame':>16s}"]
    print("\n".join(lines), flush=True)
    for size in args.sizes:
        for name in args.nets:
            for th in args.threads:
                torch.set_num_threads(th)
                r = measure(name, size, args.batch, args.repeats)
                line = (f"{name:11s} {size:4d} {th:3d} {r['parameters']:11,d} {r['train_frames_per_s']:14.1f} "
                        f"{r['latency_ms']:16.2f} {r['batched_ms_per_frame']:16.2f}")
                print(line, flush=True)
                lines.append(line)
    Path(args.out).write_text("\n".join(lines) + "\n")
    print(f"-> {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
