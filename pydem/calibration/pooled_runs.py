"""A rig's other stores pooled into a diagnosis store's surrogates.

A campaign over fewer parameters at the same rig and preset (say the three-parameter angle-of-
repose campaign for seed 000's materials beside the six-parameter diagnosis store) ran points of
the diagnosis store's box: each parameter it did not vary had the value its preset gives (an
effect that was off: the effect's neutral value). Its runs therefore train the same surrogates,
once mapped into the diagnosis store's parameter columns. Stores are pooled only when that
mapping is exact: same rig, preset, rig protocol and physics, the same resolved configuration
apart from the varied keys, and every fixed value inside the diagnosis store's ranges."""
from __future__ import annotations

import numpy as np

from ..campaign.runner import NOT_PHYSICS, resolved_config
from ..rigs.config import get_value


class PoolError(ValueError):
    """Two stores of one rig that cannot be pooled (the reason named)."""


def fixed_values(main, other) -> dict[str, float]:
    """{parameter of `main` that `other` did not vary: the value it had in `other`'s runs}."""
    cfg = other.spec.config({})
    return {name: float(get_value(cfg, name)) for name in main.spec.names if name not in other.spec.ranges}


def check_poolable(main, other) -> None:
    """Raises PoolError unless `other`'s runs are points of `main`'s box (see the module text)."""
    where = f"{other.path.name} cannot join {main.path.name}"
    if other.spec.rig != main.spec.rig or other.spec.preset != main.spec.preset:
        raise PoolError(f"{where}: rig/preset {other.spec.rig}/{other.spec.preset} vs {main.spec.rig}/{main.spec.preset}")
    if other.rig_protocol != main.rig_protocol or other.physics != main.physics:
        raise PoolError(f"{where}: rig protocol {other.rig_protocol} / libdem {other.physics} vs "
                        f"{main.rig_protocol} / {main.physics}")
    extra = [n for n in other.spec.names if n not in main.spec.ranges]
    if extra:
        raise PoolError(f"{where}: it varies {', '.join(extra)}, which {main.path.name} does not")
    varied = {k.split(".")[-1] for k in list(main.spec.ranges) + list(other.spec.ranges)}
    a = main.provenance.get("rig_config") or resolved_config(main.spec)
    b = other.provenance.get("rig_config") or resolved_config(other.spec)
    differ = [k for k in sorted(set(a) & set(b)) if k not in NOT_PHYSICS and k != "params.effects"
              and k.split(".")[-1] not in varied and a[k] != b[k]]
    if differ:
        raise PoolError(f"{where}: the rig differs in " + ", ".join(f"{k} ({b[k]} vs {a[k]})" for k in differ))
    for name, v in fixed_values(main, other).items():
        lo, hi = main.spec.ranges[name]
        if not lo <= v <= hi:
            raise PoolError(f"{where}: its {name} = {v:g} lies outside {main.path.name}'s range [{lo:g}, {hi:g}]")
    for name, (lo, hi) in other.spec.ranges.items():
        mlo, mhi = main.spec.ranges[name]
        if lo < mlo or hi > mhi:
            raise PoolError(f"{where}: its {name} range [{lo:g}, {hi:g}] exceeds [{mlo:g}, {mhi:g}]")


def pooled_params(main, other) -> np.ndarray:
    """`other`'s run parameters (every run, in its order) in `main`'s parameter columns."""
    fixed = fixed_values(main, other)
    cols = [other.params[:, other.spec.names.index(n)] if n in other.spec.ranges
            else np.full(len(other.params), fixed[n]) for n in main.spec.names]
    return np.column_stack(cols) if cols else np.empty((len(other.params), 0))
