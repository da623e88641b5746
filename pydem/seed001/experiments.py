"""Seed 001's three learning experiments on a frame store, each beside its physics baseline
(docs/seed001.md):

- `compare`: AlexNet, ResNet-50, VGG-16, VGG-19 regress the remaining discharge time from a
  frame; seed 001's random 60/20/20 split of the frames; MAE, RMSE, R^2 (its Table 2);
- `point_to_point`: AlexNet-FC on two splits — random frames (the seed's protocol; neighbouring
  frames of one run are near-duplicates, so it flatters) and leave-cases-out (whole cases held
  out: a new hopper); R^2 and average relative error per packing pattern;
- `process`: the CNN-LSTM predicting each case's NRRP beyond the first 20 % of its
  time-ordered frames — trained on those frames only (seed 001's protocol), or pretrained on
  other cases' whole discharges and fine-tuned on them; average relative error per packing.

Baselines: the remaining discharge time as the frame's fill fraction (image-only NRRP
estimate) times Beverloo's discharge time (C, k fitted on the training cases); NRRP by a
constant-rate extrapolation of the first 20 %, and (pretrained protocol) a fill-level gauge: NRRP
as a cubic of the frame's fill fraction, fitted on the pretraining cases of the same packing.
Every result records its settings, the time each
training took and the machine, so the docs' tables can say what stands behind them."""
from __future__ import annotations

import copy
import json
import platform
import time
from pathlib import Path

import numpy as np
import torch

from nn import cnn, training

from ..progress import EpochProgress
from . import baselines, frame_data, gauges
from .store import FrameStore

PACKINGS = ("A", "B1", "B2", "B3", "B4")
LSTM_CLIP = 1.0  # gradient norm cap of the CNN-LSTM's steps (recurrent layers)


def packing_of(case: str) -> str:
    return case.split("-")[0]


def _machine(device: torch.device | None = None) -> str:
    import os
    where = f", on {torch.cuda.get_device_name(device)}" if device is not None and device.type == "cuda" else ""
    return (f"{platform.machine()}, {len(os.sched_getaffinity(0))} cores, torch {torch.__version__}, "
            f"{torch.get_num_threads()} threads{where}")


def _beverloo_per_frame(f: frame_data.Frames, train_cases, first_frames: dict) -> tuple[np.ndarray, dict]:
    """Remaining discharge time per frame: fill fraction x Beverloo discharge time of its case."""
    c, k, t_dis = baselines.beverloo_discharge({cs: f.discharge[cs] for cs in train_cases}, f.attrs)
    pred = np.empty(len(f.x))
    for cs in np.unique(f.case):
        m = f.case == cs
        pred[m] = baselines.fill_fraction(f.x[m], first_frames[cs]) * t_dis(f.attrs[cs])
    return pred, {"C": c, "k": k}


def _first_frames(store, size: int, cases=None) -> dict:
    s = FrameStore(store)
    return {c: frame_data.shrink(s.read_case(c)["frames"][:1], size)[0] for c in (cases or s.cases())}


def _train(name: str, build, f: frame_data.Frames, tr, va, epochs: int, batch: int, lr: float, seed: int, out: Path, say,
           device: torch.device = torch.device("cpu"), time_budget: float | None = None):
    torch.manual_seed(seed)
    model = build().to(device)
    t0 = time.perf_counter()
    scaling = training.fit(model, f.x[tr], f.remaining[tr], f.x[va], f.remaining[va], epochs=epochs, batch=batch, lr=lr,
                         seed=seed, checkpoint=out / f"{name}.pt", progress=EpochProgress(say), time_budget=time_budget)
    seconds = time.perf_counter() - t0
    return model, scaling, seconds


