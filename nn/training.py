"""Training image networks with torch (nn.cnn's AlexNet-FC, CNN-LSTM and the four backbones):
`fit` — Adam on standardised targets, mini-batches, the weights of the best validation loss kept;
seeded, with a progress callback (epoch, loss, frames/s, time left) and a checkpoint after every
epoch from which a killed training resumes; on the device the model sits on (`pick_device`: a GPU
when torch sees one, bfloat16 autocast there; nothing requires one); `windows` for the recurrent
network; `predict`; `best_weights` of a checkpoint, to start another training from."""
from __future__ import annotations

import contextlib
import math
import time
from pathlib import Path

import numpy as np
import torch


def pick_device(name: str = "auto") -> torch.device:
    """'auto': the GPU when torch sees one, else the CPU; 'cpu' or 'cuda' to choose."""
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    if name not in ("cpu", "cuda"):
        raise ValueError(f"device: 'auto', 'cpu' or 'cuda', got {name!r}")
    if name == "cuda" and not torch.cuda.is_available():
        raise ValueError("device 'cuda' asked for, but torch sees no GPU on this machine")
    return torch.device(name)


def _device_of(model: torch.nn.Module) -> torch.device:
    return next(model.parameters()).device


def _autocast(device: torch.device):
    """bfloat16 autocast on a GPU (its tensor cores; the loss stays float32), nothing on the CPU
    (which keeps the CPU runs bitwise reproducible)."""
    return torch.autocast("cuda", torch.bfloat16) if device.type == "cuda" else contextlib.nullcontext()


def fit(model: torch.nn.Module, x: np.ndarray, y: np.ndarray, x_val: np.ndarray, y_val: np.ndarray, epochs: int = 20,
        batch: int = 32, lr: float = 1e-4, seed: int = 0, checkpoint: str | Path | None = None, progress=None,
        scaling: dict | None = None, clip: float | None = None, time_budget: float | None = None) -> dict:
    """Trains model (in place, initialised by the caller: seed torch before building it, move it
    to its device) to predict y from x with MSE on standardised targets; keeps the weights of
    the best validation loss. With checkpoint (a file), the state after each epoch is
    saved there and a rerun continues from it. Returns the history and the target scaling
    (`scaling`, e.g. a pretrained model's, is kept instead of the targets' own); `clip`: the
    gradient's largest norm per step (recurrent networks: one large step can collapse them);
    `time_budget`: seconds after which no further epoch starts (the history says how many ran)."""
    torch.manual_seed(seed)
    dev = _device_of(model)
    mean, sd = (float(scaling["mean"]), float(scaling["sd"])) if scaling else (float(np.mean(y)), float(np.std(y) or 1.0))
    # on a GPU the whole set moves there once (a few GB at most), not batch by batch
    xt, yt = torch.from_numpy(np.ascontiguousarray(x)).to(dev), torch.from_numpy(((y - mean) / sd).astype(np.float32)).to(dev)
    xv, yv = torch.from_numpy(np.ascontiguousarray(x_val)).to(dev), ((y_val - mean) / sd).astype(np.float32)
    opt = torch.optim.Adam(model.parameters(), lr=lr)
    state = {"epoch": 0, "history": [], "best": math.inf, "best_weights": None}
    ck = Path(checkpoint) if checkpoint else None
    signature = {"model": type(model).__name__, "parameters": sum(p.numel() for p in model.parameters()),
                 "x": list(np.shape(x)), "x_val": list(np.shape(x_val)), "batch": batch, "lr": lr, "seed": seed}
    if clip is not None:
        signature["clip"] = clip
    if ck is not None and ck.exists():
        saved = torch.load(ck, weights_only=False, map_location="cpu")  # the optimiser's state follows its parameters
        if saved.get("signature") != signature:
            raise ValueError(f"{ck}: a checkpoint of another training ({saved.get('signature')}); remove it to start afresh")
        model.load_state_dict(saved["model"])
        opt.load_state_dict(saved["optimizer"])
        state = saved["state"]
        torch.set_rng_state(saved["rng"])
    t0, seen = time.perf_counter(), 0
    for epoch in range(state["epoch"] + 1, epochs + 1):
        model.train()
        order = torch.randperm(len(yt))
        total = 0.0
        for i in range(0, len(order), batch):
            idx = order[i:i + batch].to(dev)
            opt.zero_grad()
            with _autocast(dev):
                out = model(xt[idx])
            loss = torch.mean((out.float().reshape(yt[idx].shape) - yt[idx]) ** 2)
            loss.backward()
            if clip is not None:
                torch.nn.utils.clip_grad_norm_(model.parameters(), clip)
            opt.step()
            total += float(loss.detach()) * len(idx)
            seen += len(idx)
        val = float(np.mean((predict_scaled(model, xv, batch) - yv.reshape(-1)) ** 2)) if len(yv) else math.nan
        state["history"].append({"epoch": epoch, "loss": total / len(yt), "validation": val})
        if not (val >= state["best"]):  # the first epoch, a better one, or no validation set
            state["best"] = val
            state["best_weights"] = {k: v.detach().clone() for k, v in model.state_dict().items()}
        state["epoch"] = epoch
        if ck is not None:
            ck.parent.mkdir(parents=True, exist_ok=True)
            tmp = ck.with_suffix(".tmp")
            torch.save({"model": model.state_dict(), "optimizer": opt.state_dict(), "state": state,
                        "rng": torch.get_rng_state(), "signature": signature}, tmp)
            tmp.replace(ck)
        if progress is not None:
            rate = seen / max(time.perf_counter() - t0, 1e-9)
            progress(epoch, epochs, total / len(yt), val, rate, (epochs - epoch) * len(yt) / max(rate, 1e-9))
        if time_budget is not None and time.perf_counter() - t0 >= time_budget and epoch < epochs:
            if hasattr(progress, "say"):
                progress.say(f"  time budget of {time_budget:.0f} s spent after epoch {epoch} of {epochs}")
            break
    if state["best_weights"] is not None:
        model.load_state_dict(state["best_weights"])
    model.eval()
    return {"history": state["history"], "mean": mean, "sd": sd}


