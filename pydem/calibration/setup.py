"""What a diagnosis works with, loaded once: the campaign stores (one per rig), their surrogates,
the parameter box they share and the candidates they cover; and measurement files turned into
observations (rows the surrogates cannot represent are reported, never matched elsewhere)."""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path

from ..campaign import Campaign
from ..campaign.store import check_same_physics
from ..measurements import load as load_measurements
from .candidates import BASE_PARAMETERS, Candidate, registry
from .pooled_runs import check_poolable, joined_box
from .quantities import Observation, ObservationError, observation
from .similarity import MATERIAL_TEST, MaterialProperties, Scaling
from .store_data import preset_conditions, replicate_stores
from .surrogates import attach_run_correlations, load_or_train

# the shipped diagnosis stores, one per rig (and stores pooled into one, open_store_groups): at the
# rigs' tiny presets (the CI's, quick to remake) and at their default presets (the ones
# measurements made with the default rigs are compared with)
TINY_STORES = ("data/campaigns/diag_ring_shear_tiny.h5", "data/campaigns/diag_aor_tiny.h5",
               "data/campaigns/diag_hopper_tiny.h5")
# (aor_jku.h5: seed 000's three-parameter angle-of-repose campaign, pooled into the angle-of-repose
# surrogates; diag_hopper_default.h5: the hopper's two-size runs, pooled into its size-spread store;
# *_axes.h5: runs on the base model and its one-effect axes, pooled into their rig's store; all
# their runs are points of the diagnosis box, pooled_runs.py)
DEFAULT_STORES = ("data/campaigns/diag_ring_shear_default.h5", "data/campaigns/diag_ring_shear_default_axes.h5",
                  "data/campaigns/diag_aor_default.h5", "data/campaigns/aor_jku.h5",
                  "data/campaigns/diag_aor_default_axes.h5", "data/campaigns/diag_hopper_default_spread.h5",
                  "data/campaigns/diag_hopper_default.h5", "data/campaigns/diag_hopper_default_axes.h5")


def shipped_stores(preset: str) -> list[str]:
    """The diagnosis stores of a preset as `pydem diagnose` loads them (DEFAULT_STORES, TINY_STORES:
    the pooled ones included, so nets are trained and cached for the same training sets), else
    data/campaigns/diag_<rig>_<preset>.h5 of each rig; paths relative to the repository."""
    shipped = {"default": DEFAULT_STORES, "tiny": TINY_STORES}
    return list(shipped.get(preset, [f"data/campaigns/diag_{r}_{preset}.h5" for r in ("ring_shear", "aor", "hopper")]))


@dataclass
class Setup:
    stores: dict            # rig -> CampaignStore
    nets: dict              # Quantity -> QuantityNet
    ranges: dict            # parameter -> (lo, hi), the box every store covers
    candidates: list[Candidate]
    physics: str            # libdem major.minor of the runs
    defaults: dict = field(default_factory=dict)  # condition -> preset value (rows that do not give it)
    pooled: dict = field(default_factory=dict)    # rig -> the stores pooled into its surrogates

    def scaling(self, material: MaterialProperties) -> Scaling:
        """How a material's rows are compared with these stores (similarity.py): its particle
        density, size and modulus against theirs."""
        params = next(iter(self.stores.values())).spec.config({}).params
        sizes = {rig: store_diameter(st.spec.config({})) for rig, st in self.stores.items()}
        return Scaling(material, float(params.density), float(params.youngs_modulus), sizes)

    def for_material(self, scaling: Scaling) -> "Setup":
        """This setup with the material's size spread as the base model's (Scaling.candidates)."""
        return dataclasses.replace(self, candidates=scaling.candidates(self.candidates, self.ranges))

    def store_provenance(self) -> dict:
        """{rig: path, commit and libdem of its store, and the paths of the stores pooled in}, for reports."""
        return {r: {"path": str(s.path), "commit": s.provenance.get("git_commit"), "libdem": s.provenance.get("libdem"),
                    "pooled": [str(o.path) for o in self.pooled.get(r, [])]} for r, s in self.stores.items()}


def store_diameter(cfg) -> float:
    """The mass-mean sphere diameter of a rig's configuration: its `diameter`, or the hopper's two
    species weighted by the fine volume fraction."""
    if hasattr(cfg, "diameter"):
        return float(cfg.diameter)
    return float(cfg.fine_fraction * cfg.d_small + (1.0 - cfg.fine_fraction) * cfg.d_large)


def _relative_volume(store, stores) -> float:
    """The store's box volume relative to the union of the stores' ranges, parameter by parameter."""
    vol = 1.0
    for name, (lo, hi) in store.spec.ranges.items():
        los = [st.spec.ranges[name][0] for st in stores if name in st.spec.ranges]
        his = [st.spec.ranges[name][1] for st in stores if name in st.spec.ranges]
        vol *= (hi - lo) / max(max(his) - min(los), 1e-300)
    return vol


