"""A rig's other stores pooled into a diagnosis store's surrogates (pydem/calibration/pooled_runs.py):
a three-parameter campaign's runs land in the six-parameter box at the values its preset gave
the parameters it did not vary (an effect that was off: its neutral value), and stores whose
runs are not points of the box are refused with the reason named."""
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from pydem.calibration.pooled_runs import PoolError, check_poolable, pooled_params
from pydem.calibration.quantities import Quantity
from pydem.calibration.store_data import training_tables
from pydem.campaign.runner import resolved_config
from pydem.campaign.spec import CampaignSpec

BOX = {"friction": (0.05, 1.0), "rolling_friction": (0.0, 0.6), "restitution": (0.2, 0.9),
       "wall_friction": (0.05, 1.0), "effects.cohesion_sjkr.cohesion_energy_density": (0.0, 1e5),
       "size_spread": (0.0, 0.5)}
THREE = {"friction": (0.2, 1.0), "rolling_friction": (0.05, 0.6), "restitution": (0.2, 0.9)}


def store(name, ranges, params, values, preset="tiny", fixed=None, protocol=1, libdem="0.2.0", rig="aor"):
    spec = CampaignSpec(rig, dict(ranges), preset, dict(fixed or {}))
    prov = {"rig_protocol": protocol, "libdem": libdem, "rig_config": resolved_config(spec)}
    return SimpleNamespace(spec=spec, path=Path(name), params=np.asarray(params, float), provenance=prov,
                           rig_protocol=protocol, physics=".".join(libdem.split(".")[:2]),
                           values=np.asarray(values, float), status=np.ones(len(params), int),
                           metric_names=["angle_of_repose", "bulk_density"])


def test_runs_map_to_the_preset_values_of_what_they_did_not_vary():
    main = store("six.h5", BOX, [[0.5, 0.3, 0.5, 0.4, 2e4, 0.2]], [[35.0, 1500.0]])
    other = store("three.h5", THREE, [[0.3, 0.1, 0.4], [0.9, 0.5, 0.6]], [[30.0, 1490.0], [41.0, 1470.0]])
    check_poolable(main, other)
    x = pooled_params(main, other)
    # wall friction: the rig's knob (0.5, not the particles' friction); cohesion off: 0; spread: 0.1
    assert np.allclose(x, [[0.3, 0.1, 0.4, 0.5, 0.0, 0.1], [0.9, 0.5, 0.6, 0.5, 0.0, 0.1]])
    names, xs, ys = training_tables(main, [other])[Quantity("aor", "angle_of_repose")]
    assert names == list(BOX) and xs.shape == (3, 6) and list(ys) == [35.0, 30.0, 41.0]


@pytest.mark.parametrize("change, words", [
    (dict(preset="default"), "rig/preset"),
    (dict(protocol=2), "rig protocol"),
    (dict(libdem="0.1.0"), "libdem"),
    (dict(fixed={"lift_speed": 0.05}), "the rig differs in lift_speed"),
    (dict(fixed={"wall_friction": 1.5}), "wall_friction = 1.5 lies outside"),
])
def test_stores_whose_runs_are_not_points_of_the_box_are_refused(change, words):
    main = store("six.h5", BOX, [[0.5, 0.3, 0.5, 0.4, 2e4, 0.2]], [[35.0, 1500.0]])
    kw = dict(preset="tiny", fixed=None, protocol=1, libdem="0.2.0") | change
    other = store("three.h5", THREE, [[0.3, 0.1, 0.4]], [[30.0, 1490.0]], **kw)
    with pytest.raises(PoolError, match=words):
        check_poolable(main, other)


def test_a_store_varying_more_than_the_main_one_is_refused():
    main = store("three.h5", THREE, [[0.3, 0.1, 0.4]], [[30.0, 1490.0]])
    wide = store("other.h5", {**THREE, "wall_restitution": (0.3, 0.7)}, [[0.3, 0.1, 0.4, 0.5]], [[30.0, 1490.0]])
    with pytest.raises(PoolError, match="varies wall_restitution"):
        check_poolable(main, wide)


