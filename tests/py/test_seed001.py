"""Seed 001's pipeline on the shipped frame subset (data/seed001/frames_subset.h5: every case of
Table 1, every 20th frame of the full set; docs/seed001.md): the stored labels are consistent
with the physics of a discharge, the GRA weights are percentages, and the two cheap experiments
and the report run end to end (tiny settings: this checks the chain, not the networks' skill)."""
import argparse
import json
import os
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
SUBSET = ROOT / "data/seed001/frames_subset.h5"


def test_the_subset_holds_every_case_with_consistent_labels():
    from pydem.seed001.store import FrameStore
    from pydem.rigs.hopper import TABLE1
    store = FrameStore(SUBSET)
    assert store.cases() == sorted(TABLE1)
    for case in store.cases():
        d = store.read_case(case)
        assert d["frames"].dtype == np.uint8 and d["frames"].shape[1:] == (224, 224) and len(d["frames"]) >= 5
        assert np.allclose(d["remaining_time"], d["discharge_time"] - d["time"])
        assert np.all(np.diff(d["time"]) > 0) and np.all(np.diff(d["nrrp"]) <= 0)  # time-ordered, emptying
        assert 0.0 <= d["nrrp"].min() and d["nrrp"].max() <= 1.0


def test_gra_weights_are_percentages_over_the_cases():
    from pydem.seed001.store import FrameStore
    from pydem.seed001.gra import PARAMETERS, gra_tables
    store = FrameStore(SUBSET)
    tables = gra_tables({c: float(store.read_case(c)["discharge_time"]) for c in store.cases()})
    assert set(tables) == {"A", "B1", "B2", "B3", "B4", "all"}
    for t in tables.values():
        assert set(t) == set(PARAMETERS) and sum(t.values()) == pytest.approx(100.0)


def test_pydem_images_is_the_seed001_command_line():
    """`pydem images ...` hands its arguments to pydem.seed001.cli whole (its own --help included)."""
    import subprocess
    import sys
    run = lambda *a: subprocess.run([sys.executable, "-m", "pydem", "images", *a], capture_output=True, text=True,
                                    timeout=120)
    r = run("--help")
    assert r.returncode == 0 and "usage: pydem images" in r.stdout and "point-to-point" in r.stdout
    r = run("gra", "--store", str(SUBSET))
    assert r.returncode == 0 and r.stdout.startswith("| parameter | A | B1 |"), r.stderr