def compare(store, out, size: int = 64, every: int = 4, epochs: int = 8, batch: int = 32, lr: float = 1e-4,
            models=tuple(cnn.BACKBONES), seed: int = 0, device: str = "auto", time_budget: float | None = None,
            checkpoints=None, say=print) -> dict:
    """`time_budget`: seconds of training per network after which no further epoch starts (each
    network's row says how many epochs it had); `checkpoints`: their folder when not `out` (a
    VGG's with its optimiser state is 1.6 GB)."""
    unknown = sorted(set(models) - set(cnn.BACKBONES))
    if unknown:
        raise ValueError(f"networks {unknown}: not among {sorted(cnn.BACKBONES)}")
    out = Path(out)
    dev = training.pick_device(device)
    f = frame_data.load_frames(store, size=size, every=every)
    tr, va, te = frame_data.random_split(len(f.x), seed)
    say(f"compare: {len(f.x)} frames of {len(f.discharge)} cases at {size} x {size}; train {len(tr)}, validation {len(va)}, "
        f"test {len(te)}; on {dev}")
    res = {"settings": {"size": size, "every": every, "epochs": epochs, "batch": batch, "lr": lr, "seed": seed,
                        "frames": int(len(f.x)), "split": "random 60/20/20 over frames", "device": str(dev)}
           | ({"time_budget_s": time_budget} if time_budget is not None else {}),
           "machine": _machine(dev), "models": {}}
    for name in models:
        say(f"- {name}")
        model, scaling, seconds = _train(name, cnn.BACKBONES[name], f, tr, va, epochs, batch, lr, seed,
                                         Path(checkpoints or out), say, dev, time_budget)
        t0 = time.perf_counter()
        pred = training.predict(model, f.x[te], scaling)
        per_frame = (time.perf_counter() - t0) / max(len(te), 1)
        res["models"][name] = frame_data.scores(f.remaining[te], pred) | {
            "train_seconds": seconds, "epochs_run": len(scaling["history"]),
            "predict_ms_per_frame": 1e3 * per_frame, "parameters": cnn.parameter_count(model)}
        say(f"  {name}: " + ", ".join(f"{k} {v:.4g}" for k, v in res["models"][name].items()))
        _save(out / "compare.json", res)  # each network's row is kept as soon as it exists
    base, law = _beverloo_per_frame(f, sorted(f.discharge), _first_frames(store, size))
    res["baseline"] = frame_data.scores(f.remaining[te], base[te]) | {"law": law}
    _save(out / "compare.json", res)
    return res


