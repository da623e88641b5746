"""Long rig runs split by checkpoints end bitwise as the uninterrupted run: every metric, the
step count and the time series. The ring shear checkpoints at phase boundaries (max_phases
splits it); the angle of repose and the hopper inside their phases, right after a chunk's steps
(stop_at splits them at a simulated time: inside the filling, the settling, the lift, the
discharge). A checkpoint of other settings is refused by name; a finished run removes its own."""
import numpy as np
import pytest

from pydem.rigs import RIGS, load


# the tiny ring shear's shearing shortened (its phases as they are): the splits, not the physics, are checked
SHORT = {"ring-shear": ["first_preshear_displacement=3e-3", "preshear_displacement=2e-3", "shear_displacement=1.5e-3"]}


def tiny(rig, *extra):
    cls, cfg_cls = RIGS[rig]
    return cls(load(cfg_cls, "tiny", None, ["num_threads=1", *SHORT.get(rig, []), *extra]))


def assert_same_run(res, whole):
    assert {k: (m.value, m.uncertainty) for k, m in res.metrics.items()} == \
           {k: (m.value, m.uncertainty) for k, m in whole.metrics.items()}
    assert res.info["steps"] == whole.info["steps"]
    assert res.series.keys() == whole.series.keys()
    for k in whole.series:
        assert np.array_equal(res.series[k], whole.series[k]), k


@pytest.mark.slow
def test_split_ring_shear_is_bitwise_the_whole_run(tmp_path):
    whole = tiny("ring-shear").run(seed=4)
    rig = tiny("ring-shear")
    assert rig.run(seed=4, checkpoint=tmp_path, max_phases=2) is None       # fill, load, first pre-shear
    assert (tmp_path / "ring_shear.json").exists() and (tmp_path / "ring_shear.h5").exists()
    assert rig.run(seed=4, checkpoint=tmp_path, max_phases=2) is None       # two more phases
    res = rig.run(seed=4, checkpoint=tmp_path)                              # the rest
    assert res.info["resumed_at_phase"] == 4
    assert_same_run(res, whole)
    assert not (tmp_path / "ring_shear.json").exists()  # done: no stale checkpoint left


@pytest.mark.parametrize("rig, stops", [("aor", (0.05, 0.7)),          # settling, then the lift
                                        ("hopper", (0.05, 0.25, 0.3))])  # a filling batch, settling, discharge
def test_split_run_inside_phases_is_bitwise_the_whole_run(tmp_path, rig, stops):
    whole = tiny(rig).run(seed=3)
    assert stops[-1] < whole.info["simulated_time"]
    r = tiny(rig)
    for t in stops:
        assert r.run(seed=3, checkpoint=tmp_path, stop_at=t) is None
        assert (tmp_path / f"{rig}.json").exists()
    res = r.run(seed=3, checkpoint=tmp_path)
    assert res.info["resumed_at"] >= stops[-1]
    assert_same_run(res, whole)
    assert not (tmp_path / f"{rig}.json").exists()


def test_a_checkpoint_of_other_settings_is_refused(tmp_path):
    assert tiny("ring-shear").run(seed=4, checkpoint=tmp_path, max_phases=2) is None
    with pytest.raises(ValueError, match="another configuration, parameter set or seed"):
        tiny("ring-shear", "preshear_stress=3000").run(seed=4, checkpoint=tmp_path)
    with pytest.raises(ValueError, match="another configuration"):
        tiny("ring-shear").run(seed=5, checkpoint=tmp_path)
    assert tiny("aor").run(seed=1, checkpoint=tmp_path / "a", stop_at=0.02) is None
    with pytest.raises(ValueError, match="another configuration"):
        tiny("aor", "lift_speed=0.05").run(seed=1, checkpoint=tmp_path / "a")


def test_a_damaged_checkpoint_is_named(tmp_path):
    assert tiny("aor").run(seed=1, checkpoint=tmp_path, stop_at=0.02) is None
    (tmp_path / "aor.json").write_text('{"signature": ')
    with pytest.raises(ValueError, match="not a readable checkpoint"):
        tiny("aor").run(seed=1, checkpoint=tmp_path)
