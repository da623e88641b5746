"""Training and judging seed 001's image networks on a frame store (pydem.frames.FrameStore),
beside the physics baselines.

- `load_frames`: every stored frame of the chosen cases as float32 (n, 1, size, size) in [0, 1]
  (area-averaged from the stored 224 x 224 crop when size < 224), or its two species as two
  channels (`species_frames`), with its case, time, remaining discharge time and NRRP;
- splits: `random_split` (seed 001's 60/20/20 over frames: neighbouring frames of one run are
  near-duplicates, so it flatters) and `case_split` (whole cases held out: what a user predicting
  a new hopper gets);
- `fit`: Adam on standardised targets, mini-batches, the weights of the best validation loss
  kept; seeded, with progress (epoch, loss, frames/s, time left) and a checkpoint after every
  epoch from which a killed training resumes; on the device the model sits on (`pick_device`:
  a GPU when torch sees one, bfloat16 autocast there; nothing requires one);
- `scores`: MAE, RMSE, R^2 (seed 001, Eqs. 7-9) and the average relative error (Eq. 10, away
  from the empty end);
- baselines: Beverloo's slot law for a case's discharge time (C and k fitted on training cases
  only) and, per frame, the remaining time as the frame's fill fraction times it; a constant-rate
  extrapolation of the first 20 % of NRRP(t), and the NRRP as two image gauges calibrated on
  training cases read it: from the frame's fill level, and from each species' visible fill."""
from __future__ import annotations

import contextlib
import math
import time
from dataclasses import dataclass
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


@dataclass
class Frames:
    x: np.ndarray          # (n, channels, size, size) float32 in [0, 1]
    case: np.ndarray       # (n,) case names
    time: np.ndarray       # s since the gate opened
    remaining: np.ndarray  # remaining discharge time (s)
    nrrp: np.ndarray
    discharge: dict        # case -> discharge time (s)
    attrs: dict            # case -> stored attributes

    def take(self, idx) -> "Frames":
        return Frames(self.x[idx], self.case[idx], self.time[idx], self.remaining[idx], self.nrrp[idx],
                      self.discharge, self.attrs)


def shrink(frames: np.ndarray, size: int) -> np.ndarray:
    """uint8 (n, H, W) -> float32 (n, 1, size, size) in [0, 1], area-averaged."""
    x = torch.from_numpy(np.asarray(frames, np.float32) / 255.0)[:, None]
    if size != x.shape[-1]:
        x = torch.nn.functional.adaptive_avg_pool2d(x, size)
    return x.numpy()


def species_frames(frames: np.ndarray, size: int) -> np.ndarray:
    """uint8 (n, H, W) grey frames -> float32 (n, 2, size, size): one frame per species (fine,
    coarse; pydem.frames.species_masks), each in the grey frames' convention — 0 where the
    species covers the pixel, 1 where it does not — area-averaged to size."""
    from pydem.frames import species_masks
    out = []
    for i in range(0, len(frames), 256):
        m = torch.from_numpy(species_masks(frames[i:i + 256]).astype(np.float32))
        if size != m.shape[-1]:
            m = torch.nn.functional.adaptive_avg_pool2d(m, size)
        out.append(1.0 - m.numpy())
    return np.concatenate(out) if out else np.zeros((0, 2, size, size), np.float32)


INPUTS = {"grey": shrink, "species": species_frames}  # what a network sees of a stored frame


def load_frames(store_path, cases=None, size: int = 224, every: int = 1, inputs: str = "grey") -> Frames:
    """Every `every`-th frame of each case (all stored cases when cases is None), in time order,
    as `inputs` gives it: the grey frame (1 channel) or its two species (INPUTS)."""
    from pydem.frames import FrameStore
    if inputs not in INPUTS:
        raise ValueError(f"inputs: one of {sorted(INPUTS)}, got {inputs!r}")
    store = FrameStore(store_path)
    names = cases or store.cases()
    xs, cs, ts, rs, ns, dis, attrs = [], [], [], [], [], {}, {}
    for c in names:
        d = store.read_case(c)
        sl = slice(None, None, every)
        xs.append(INPUTS[inputs](d["frames"][sl], size))
        cs += [c] * len(xs[-1])
        ts.append(d["time"][sl]), rs.append(d["remaining_time"][sl]), ns.append(d["nrrp"][sl])
        dis[c] = float(d["discharge_time"])
        attrs[c] = {"case": c} | {k: v for k, v in d.items() if k not in ("frames", "time", "remaining_time", "nrrp")}
    if not xs:
        raise ValueError(f"{store_path}: no frames of the cases {names}")
    return Frames(np.concatenate(xs), np.array(cs), np.concatenate(ts), np.concatenate(rs), np.concatenate(ns), dis, attrs)