def point_to_point(store, out, size: int = 64, every: int = 2, epochs: int = 12, batch: int = 32, lr: float = 1e-4,
                   seed: int = 0, device: str = "auto", checkpoints=None, extra=(), extra_per_packing: int | None = None,
                   say=print) -> dict:
    """AlexNet-FC on the remaining discharge time, two splits of the Table 1 frames: random frames
    and leave cases out (the -5 cases tested, the -4 cases validating). `extra`: frame stores of
    more hoppers (pydem images hoppers; the first `extra_per_packing` of each packing) that join
    the leave-cases-out training only (and the Beverloo baseline's fit); the random split stays
    the seed's protocol on Table 1's frames."""
    out = Path(out)
    dev = training.pick_device(device)
    table1 = frame_data.load_frames(store, size=size, every=every)
    cases = sorted(table1.discharge)
    more = extra_hoppers(extra, cases, extra_per_packing)
    f = frame_data.concat([table1] + [frame_data.load_frames(path, cases=names, size=size, every=every)
                                      for path, names in _by_store(more).items()])
    test_cases = [c for c in cases if c.endswith("-5")]       # one case of every packing
    val_cases = [c for c in cases if c.endswith("-4")]
    first = _first_frames(store, size)
    for path, names in _by_store(more).items():
        first |= _first_frames(path, size, names)
    res = {"settings": {"size": size, "every": every, "epochs": epochs, "batch": batch, "lr": lr, "seed": seed,
                        "frames": int(len(table1.x)), "test_cases": test_cases, "validation_cases": val_cases,
                        "extra_hoppers": sorted(more), "extra_frames": int(len(f.x) - len(table1.x)), "device": str(dev)},
           "machine": _machine(dev), "splits": {}}
    for split, (tr, va, te) in (("random_frames", frame_data.random_split(len(table1.x), seed)),  # Table 1's frames come first in f
                                ("leave_cases_out", frame_data.case_split(f.case, test_cases, val_cases))):
        say(f"- AlexNet-FC, {split}: train {len(tr)}, validation {len(va)}, test {len(te)} frames")
        if not (len(tr) and len(va) and len(te)):
            say("  an empty part (leave-cases-out holds out the -5 cases and validates on the -4 cases): skipped")
            continue
        model, scaling, seconds = _train(f"alexnet_fc_{split}", cnn.AlexNetFC, f, tr, va, epochs, batch, lr, seed,
                                         Path(checkpoints or out), say, dev)
        pred = training.predict(model, f.x[te], scaling)
        train_cases = sorted(set(f.case[tr]))
        base, law = _beverloo_per_frame(f, train_cases, first)
        row = {"all": frame_data.scores(f.remaining[te], pred), "baseline_all": frame_data.scores(f.remaining[te], base[te]),
               "train_seconds": seconds, "law": law, "per_packing": {},
               "test": {"case": f.case[te].tolist(), "remaining": f.remaining[te].tolist(), "predicted": pred.tolist(),
                        "baseline": base[te].tolist()}}
        for pk in PACKINGS:
            m = np.array([packing_of(c) == pk for c in f.case[te]])
            if m.sum() > 1:
                row["per_packing"][pk] = {"net": frame_data.scores(f.remaining[te][m], pred[m]),
                                          "baseline": frame_data.scores(f.remaining[te][m], base[te][m])}
        res["splits"][split] = row
        say(f"  R^2 {row['all']['r2']:.3f}, relative error {row['all']['relative_error']:.3f} "
            f"(baseline {row['baseline_all']['r2']:.3f}, {row['baseline_all']['relative_error']:.3f})")
    _save(out / "point_to_point.json", res)
    return res


def fold_of(case: str) -> str:
    """A case's fold for leave-cases-out: its index within its packing (A-3 -> "3")."""
    return case.rsplit("-", 1)[1]


def _nrrp_windows(f: frame_data.Frames, window: int, stride: int = 1, base: np.ndarray | None = None):
    """Windows of the case's frames and their targets: the NRRP, or its residual on `base` (the
    chosen gauge's reading of every frame)."""
    y = f.nrrp if base is None else f.nrrp - base
    return training.windows(f.x, y.astype(np.float32), window, stride)


def _read_later(model, f: frame_data.Frames, k: int, window: int, scaling: dict, base: np.ndarray | None = None) -> np.ndarray:
    """The NRRP of every frame from k on, read from the window of `window` frames ending there (the
    network's output, plus base[k:] when it learnt the residual on a gauge)."""
    xr, _ = training.windows(f.x[k - window + 1:], f.nrrp[k - window + 1:], window)
    out = training.predict(model, xr, scaling).reshape(len(xr), window)[:, -1]
    return np.clip(out + (0.0 if base is None else base[k:]), 0.0, 1.0)


def _pretrained_weights(run: Path, fold: str) -> dict:
    """The best-validation weights of fold `fold`'s pretraining in an earlier `process` run's folder."""
    try:
        return training.best_weights(run / f"lstm_pretrain_fold{fold}.pt")
    except ValueError as exc:
        raise ValueError(f"warm start: {exc}; the run must be a pretrained `process` run on the same store") from exc


def _window_mse(model, xw, yw, scaling: dict) -> float:
    return float(np.mean((training.predict(model, xw, scaling).reshape(yw.shape) - yw) ** 2))


def extra_hoppers(stores, table1: list[str], per_packing: int | None = None) -> dict:
    """{case: store} of the hoppers in `stores` (pydem images hoppers), the first `per_packing` of
    each packing when given. A name that is also a Table 1 case, or in two stores, is refused:
    a test case must never reach the training."""
    found: dict = {}
    for path in stores or ():
        for c in FrameStore(path).cases():
            if c in table1 or c in found:
                raise ValueError(f"{path}: {c} is {'a Table 1 case' if c in table1 else 'in ' + str(found[c])} too; "
                                 f"extra hoppers must be other hoppers")
            found[c] = path
    if per_packing is not None:
        keep = {c for pk in PACKINGS for c in sorted(x for x in found if packing_of(x) == pk)[:per_packing]}
        found = {c: v for c, v in found.items() if c in keep}
    return found