def test_a_different_blow_up_limit_does_not_block_pooling():
    """max_overlap_ratio only stops a run that blew up (every run below it is the same): stores that
    differ in it pool; the thread count likewise."""
    main = store("six.h5", BOX, [[0.5, 0.3, 0.5, 0.4, 2e4, 0.2]], [[35.0, 1500.0]],
                 fixed={"max_overlap_ratio": 0.6, "num_threads": 2}, rig="hopper")
    other = store("three.h5", THREE, [[0.3, 0.1, 0.4]], [[30.0, 1490.0]], rig="hopper")
    check_poolable(main, other)
    with pytest.raises(PoolError, match="the rig differs in fine_fraction"):
        check_poolable(main, store("three.h5", THREE, [[0.3, 0.1, 0.4]], [[30.0, 1490.0]], rig="hopper",
                                   fixed={"fine_fraction": 0.5}))


def test_a_hopper_that_did_not_empty_trains_no_discharge_metric():
    """A run that jammed measured no discharge time and no flow rate (its 20-80 % slope mixes flow
    and standstill): neither surrogate learns from it, as no pseudo-measurement contains it
    (confirm.rig_values); its bulk density, measured before the gate opened, still counts."""
    ranges = {"friction": (0.05, 1.0), "slot_width": (0.03, 0.08)}
    main = store("hopper.h5", ranges, [[0.3, 0.05], [0.9, 0.04]], [[1.2, 1.1, 1300.0], [np.nan, 0.3, 1250.0]],
                 preset="default", rig="hopper")
    main.metric_names = ["discharge_time", "mass_flow_rate", "bulk_density"]
    tables = training_tables(main)
    assert list(tables[Quantity("hopper", "mass_flow_rate")][2]) == [1.1]
    assert list(tables[Quantity("hopper", "discharge_time")][2]) == [1.2]
    assert list(tables[Quantity("hopper", "bulk_density")][2]) == [1300.0, 1250.0]


def test_a_slab_past_one_edge_extends_the_box_and_a_corner_left_unrun_is_refused():
    """A store over the same ranges but one, which continues past the main store's edge (wall friction
    1.0-1.2 beside 0.05-1.0), extends the rig's box; two slabs that leave a corner unrun (wall
    friction 1.0-1.2 only at low friction, friction 1.0-1.2 only at low wall friction) do not
    fill their joined box, and say how much of it is missing: (0.2 / 1.15)^2 = 3.02 %."""
    from pydem.calibration.pooled_runs import joined_box
    main = store("six.h5", BOX, [[0.5, 0.3, 0.5, 0.4, 2e4, 0.2]], [[35.0, 1500.0]])
    slab = store("slab.h5", {**BOX, "wall_friction": (1.0, 1.2)}, [[0.5, 0.3, 0.5, 1.1, 2e4, 0.2]], [[36.0, 1500.0]])
    check_poolable(main, slab)
    box = joined_box(main, [slab])
    assert box["wall_friction"] == (0.05, 1.2) and box["friction"] == BOX["friction"]
    assert joined_box(main, []) == {n: tuple(r) for n, r in BOX.items()}
    gap = store("gap.h5", {**BOX, "friction": (1.0, 1.2)}, [[1.1, 0.3, 0.5, 0.4, 2e4, 0.2]], [[36.0, 1500.0]])
    with pytest.raises(PoolError, match=r"leave 3\.02 % of their joined box \(friction \[0.05, 1.2\], "
                                        r"wall_friction \[0.05, 1.2\]\) without runs"):
        joined_box(main, [slab, gap])


def test_the_shipped_hopper_slab_extends_its_box_to_rough_walls():
    """The hopper's wall-friction slab (1.0-1.2, every other range the size-spread store's) pools in,
    and the hopper's box reaches 1.2; the store alone keeps 1.0."""
    from pydem.calibration.setup import open_store_groups
    root = Path(__file__).resolve().parents[2] / "data/campaigns"
    main = [root / "diag_hopper_default_spread.h5", root / "diag_hopper_default.h5"]
    assert open_store_groups(main)["hopper"][2]["wall_friction"] == (0.05, 1.0)
    store, pooled, box = open_store_groups(main + [root / "diag_hopper_default_roughwalls.h5"])["hopper"]
    assert store.path.name == "diag_hopper_default_spread.h5" and box["wall_friction"] == (0.05, 1.2)
