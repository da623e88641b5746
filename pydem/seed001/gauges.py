"""The image gauges of seed 001's NRRP study: hand-made readers of the remaining-particle ratio
from a frame, calibrated by least squares on the whole discharges of training hoppers of the same
packing — no learning beyond that (docs/seed001.md, "Two image gauges"):

- `fill_level`: a cubic of the frame's grey fill fraction (baselines.fill_level_nrrp);
- `species`: the count from each species' fill, quadratic in each, weighted by the fines' share
  of the count (baselines.species_gauge_nrrp; of degrees 1-3, fitted per packing or over all, the
  quadratic per packing erred least on the 1 ms frame set).

They stand beside the CNN-LSTM as its baselines, and one of them — the one `chosen` from the
training hoppers alone — is the baseline whose residual the network may learn instead of the
count itself (experiments.process, target "residual")."""
from __future__ import annotations

import json

import numpy as np

from ..rigs.table1 import row_from_json
from . import baselines, frame_data
from .store import FrameStore

GAUGES = ("fill_level", "species")
SPECIES_DEGREE = 2


def inputs(store, cases, size: int) -> dict:
    """What the gauges read of each case's frames: its grey fill fraction at the network's frame
    size (baselines.fill_fraction) and the fill of each species (baselines.species_fill, from the
    stored 224 x 224 frames), with the fines' share of its count (from Table 1, or for a hopper
    drawn like them from the row stored with it)."""
    st, out = FrameStore(store), {}
    for c in cases:
        d = st.read_case(c)
        raw = d["frames"]
        row = row_from_json(json.loads(d["row"])) if "row" in d else None
        grey = frame_data.shrink(raw, size)
        out[c] = {"fill": baselines.fill_fraction(grey, grey[0]), "species": baselines.species_fill(raw),
                  "fines_share": baselines.fines_count_share(c, row)}
    return out


def readings(case: str, train: list[str], gauge_inputs: dict, nrrp: dict, k: int) -> dict:
    """{gauge: the case's NRRP from frame k on} with both gauges calibrated on `train`'s whole
    discharges (gauge_inputs: `inputs`; nrrp: each training case's NRRP series)."""
    g = gauge_inputs
    design = lambda c: baselines.species_design(g[c]["species"], g[c]["fines_share"], SPECIES_DEGREE)  # noqa: E731
    y = np.concatenate([nrrp[c] for c in train])
    return {"fill_level": baselines.fill_level_nrrp(np.concatenate([g[c]["fill"] for c in train]), y, g[case]["fill"][k:]),
            "species": baselines.species_gauge_nrrp(np.concatenate([design(c) for c in train]), y, design(case)[k:])}


def scored(case: str, train: list[str], gauge_inputs: dict, nrrp: dict, k: int) -> dict:
    """Both gauges' scores on the case from frame k on, calibrated on `train`, and their readings
    (as `<gauge>_nrrp` lists): what the process experiment reports beside its network."""
    row = readings(case, train, gauge_inputs, nrrp, k) if train else {}
    truth = nrrp[case][k:]
    return {name: frame_data.scores(truth, v) for name, v in row.items()} | {f"{name}_nrrp": v.tolist() for name, v in row.items()}


def chosen(gauge_inputs: dict, nrrp: dict, train: list[str], first: dict) -> str:
    """The gauge a user would pick from the training hoppers alone: the one with the smaller mean
    error when each training hopper, from its first[c] frames on, is read by the gauge calibrated
    on the others. With a single training hopper: the fill level."""
    if len(train) < 2:
        return "fill_level"
    errs = [{g: frame_data.scores(nrrp[c][first[c]:], v)["relative_error"]
             for g, v in readings(c, [t for t in train if t != c], gauge_inputs, nrrp, first[c]).items()} for c in train]
    return min(GAUGES, key=lambda g: np.mean([e[g] for e in errs]))


def cross_fitted(gauge: str, gauge_inputs: dict, nrrp: dict, train: list[str]) -> dict:
    """{c: c's whole NRRP series as the gauge reads it, calibrated on the other training hoppers}:
    the baseline a network learns its residual on, as poor on a training hopper as on a new one
    (calibrated on c itself it would be far better, and the network would learn too small a
    residual). With a single training hopper: calibrated on it."""
    return {c: readings(c, [t for t in train if t != c] or [c], gauge_inputs, nrrp, 0)[gauge] for c in train}
