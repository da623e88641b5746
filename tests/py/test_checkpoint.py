"""A ring-shear run split across three calls by checkpoints (max_phases) ends with every metric,
the step count and the lid's time series bitwise those of the uninterrupted run; a checkpoint
of another configuration is refused by name; a finished run removes its checkpoint."""
import numpy as np
import pytest

from pydem.rigs import RIGS, load


def tiny(*extra):
    cls, cfg_cls = RIGS["ring-shear"]
    return cls(load(cfg_cls, "tiny", None, ["num_threads=1", *extra]))


def test_split_run_is_bitwise_the_whole_run(tmp_path):
    whole = tiny().run(seed=4)
    rig = tiny()
    assert rig.run(seed=4, checkpoint=tmp_path, max_phases=2) is None       # fill, load, first pre-shear
    assert (tmp_path / "ring_shear.json").exists() and (tmp_path / "ring_shear.h5").exists()
    assert rig.run(seed=4, checkpoint=tmp_path, max_phases=2) is None       # two more phases
    res = rig.run(seed=4, checkpoint=tmp_path)                              # the rest
    assert res.info["resumed_at_phase"] == 4
    assert {k: (m.value, m.uncertainty) for k, m in res.metrics.items()} == \
           {k: (m.value, m.uncertainty) for k, m in whole.metrics.items()}
    assert res.info["steps"] == whole.info["steps"]
    assert np.array_equal(res.series["tau"], whole.series["tau"]) and np.array_equal(res.series["sigma"], whole.series["sigma"])
    assert not (tmp_path / "ring_shear.json").exists()  # done: no stale checkpoint left


def test_a_checkpoint_of_other_settings_is_refused(tmp_path):
    assert tiny().run(seed=4, checkpoint=tmp_path, max_phases=2) is None
    with pytest.raises(ValueError, match="another configuration, parameter set or seed"):
        tiny("preshear_stress=3000").run(seed=4, checkpoint=tmp_path)
    with pytest.raises(ValueError, match="another configuration"):
        tiny().run(seed=5, checkpoint=tmp_path)