@pytest.mark.slow
def test_experiments_and_report_run_on_the_subset(tmp_path, capsys):
    import torch
    from pydem.seed001 import experiments as ex
    from pydem.seed001.report import write
    torch.set_num_threads(1)
    p2p = ex.point_to_point(SUBSET, tmp_path, size=64, every=2, epochs=1, say=lambda *a: None)
    assert set(p2p["splits"]) == {"random_frames", "leave_cases_out"}
    assert p2p["settings"]["test_cases"] == ["A-5", "B1-5", "B2-5", "B3-5", "B4-5"]
    lco = p2p["splits"]["leave_cases_out"]
    assert set(lco["test"]["case"]) == set(p2p["settings"]["test_cases"])  # whole cases held out
    proc = ex.process(SUBSET, tmp_path, size=32, window=2, epochs=1, fraction=0.4, finetune_epochs=2, say=lambda *a: None)
    assert set(proc["per_packing"]) == {"A", "B1", "B2", "B3", "B4"}
    assert proc["settings"]["protocol"] == "pretrained"
    assert all(set(v) == {"net", "baseline", "zero_shot", "fill_level", "species"} for v in proc["per_packing"].values())
    # the gauge is calibrated on the cases the network pretrains on: for fold 1, folds 3, 4, 5
    assert ex.pretraining_folds("1", ["1", "2", "3", "4", "5"]) == ["3", "4", "5"]
    assert all(isinstance(r["finetune_kept"], bool) for r in proc["cases"].values())
    page = write(SUBSET, tmp_path, tmp_path / "report")
    text = page.read_text()
    assert "Grey relational analysis" in text and "AlexNet-FC point to point" in text and "data:image/png;base64," in text
    assert json.loads((tmp_path / "process.json").read_text())["settings"]["window"] == 2
    # the network on the two species' channels: same protocol, same gauges
    sp = ex.process(SUBSET, tmp_path / "species", size=32, window=2, epochs=1, fraction=0.4, finetune_epochs=2, inputs="species",
                    say=lambda *a: None)
    assert sp["settings"]["inputs"] == "species" and set(sp["per_packing"]) == set(proc["per_packing"])
    assert sp["cases"]["B1-1"]["species"] == proc["cases"]["B1-1"]["species"]  # the gauges do not depend on it
    # extra hoppers (here subset cases under other names: the plumbing, no DEM) join every fold's
    # pretraining and the gauges' calibration and are never tested; with the residual target each
    # case names the gauge chosen for its packing, whose reading the network corrects
    from pydem.seed001 import gauges
    from pydem.seed001.store import FrameStore
    extra = extra_store(tmp_path / "extra.h5", {f"{pk}-x0{i}": f"{pk}-{i}" for pk in ex.PACKINGS for i in (1, 2)})
    kw = dict(size=32, window=2, epochs=1, fraction=0.4, finetune_epochs=2, say=lambda *a: None)
    res = ex.process(SUBSET, tmp_path / "r", extra=[extra], extra_per_packing=1, target="residual", **kw)
    assert res["settings"]["extra_hoppers"] == [f"{pk}-x01" for pk in ex.PACKINGS] and "gauge" not in proc["cases"]["A-1"]
    assert set(res["cases"]) == set(FrameStore(SUBSET).cases())  # the extra hoppers are never test cases
    assert all(r["gauge"] in gauges.GAUGES and 0 <= min(r["predicted"]) <= max(r["predicted"]) <= 1
               for r in res["cases"].values())
    assert res["cases"]["A-1"]["fill_level_nrrp"] != proc["cases"]["A-1"]["fill_level_nrrp"]  # calibrated on more
    # the curve of error against hoppers used: the gauges at each count, the networks' points from
    # their runs (proc: no extra hopper; res: one per packing), the power law through them
    curve = more_hoppers_study().curve
    args = argparse.Namespace(table1=str(SUBSET), extra=str(extra), packings=list(ex.PACKINGS), counts=[0, 1, 2], size=32,
                              window=2, networks=[str(tmp_path), str(tmp_path / "r")], out=str(tmp_path / "curve.json"),
                              figure=str(tmp_path / "curve.png"))
    assert curve(args) == 0 and (tmp_path / "curve.png").stat().st_size > 0
    got = json.loads((tmp_path / "curve.json").read_text())["packings"]["B1"]
    assert [r["hoppers"] for r in got["gauges"].values()] == [3, 4, 5] and got["extra_available"] == 2
    assert {k: r["hoppers"] for k, r in got["network"].items()} == {"0": 3, "1": 4}
    assert got["network"]["1"]["net"] == res["per_packing"]["B1"]["net"] and got["network"]["1"]["training"]["target"] == "residual"
    # the two runs learnt different targets: no power law through them, only the gauge's
    assert set(got["reach"]) == {"chosen gauge"}
    capsys.readouterr()
    runs = [str(tmp_path / "process.json"), str(tmp_path / "r")]  # a run's JSON or its folder
    assert more_hoppers_study().table(argparse.Namespace(networks=runs, packings=list(ex.PACKINGS))) == 0
    rows = capsys.readouterr().out.splitlines()[2:]
    assert [r.split(" | ")[0] for r in rows] == [f"| {pk}" for pk in ex.PACKINGS] and all(r.count(" / ") == 6 for r in rows)
    # AlexNet-FC: the extra hoppers train the leave-cases-out split only; the random split stays Table 1's
    more = ex.point_to_point(SUBSET, tmp_path / "pe", size=64, every=4, epochs=1, extra=[extra], say=lambda *a: None)
    assert more["settings"]["extra_hoppers"] == sorted(f"{pk}-x0{i}" for pk in ex.PACKINGS for i in (1, 2))
    assert set(more["splits"]["leave_cases_out"]["test"]["case"]) == set(p2p["settings"]["test_cases"])
    assert more["settings"]["frames"] + more["settings"]["extra_frames"] > more["settings"]["frames"]
    # a warm start takes each fold's pretrained weights of an earlier run: with no further epoch on
    # the same targets it reads every case exactly as that run did before fine-tuning
    warm = ex.process(SUBSET, tmp_path / "w", size=32, window=2, epochs=0, fraction=0.4, finetune_epochs=2,
                      warm_start=tmp_path, say=lambda *a: None)
    assert all(warm["cases"][c]["zero_shot"] == proc["cases"][c]["zero_shot"] for c in proc["cases"])
    with pytest.raises(ValueError, match="do not fit these inputs"):  # the grey run's networks, species inputs
        ex.process(SUBSET, tmp_path / "w2", inputs="species", warm_start=tmp_path, **kw)
    with pytest.raises(ValueError, match="not found"):
        ex.process(SUBSET, tmp_path / "w3", warm_start=tmp_path / "nothing", **kw)
    clash = extra_store(tmp_path / "clash.h5", {"A-1": "A-1"})  # a test case among the training hoppers: refused
    with pytest.raises(ValueError, match="A-1 is a Table 1 case"):
        ex.process(SUBSET, tmp_path / "c", extra=[clash], **kw)


