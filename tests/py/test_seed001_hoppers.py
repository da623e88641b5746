"""More hoppers as a data set of their own (pydem/seed001/hoppers.py): drawn like Table 1's, run
into one frame store per packing, resumable, a failure kept with its reason and never silently
dropped, a store of other draws refused by name. Small beds (a third of Table 1's solid volume,
a frame every 20 ms) keep it to seconds."""
import json

import numpy as np
import pytest

from pydem.rigs.table1 import draw_like_table1
from pydem.seed001.hoppers import run_hoppers
from pydem.seed001.store import FrameStore

QUICK = dict(frame_interval=0.02, workers=2, volume_scale=0.3)


def test_more_hoppers_are_stored_resumed_and_their_failures_kept(tmp_path):
    said = []
    store = tmp_path / "extra_B2.h5"
    got = run_hoppers(store, "B2", 2, seed=17, say=said.append, **QUICK)  # two beds of 6 and 9 mm spheres
    assert got == {"stored": ["B2-x01", "B2-x02"], "failed": {}}, said
    rows = draw_like_table1("B2", 2, 17, 0.3)
    for name in got["stored"]:
        d = FrameStore(store).read_case(name)
        assert json.loads(d["row"])[0] == rows[name][0] and d["packing"] == "B2" and d["frame_interval"] == 0.02
        assert d["frames"].shape[1:] == (224, 224) and d["frames"].dtype == np.uint8
        assert d["nrrp"][0] == 1.0 and np.all(np.diff(d["nrrp"]) <= 0) and d["remaining_time"][-1] >= 0
    assert any("2/2 done, 0 failed" in m for m in said)
    said.clear()
    assert run_hoppers(store, "B2", 2, seed=17, say=said.append, **QUICK)["stored"] == ["B2-x01", "B2-x02"]
    assert "running 0" in said[0]  # resumed: nothing left to run
    with pytest.raises(ValueError, match="made with other settings"):  # another draw: other hoppers under these names
        run_hoppers(store, "B2", 2, seed=18, say=said.append, **QUICK)
    # beds too shallow to measure: each failure is kept with its reason and reported, not run again
    shallow = tmp_path / "shallow.h5"
    got = run_hoppers(shallow, "A", 1, seed=17, say=said.append, **(QUICK | {"volume_scale": 0.05}))
    assert got["stored"] == [] and "too shallow" in got["failed"]["A-x01"]
    said.clear()
    run_hoppers(shallow, "A", 1, seed=17, say=said.append, **(QUICK | {"volume_scale": 0.05}))
    assert "1 failed before" in said[0] and any("A-x01: failed before: the run failed" in m for m in said)
    assert FrameStore(shallow).cases() == []  # a failure is no case


def test_the_table1_frame_set_runs_in_workers_and_resumes(tmp_path):
    """`pydem images frames` runs the Table 1 cases the store lacks side by side (the same runner
    as the extra hoppers), each stored with its Table 1 parameters; a rerun skips them."""
    from pydem.seed001.cli import main
    store = tmp_path / "f.h5"
    assert main(["frames", "--store", str(store), "--cases", "A-1", "--frame-interval", "0.02", "--workers", "2"]) == 0
    d = FrameStore(store).read_case("A-1")
    assert d["particles"] == 620 and d["param_particles"] == 620 and d["packing"] == "A" and d["nrrp"][0] == 1.0
    assert main(["frames", "--store", str(store), "--cases", "A-1", "--frame-interval", "0.02"]) == 0