def random_split(n: int, seed: int = 0, fractions=(0.6, 0.2, 0.2)) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(train, validation, test) frame indices, seed 001's random 60/20/20."""
    order = np.random.default_rng(seed).permutation(n)
    a, b = int(round(fractions[0] * n)), int(round((fractions[0] + fractions[1]) * n))
    return np.sort(order[:a]), np.sort(order[a:b]), np.sort(order[b:])


def case_split(case: np.ndarray, test_cases, validation_cases) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(train, validation, test) indices with whole cases held out."""
    test, val = np.isin(case, list(test_cases)), np.isin(case, list(validation_cases))
    if (test & val).any():
        raise ValueError("a case cannot be both a validation and a test case")
    return np.flatnonzero(~test & ~val), np.flatnonzero(val), np.flatnonzero(test)


def scores(y: np.ndarray, pred: np.ndarray, floor: float = 0.1) -> dict:
    """MAE, RMSE, R^2 (seed 001 Eqs. 7-9) and the average relative error |y - pred| / y (Eq. 10)
    over the rows with y >= floor x max(y): the remaining time and the NRRP both fall to zero at
    the end of a discharge, where a relative error has no bound and would drown the rest."""
    y, pred = np.asarray(y, float), np.asarray(pred, float)
    if len(y) == 0:
        return {"mae": math.nan, "rmse": math.nan, "r2": math.nan, "relative_error": math.nan, "n": 0}
    err = pred - y
    rel = y >= floor * y.max()
    rel &= y > 0
    return {"mae": float(np.mean(np.abs(err))), "rmse": float(np.sqrt(np.mean(err ** 2))),
            "r2": float(1.0 - np.sum(err ** 2) / np.sum((y - y.mean()) ** 2)) if len(y) > 1 else math.nan,
            "relative_error": float(np.mean(np.abs(err[rel]) / y[rel])) if rel.any() else math.nan, "n": int(len(y))}


class Progress:
    def __init__(self, say=print):
        self.say = say

    def __call__(self, epoch: int, epochs: int, loss: float, val: float, rate: float, left: float):
        self.say(f"  epoch {epoch}/{epochs}  loss {loss:.4g}  validation {val:.4g}  {rate:.0f} frames/s  "
                 f"{left / 60:.1f} min left")


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


# ---- physics baselines -------------------------------------------------------------------

def case_mass_and_size(attrs: dict) -> tuple[float, float, float]:
    """(total mass kg, mean diameter m, solid density) of a stored Table 1 case from its attributes."""
    from pydem.rigs.table1 import TABLE1, solid_volume
    row = TABLE1[attrs["case"]]
    phi, dd, rho = row[3], row[9], row[10]
    return rho * solid_volume(row), (phi * dd[0] + (1.0 - phi) * dd[1]) / 1000.0, float(rho)


def beverloo_discharge(train: dict[str, float], attrs: dict[str, dict], slot: float = 0.054, length: float = 0.04):
    """Beverloo's slot law W = C rho sqrt(g) L (b - k d)^(3/2) with the solid density (the packing
    fraction goes into C), C and k fitted on the training cases' mean flow rates M / t_dis (least
    squares in W^(2/3), a grid over k); returns (C, k, predict(case attrs) -> discharge time)."""
    rows = [(case_mass_and_size(attrs[c]), t) for c, t in train.items()]
    best = None
    for k in np.linspace(0.0, 3.0, 301):
        feats = np.array([rho * math.sqrt(9.81) * length * max(slot - k * d, 1e-6) ** 1.5 for (m, d, rho), _ in rows])
        w = np.array([m / t for (m, d, rho), t in rows])
        c = float(feats @ w / (feats @ feats))
        err = float(np.sum((w ** (2 / 3) - (c * feats) ** (2 / 3)) ** 2))
        if best is None or err < best[0]:
            best = (err, c, float(k))
    _, c, k = best

    def discharge_time(a: dict) -> float:
        m, d, rho = case_mass_and_size(a)
        return m / (c * rho * math.sqrt(9.81) * length * max(slot - k * d, 1e-6) ** 1.5)
    return c, k, discharge_time


def fill_fraction(x: np.ndarray, first: np.ndarray) -> np.ndarray:
    """Each frame's particle pixels (darker than the background) over those of its case's first
    frame: an image-only estimate of the NRRP."""
    dark = lambda f: np.sum(f < 0.9 * np.median(f), axis=(-2, -1)).reshape(len(f))  # noqa: E731
    return dark(x) / max(float(dark(first[None])[0]), 1.0)


def fill_level_nrrp(fill_train: np.ndarray, nrrp_train: np.ndarray, fill: np.ndarray, degree: int = 3) -> np.ndarray:
    """The NRRP a fill-level gauge reads: a polynomial (degree 3) of the frame's fill fraction
    fitted to training cases' whole discharges, clipped to [0, 1] — what the image's fill level
    alone carries about the count that remains, once calibrated on other hoppers."""
    coeffs = np.polyfit(np.asarray(fill_train, float), np.asarray(nrrp_train, float), degree)
    return np.clip(np.polyval(coeffs, np.asarray(fill, float)), 0.0, 1.0)


def fines_count_share(case: str, row: tuple | None = None) -> float:
    """The fine spheres' share of a Table 1 case's count (its fine volume fraction and two sizes),
    or of a hopper given by its Table 1-style row."""
    from pydem.rigs.table1 import TABLE1, species_counts
    n, _nu, _e, phi, *_, dd, _rho = row if row is not None else TABLE1[case]
    nf, nc = species_counts(n, dd[0], dd[1], phi)
    return nf / (nf + nc)


def species_fill(frames: np.ndarray) -> np.ndarray:
    """(n, H, W) uint8 grey frames of one case -> (n, 2): the pixels only fine spheres, and only
    coarse ones, can show (pydem.frames.species_masks), each over its case's first frame's —
    how much of each species the front view still shows."""
    from pydem.frames import species_masks
    counts = species_masks(frames).sum(axis=(-2, -1))
    return counts / np.maximum(counts[:1], 1.0)


def species_design(fill: np.ndarray, fines_share: float, degree: int = 3) -> np.ndarray:
    """The species gauge's regressors: w F^i and (1 - w) K^i for i = 1..degree, F and K the
    species' fill (species_fill), w the fines' share of the count: the count that remains is the
    fines' share times the share of fines left plus the coarse's, each read from its own fill."""
    f, k = np.asarray(fill, float).T
    return np.column_stack([fines_share * f ** i for i in range(1, degree + 1)]
                           + [(1.0 - fines_share) * k ** i for i in range(1, degree + 1)])


def species_gauge_nrrp(design_train: np.ndarray, nrrp_train: np.ndarray, design: np.ndarray) -> np.ndarray:
    """The NRRP a species gauge reads: least squares of the count on species_design's regressors
    over training cases' whole discharges, clipped to [0, 1]."""
    beta = np.linalg.lstsq(np.asarray(design_train, float), np.asarray(nrrp_train, float), rcond=None)[0]
    return np.clip(np.asarray(design, float) @ beta, 0.0, 1.0)


def constant_rate_nrrp(t: np.ndarray, nrrp: np.ndarray, fraction: float = 0.2) -> np.ndarray:
    """NRRP(t) extrapolated at the constant rate of a straight line through the first `fraction`
    of the (time-ordered) series, clipped to [0, 1]."""
    k = max(2, int(round(fraction * len(t))))
    slope, icpt = np.polyfit(t[:k], nrrp[:k], 1)
    return np.clip(icpt + slope * t, 0.0, 1.0)