def open_store_groups(paths) -> dict:
    """{rig: (main store, [stores pooled into it], the box they cover together)}: per rig the store
    that varies the most parameters over the largest box (in units of each range's own width: the
    product of the widths relative to the union box) is the main one; every other store of that rig
    must be poolable into it (pooled_runs.py, else a PoolError naming why), and stores that extend
    its box must fill the joined box together (pooled_runs.joined_box)."""
    by_rig = {}
    for p in paths:
        st = Campaign.open(p).store
        by_rig.setdefault(st.spec.rig, []).append(st)
    if not by_rig:
        raise ValueError("no campaign stores given")
    groups = {}
    for rig, sts in by_rig.items():
        # a store whose design holds parameters at neutral values (one-effect axes) is never the main one
        main = max(sts, key=lambda st: (len(st.spec.ranges), not st.spec.neutral, _relative_volume(st, sts)))
        others = [st for st in sts if st is not main]
        for o in others:
            check_poolable(main, o)
        groups[rig] = (main, others, joined_box(main, others))
    return groups


def open_stores(paths) -> dict:
    """{rig: the main store of the rig} (open_store_groups)."""
    return {rig: main for rig, (main, _, _) in open_store_groups(paths).items()}


def load_setup(paths, say=print, retrain: bool = False) -> Setup:
    groups = open_store_groups(paths)
    stores = {rig: main for rig, (main, _, _) in groups.items()}
    physics = check_same_physics(stores.values(), "diagnose with")
    nets, ranges, defaults = {}, {}, {}
    for rig, st in stores.items():
        missing = [n for n in BASE_PARAMETERS if n not in st.spec.ranges]
        if missing:
            raise ValueError(f"{st.path}: the diagnosis needs the base parameters {', '.join(missing)} varied")
        rig_nets = load_or_train(st, say, retrain, pooled=groups[rig][1])
        attach_run_correlations(list(rig_nets.values()), replicate_stores(st, groups[rig][1]), say=lambda *a: None)
        nets.update(rig_nets)
        for name, (lo, hi) in groups[rig][2].items():
            if name in ranges:
                lo, hi = max(lo, ranges[name][0]), min(hi, ranges[name][1])
            ranges[name] = (lo, hi)
        defaults.update(preset_conditions(st))
    cands = [c for c in registry() if c.parameter in ranges]
    return Setup(stores, nets, ranges, cands, physics, defaults, {r: others for r, (_, others, _) in groups.items()})


def observations_from_file(path: str | Path, material: str, setup: Setup) -> tuple[list[Observation], list[str]]:
    """(usable observations, one line per row left out and why) of a measurement file."""
    return observations_of(load_measurements(path, material), setup, str(path), material)


# how far past a campaign's declared range a condition is still compared (a fraction of the range):
# a smooth net moves little over 2 %, and labs round (seed 000's programme pre-shears at 10.07 kPa)
RANGE_TOLERANCE = 0.02


def declared_range(setup: Setup, rig: str, condition: str) -> tuple[float, float] | None:
    """The range of a condition that the rig's campaigns declare (the main store's and those pooled
    into it, joined): a condition inside it is inside the stores, whatever the design's extreme points."""
    spans = [st.spec.ranges[condition] for st in [setup.stores[rig], *setup.pooled.get(rig, [])]
             if condition in st.spec.ranges]
    return (min(a for a, _ in spans), max(b for _, b in spans)) if spans else None


def observations_of(measurements: list, setup: Setup, source: str, material: str,
                    scaling: Scaling | None = None) -> tuple[list[Observation], list[str]]:
    """(usable observations, one line per row left out and why) of a material's measurement rows
    (measurements.load), read from `source`, compared with the stores through `scaling` (default:
    setup.scaling of these rows)."""
    rows = [m for m in measurements if m.use == "calibrate" and m.test != MATERIAL_TEST]
    scaling = scaling if scaling is not None else setup.scaling(MaterialProperties.from_rows(measurements))
    out, skipped = [], []
    for m in rows:
        try:
            o = observation(m, setup.defaults)
        except ObservationError as exc:
            skipped.append(str(exc))
            continue
        try:
            o = scaling.observation(o)
        except ObservationError as exc:
            skipped.append(f"line {m.line}: {exc}")
            continue
        if o.quantity not in setup.nets:
            skipped.append(f"line {m.line}: {m.label}: no campaign store offers {o.quantity.key} "
                           f"(stores: {', '.join(sorted(setup.stores))})")
            continue
        net = setup.nets[o.quantity]
        outside, near = [], []
        for k, v in o.conditions.items():
            if k not in net.input_names:
                continue
            span = declared_range(setup, o.quantity.rig, k)
            lo, hi = span if span else (net.lo[net.input_names.index(k)], net.hi[net.input_names.index(k)])
            past = max(lo - v, v - hi, 0.0) / (hi - lo)
            if past > RANGE_TOLERANCE:
                outside.append(f"{k}={v:g} outside [{lo:g}, {hi:g}]")
            elif past > 0:
                near.append((k, f"{k}={v:g} lies {100 * past:.1f} % of the range past the campaign's [{lo:g}, {hi:g}]"))
        if outside:
            skipped.append(f"line {m.line}: {m.label}: condition {', '.join(outside)} (the campaign's declared range, "
                           f"{100 * RANGE_TOLERANCE:g} % past it allowed){scaling.condition_note(o)}")
            continue
        if near:
            o = dataclasses.replace(o, extrapolated=dict(near))
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
        raise ObservationError(f"{source}: no row of {material!r} can be compared with the campaigns "
                               f"(they offer {offered}); " + "; ".join(skipped))
    return out, skipped
