"""A rig's other stores pooled into a diagnosis store's surrogates.

A campaign over fewer parameters at the same rig and preset (say the three-parameter angle-of-
repose campaign for seed 000's materials beside the six-parameter diagnosis store) ran points of
the diagnosis store's box: each parameter it did not vary had the value its preset gives (an
effect that was off: the effect's neutral value). Its runs therefore train the same surrogates,
once mapped into the diagnosis store's parameter columns. Stores are pooled only when that
mapping is exact: same rig, preset, rig protocol and physics, the same resolved configuration
apart from the varied keys, and every fixed value inside the diagnosis store's ranges.

A store may also extend the box: a slab past one edge (pre-shear 10-20 kPa beside a 0.5-10 kPa
store, every other range the same) spends its runs only where the box grows. The rig's box is then
the stores' joined ranges, provided their boxes fill it together — a corner that no store ran would
be extrapolation that the box claims to cover (joined_box)."""
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


def joined_box(main, others) -> dict[str, tuple[float, float]]:
    """The box a rig's stores cover together: `main`'s ranges, joined with those of the stores that
    extend them. Raises PoolError when the boxes of the stores that vary every parameter (designs over
    the whole box, not held on axes) leave part of the joined box without runs."""
    names = list(main.spec.ranges)
    box = {n: tuple(main.spec.ranges[n]) for n in names}
    for o in others:
        for n, (lo, hi) in o.spec.ranges.items():
            box[n] = (min(box[n][0], lo), max(box[n][1], hi))
    if box == {n: tuple(main.spec.ranges[n]) for n in names}:
        return box
    full = [st for st in [main, *others] if set(st.spec.ranges) == set(names) and not st.spec.neutral]
    width = np.array([box[n][1] - box[n][0] for n in names])
    los = np.array([[st.spec.ranges[n][0] for n in names] for st in full])
    his = np.array([[st.spec.ranges[n][1] for n in names] for st in full])
    covered = 0.0  # the union's volume (relative to the joined box) by inclusion-exclusion
    for mask in range(1, 2 ** len(full)):
        idx = [i for i in range(len(full)) if mask >> i & 1]
        side = np.clip(his[idx].min(axis=0) - los[idx].max(axis=0), 0.0, None) / np.where(width > 0, width, 1.0)
        covered += (-1) ** (len(idx) + 1) * float(np.prod(side))
    if covered < 1.0 - 1e-9:
        grown = ", ".join(f"{n} [{box[n][0]:g}, {box[n][1]:g}]" for n in names if box[n] != tuple(main.spec.ranges[n]))
        raise PoolError(f"the stores of {main.path.name}'s rig leave {100 * (1 - covered):.3g} % of their joined box "
                        f"({grown}) without runs: an extending store must span every other range of the box "
                        f"(a slab past one edge)")
    return box


def pooled_params(main, other) -> np.ndarray:
    """`other`'s run parameters (every run, in its order) in `main`'s parameter columns."""
    fixed = fixed_values(main, other)
    cols = [other.params[:, other.spec.names.index(n)] if n in other.spec.ranges
            else np.full(len(other.params), fixed[n]) for n in main.spec.names]
    return np.column_stack(cols) if cols else np.empty((len(other.params), 0))