def test_windows_with_a_stride_start_every_stride_frames():
    import numpy as np
    from nn.training import windows
    x = np.arange(10, dtype=np.float32).reshape(10, 1, 1, 1)
    xw, yw = windows(x, np.arange(10.0), 4, stride=3)
    assert xw.shape == (3, 4, 1, 1, 1) and yw[:, 0].tolist() == [0.0, 3.0, 6.0] and yw[-1].tolist() == [6, 7, 8, 9]


def test_fit_keeps_a_given_target_scaling():
    import numpy as np
    import torch
    from nn.training import fit
    torch.manual_seed(0)
    model = torch.nn.Linear(1, 1)
    x = np.linspace(0, 1, 16, dtype=np.float32).reshape(-1, 1)
    s = fit(model, x, 2 * x[:, 0], x, 2 * x[:, 0], epochs=1, batch=8, scaling={"mean": 5.0, "sd": 3.0})
    assert (s["mean"], s["sd"]) == (5.0, 3.0)


def test_the_gpu_runner_reads_frames_and_table1_without_the_compiled_binding():
    """studies/seed001_device.py runs on GPU machines where libdem is not built: pydem's frame
    store and Table 1 must import there without the binding."""
    import subprocess
    import sys
    code = ("import sys; sys.path.insert(0, 'studies'); import seed001_device as d; d.import_without_binding(); "
            "import pydem.seed001.cli, pydem.seed001.store, pydem.rigs.table1, nn.training; "
            "assert 'pydem._libdem' not in sys.modules; print(len(pydem.rigs.table1.TABLE1))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT,
                         env={**os.environ, "SEED001_NO_BINDING": "1"})
    assert out.returncode == 0, out.stderr
    assert out.stdout.split()[-1] == "25"


def more_hoppers_study():
    """studies/nrrp_more_hoppers.py as a module (studies/ is not a package)."""
    import importlib.util
    spec = importlib.util.spec_from_file_location("nrrp_more_hoppers", ROOT / "studies/nrrp_more_hoppers.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_the_hoppers_needed_for_the_target_follow_the_power_law_through_the_last_points():
    """err = a n^b through (3, 0.2) and (12, 0.1): b = -1/2, a = 0.2 sqrt 3, so 0.08 is reached at
    n = (a / 0.08)^2 = 18.75 hoppers, beyond the points (an extrapolation). The fit takes the last
    three points only: a first point far above them does not change it. A reader that reaches the
    target is read off the points (the fewest hoppers at or below it); a rising error reaches nothing."""
    reach = more_hoppers_study().reach
    for points in ([(3, 0.2), (12, 0.1)], [(1, 5.0), (3, 0.2), (6, 0.2 / 2 ** 0.5), (12, 0.1)]):
        r = reach(points)
        assert r["exponent"] == pytest.approx(-0.5) and r["hoppers_for_target"] == pytest.approx(18.75)
        assert r["extrapolated"] and not r["reached"] and r["fitted_from"] == 3
    got = reach([(3, 0.1), (6, 0.07), (12, 0.05)])
    assert got["reached"] and got["hoppers_for_target"] == 6 and not got["extrapolated"]
    assert reach([(3, 0.1), (12, 0.2)])["hoppers_for_target"] is None


def test_the_networks_power_law_takes_only_runs_trained_like_the_largest():
    comparable = more_hoppers_study().comparable
    budget = {"inputs": "species", "target": "nrrp", "size": 64, "window": 8, "stride": 16, "epochs": 4}
    points = {"0": {"hoppers": 3, "training": budget | {"stride": 8, "epochs": 8}},
              "6": {"hoppers": 9, "training": budget}, "12": {"hoppers": 15, "training": budget}}
    assert set(comparable(points)) == {"6", "12"} and comparable({}) == {}


def extra_store(path, names: dict):
    """A store of 'more hoppers' made from subset cases under other names (the plumbing, not the
    physics: no DEM), each with its Table 1-style row as pydem images hoppers stores it."""
    from pydem.rigs.table1 import TABLE1, row_as_json
    from pydem.seed001.store import FrameStore
    src, dst = FrameStore(SUBSET), FrameStore(path)
    for new, old in names.items():
        d = src.read_case(old)
        dst.write_case(new, d["frames"], d["time"], d["discharge_time"], d["nrrp"],
                       {"packing": new.split("-")[0], "row": json.dumps(row_as_json(TABLE1[old]))})
    return path
