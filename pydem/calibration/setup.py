"""What a diagnosis works with, loaded once: the campaign stores (one per rig), their surrogates,
the parameter box they share and the candidates they cover; and measurement files turned into
observations (rows the surrogates cannot represent are reported, never matched elsewhere)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from ..campaign import Campaign
from ..campaign.store import check_same_physics
from ..measurements import load as load_measurements
from .candidates import BASE_PARAMETERS, Candidate, registry
from .quantities import Observation, ObservationError, observation, preset_conditions
from .surrogates import load_or_train

# the shipped diagnosis stores, one per rig: at the rigs' tiny presets (the CI's, quick to remake)
# and at their default presets (the ones measurements made with the default rigs are compared with)
TINY_STORES = ("data/campaigns/diag_ring_shear_tiny.h5", "data/campaigns/diag_aor_tiny.h5",
               "data/campaigns/diag_hopper_tiny.h5")
DEFAULT_STORES = ("data/campaigns/diag_ring_shear_default.h5", "data/campaigns/diag_aor_default.h5",
                  "data/campaigns/diag_hopper_default.h5")


@dataclass
class Setup:
    stores: dict            # rig -> CampaignStore
    nets: dict              # Quantity -> QuantityNet
    ranges: dict            # parameter -> (lo, hi), the box every store covers
    candidates: list[Candidate]
    physics: str            # libdem major.minor of the runs
    defaults: dict = field(default_factory=dict)  # condition -> preset value (rows that do not give it)


def open_stores(paths) -> dict:
    """{rig: CampaignStore}, one store per rig (two for one rig are refused)."""
    stores = {}
    for p in paths:
        st = Campaign.open(p).store
        if st.spec.rig in stores:
            raise ValueError(f"two stores for rig {st.spec.rig}: {stores[st.spec.rig].path} and {p}")
        stores[st.spec.rig] = st
    if not stores:
        raise ValueError("no campaign stores given")
    return stores


def load_setup(paths, say=print, retrain: bool = False) -> Setup:
    stores = open_stores(paths)
    physics = check_same_physics(stores.values(), "diagnose with")
    nets, ranges, defaults = {}, {}, {}
    for rig, st in stores.items():
        missing = [n for n in BASE_PARAMETERS if n not in st.spec.ranges]
        if missing:
            raise ValueError(f"{st.path}: the diagnosis needs the base parameters {', '.join(missing)} varied")
        nets.update(load_or_train(st, say, retrain))
        for name, (lo, hi) in st.spec.ranges.items():
            if name in ranges:
                lo, hi = max(lo, ranges[name][0]), min(hi, ranges[name][1])
            ranges[name] = (lo, hi)
        defaults.update(preset_conditions(st))
    cands = [c for c in registry() if c.parameter in ranges]
    return Setup(stores, nets, ranges, cands, physics, defaults)


def observations_from_file(path: str | Path, material: str, setup: Setup) -> tuple[list[Observation], list[str]]:
    """(usable observations, one line per row left out and why)."""
    rows = [m for m in load_measurements(path, material) if m.use == "calibrate"]
    out, skipped = [], []
    for m in rows:
        try:
            o = observation(m, setup.defaults)
        except ObservationError as exc:
            skipped.append(str(exc))
            continue
        if o.quantity not in setup.nets:
            skipped.append(f"line {m.line}: {m.label}: no campaign store offers {o.quantity.key} "
                           f"(stores: {', '.join(sorted(setup.stores))})")
            continue
        net = setup.nets[o.quantity]
        outside = [f"{k}={v:g} outside [{net.lo[net.input_names.index(k)]:g}, {net.hi[net.input_names.index(k)]:g}]"
                   for k, v in o.conditions.items() if k in net.input_names
                   and not net.lo[net.input_names.index(k)] <= v <= net.hi[net.input_names.index(k)]]
        if outside:
            skipped.append(f"line {m.line}: {m.label}: condition {', '.join(outside)} (the campaign's range)")
            continue
        # a condition the store does not vary: its runs all have one value, and the row must have it too
        other = [f"{k}={v:g} but the campaign ran at {setup.defaults[k]:g} only" for k, v in o.conditions.items()
                 if k not in net.input_names and k in setup.defaults
                 and not math.isclose(v, setup.defaults[k], rel_tol=1e-6)]
        if other:
            skipped.append(f"line {m.line}: {m.label}: measured at {', '.join(other)} (use a store that varies it)")
            continue
        out.append(o)
    if not out:
        offered = ", ".join(sorted(q.key for q in setup.nets))
        raise ObservationError(f"{path}: no row of {material!r} can be compared with the campaigns "
                               f"(they offer {offered}); " + "; ".join(skipped))
    return out, skipped