def _by_store(more: dict) -> dict:
    """{store: its cases, sorted} of extra_hoppers' {case: store}."""
    out: dict = {}
    for c, path in sorted(more.items()):
        out.setdefault(path, []).append(c)
    return out


def process(store, out, size: int = 64, window: int = 8, epochs: int | None = None, lr: float = 3e-4, seed: int = 0,
            fraction: float = 0.2, protocol: str = "pretrained", stride: int = 4, finetune_epochs: int = 10,
            device: str = "auto", inputs: str = "grey", extra=(), extra_per_packing: int | None = None,
            target: str = "nrrp", warm_start=None, say=print) -> dict:
    """NRRP(t) of each case from its frames, predicted beyond the first `fraction` of them.

    protocol "per-case" (seed 001's): the CNN-LSTM trained on windows of the case's first
    `fraction` of frames only (`epochs`, default 40; the last fifth of them for validation).
    protocol "pretrained": cases in five folds by their index within the packing (A-1, B1-1 ...
    in fold 1); for each fold the CNN-LSTM is trained on the whole sequences of three other folds
    (windows every `stride` frames; `epochs`, default 8), validated on the fourth, and then, for
    each of the fold's cases, fine-tuned on windows of that case's first `fraction` (lr / 10,
    `finetune_epochs`), the fine-tuned weights kept only where they lower the error on the
    case's own held-back early windows. The zero-shot prediction (no frame of the case seen) is
    reported beside it. In both, each later frame's NRRP is read from the window ending at it.
    `inputs`: what the network sees of a frame (frame_data.INPUTS): the grey frame, seed 001's, or
    its two species (fine, coarse) as separate channels.

    Pretrained only: `extra`, frame stores of more hoppers (pydem images hoppers; the first
    `extra_per_packing` of each packing when given), join every fold's pretraining and the gauges'
    calibration — never its validation or test. `target` "residual": the network learns the NRRP
    minus the reading of the gauge chosen, per packing, from the fold's training hoppers alone
    (gauges.chosen; on a training hopper the gauge calibrated on the others, gauges.cross_fitted),
    and adds that reading back. `warm_start`: the --out folder of an earlier pretrained run on the
    same store, inputs and size; each fold's network starts from that run's pretrained weights for
    the fold (its best validation epoch) instead of at random — a network pretrained on the NRRP
    already reads the fill from the frames, where one learning the small residual from scratch may
    settle on its mean."""
    if protocol not in ("pretrained", "per-case"):
        raise ValueError(f"protocol: 'pretrained' or 'per-case', got {protocol!r}")
    if target not in ("nrrp", "residual"):
        raise ValueError(f"target: 'nrrp' or 'residual', got {target!r}")
    if protocol != "pretrained" and (extra or target != "nrrp"):
        raise ValueError("extra hoppers and the residual target go with the pretrained protocol")
    if warm_start is not None and protocol != "pretrained":
        raise ValueError("a warm start goes with the pretrained protocol")
    epochs = epochs if epochs is not None else (8 if protocol == "pretrained" else 40)
    out = Path(out)
    dev = training.pick_device(device)
    cases = FrameStore(store).cases()
    more = extra_hoppers(extra, cases, extra_per_packing)
    res = {"settings": {"size": size, "window": window, "epochs": epochs, "lr": lr, "seed": seed, "fraction": fraction,
                        "protocol": protocol, "inputs": inputs, "gradient_clip": LSTM_CLIP, "device": str(dev)}
           | ({"stride": stride, "finetune_epochs": finetune_epochs, "finetune_lr": lr / 10, "target": target,
               "extra_stores": [str(x) for x in extra or ()], "extra_hoppers": sorted(more)}
              | ({"warm_start": str(warm_start)} if warm_start is not None else {})
              if protocol == "pretrained" else {}),
           "machine": _machine(dev), "cases": {}}
    data = {c: frame_data.load_frames(more.get(c, store), cases=[c], size=size, inputs=inputs) for c in cases + list(more)}
    nrrp = {c: d.nrrp for c, d in data.items()}
    folds = sorted({fold_of(c) for c in cases})
    pretrained, g_in, fold_train = {}, {}, {}
    if protocol == "pretrained":
        if len(folds) < 3:
            raise ValueError(f"{store}: cases in {len(folds)} fold(s); the pretrained protocol needs three or more")
        g_in = gauges.inputs(store, cases, size)
        for path, names in _by_store(more).items():
            g_in |= gauges.inputs(path, names, size)
        first = {c: first_part(len(d.x), fraction, window) for c, d in data.items()}
        for fold in folds:
            val_fold = validation_fold(fold, folds)
            train = [c for c in cases if fold_of(c) in pretraining_folds(fold, folds)] + list(more)
            val = [c for c in cases if fold_of(c) == val_fold]
            base, chosen = {}, {}
            if target == "residual":  # per packing: the gauge chosen on the fold's training hoppers
                for pk in PACKINGS:
                    tr_pk = [c for c in train if packing_of(c) == pk]
                    if tr_pk:
                        chosen[pk] = gauges.chosen(g_in, nrrp, tr_pk, first)
                        base |= gauges.cross_fitted(chosen[pk], g_in, nrrp, tr_pk)
                        base |= {c: gauges.readings(c, tr_pk, g_in, nrrp, 0)[chosen[pk]] for c in val if packing_of(c) == pk}
            fold_train[fold] = (train, chosen)
            tr = [_nrrp_windows(data[c], window, stride, base.get(c)) for c in train if len(data[c].x) >= window]
            va = [_nrrp_windows(data[c], window, stride, base.get(c)) for c in val if len(data[c].x) >= window]
            xt, yt = np.concatenate([a for a, _ in tr]), np.concatenate([b for _, b in tr])
            xv, yv = np.concatenate([a for a, _ in va]), np.concatenate([b for _, b in va])
            say(f"- fold {fold}: pretraining on {len(xt)} windows of {len(train)} hoppers' whole discharges"
                + (f" ({len(more)} of them extra)" if more else "") + f" (validation: fold {val_fold}, {len(xv)} windows)"
                + (f"; learning the residual on the gauge chosen per packing: {chosen}" if chosen else ""))
            torch.manual_seed(seed)
            model = cnn.CNNLSTM(in_channels=xt.shape[2])
            if warm_start is not None:
                try:
                    model.load_state_dict(_pretrained_weights(Path(warm_start), fold))
                except RuntimeError as exc:  # another network's shapes (inputs, size)
                    raise ValueError(f"warm start from {warm_start}: its networks do not fit these inputs ({exc})") from exc
            model = model.to(dev)
            t0 = time.perf_counter()
            scaling = training.fit(model, xt, yt, xv, yv, epochs=epochs, batch=8, lr=lr, seed=seed, clip=LSTM_CLIP,
                                   checkpoint=out / f"lstm_pretrain_fold{fold}.pt", progress=EpochProgress(say))
            pretrained[fold] = (model, scaling, time.perf_counter() - t0)
    for case in cases:
        f = data[case]
        k = first_part(len(f.x), fraction, window)
        if len(f.x) < k + window:
            say(f"  {case}: {len(f.x)} frames, too few for windows of {window}; skipped")
            continue
        row = {"frames": int(len(f.x)), "trained_on": int(k)}
        base = None
        if protocol == "pretrained":
            train, chosen = fold_train[fold_of(case)]
            same = [c for c in train if packing_of(c) == packing_of(case)]
            if packing_of(case) in chosen:
                row["gauge"] = chosen[packing_of(case)]
                base = gauges.readings(case, same, g_in, nrrp, 0)[row["gauge"]]
        xw, yw = _nrrp_windows(f.take(slice(None, k)), window, base=None if base is None else base[:k])
        n_val = max(1, len(xw) // 5)
        t0 = time.perf_counter()
        if protocol == "per-case":
            torch.manual_seed(seed)
            model = cnn.CNNLSTM(in_channels=f.x.shape[1]).to(dev)
            scaling = training.fit(model, xw[:-n_val], yw[:-n_val], xw[-n_val:], yw[-n_val:], epochs=epochs, batch=8,
                                   lr=lr, seed=seed, clip=LSTM_CLIP, checkpoint=out / f"lstm_{case}.pt")
        else:
            base_model, scaling, pre_seconds = pretrained[fold_of(case)]
            row["zero_shot"] = frame_data.scores(f.nrrp[k:], _read_later(base_model, f, k, window, scaling, base))
            model = copy.deepcopy(base_model)
            training.fit(model, xw[:-n_val], yw[:-n_val], xw[-n_val:], yw[-n_val:], epochs=finetune_epochs, batch=8,
                         lr=lr / 10, seed=seed, clip=LSTM_CLIP, checkpoint=out / f"lstm_finetune_{case}.pt",
                         scaling=scaling)
            before, after = (_window_mse(m, xw[-n_val:], yw[-n_val:], scaling) for m in (base_model, model))
            row["finetune_kept"] = bool(after < before)
            if not row["finetune_kept"]:
                model = base_model
            row["pretrain_seconds"] = pre_seconds
        row["train_seconds"] = time.perf_counter() - t0
        pred = _read_later(model, f, k, window, scaling, base)
        truth = f.nrrp[k:]
        constant = baselines.constant_rate_nrrp(f.time, f.nrrp, fraction)[k:]
        row |= {"net": frame_data.scores(truth, pred), "baseline": frame_data.scores(truth, constant), "time": f.time[k:].tolist(),
                "nrrp": truth.tolist(), "predicted": pred.tolist(), "baseline_nrrp": constant.tolist()}
        if protocol == "pretrained":
            row |= gauges.scored(case, same, g_in, nrrp, k)
        res["cases"][case] = row
        say(f"  {case}: relative error {row['net']['relative_error']:.3f} "
            + (f"(zero-shot {row['zero_shot']['relative_error']:.3f}) " if "zero_shot" in row else "")
            + f"(constant rate {row['baseline']['relative_error']:.3f}"
            + "".join(f", {g.replace('_', ' ')} gauge {row[g]['relative_error']:.3f}" for g in gauges.GAUGES if g in row) + ")")
    keys = ("net", "baseline") + (("zero_shot",) + gauges.GAUGES if protocol == "pretrained" else ())
    res["per_packing"] = {pk: {key: float(np.mean(errs)) for key in keys
                               if (errs := [r[key]["relative_error"] for c, r in res["cases"].items()
                                            if packing_of(c) == pk and key in r])}
                          for pk in PACKINGS if any(packing_of(c) == pk for c in res["cases"])}
    _save(out / "process.json", res)
    return res


def first_part(frames: int, fraction: float, window: int) -> int:
    """How many of a case's first frames the process experiment trains on (the rest it predicts)."""
    return max(window + 2, int(round(fraction * frames)))


def validation_fold(fold: str, folds: list[str]) -> str:
    """The fold that validates the pretraining for a fold's cases: the next one."""
    return folds[(folds.index(fold) + 1) % len(folds)]


def pretraining_folds(fold: str, folds: list[str]) -> list[str]:
    """The folds a case's network pretrains on (the pretrained protocol): all but the case's own
    and its validation fold."""
    return [f for f in folds if f not in (fold, validation_fold(fold, folds))]


def _save(path: Path, res: dict):
    path.parent.mkdir(parents=True, exist_ok=True)
    res["date"] = time.strftime("%Y-%m-%d")
    path.write_text(json.dumps(res, indent=1, default=float))