def best_weights(checkpoint: str | Path) -> dict:
    """The best-validation weights saved in a `fit` checkpoint (to start another training from)."""
    ck = Path(checkpoint)
    if not ck.exists():
        raise ValueError(f"{ck} not found")
    weights = torch.load(ck, weights_only=False, map_location="cpu")["state"]["best_weights"]
    if weights is None:
        raise ValueError(f"{ck} holds no finished epoch")
    return weights


def windows(x: np.ndarray, y: np.ndarray, length: int, stride: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Sliding windows of `length` consecutive frames, one starting every `stride` frames, for
    the CNN-LSTM: (windows, length, 1, H, W) and their targets (windows, length)."""
    n = len(x) - length + 1
    if n < 1:
        raise ValueError(f"{len(x)} frames are fewer than one window of {length}")
    idx = np.arange(length)[None, :] + np.arange(0, n, stride)[:, None]
    return x[idx], y[idx]


def predict_scaled(model: torch.nn.Module, x, batch: int = 64) -> np.ndarray:
    model.eval()
    dev = _device_of(model)
    x = torch.as_tensor(x)
    with torch.no_grad(), _autocast(dev):
        return np.concatenate([model(x[i:i + batch].to(dev)).float().reshape(-1).cpu().numpy()
                               for i in range(0, len(x), batch)]) if len(x) else np.zeros(0, np.float32)


def predict(model: torch.nn.Module, x: np.ndarray, scaling: dict, batch: int = 64) -> np.ndarray:
    return predict_scaled(model, x, batch) * scaling["sd"] + scaling["mean"]
