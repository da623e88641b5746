"""Refinement runs for one material (`pydem diagnose --refine N`, calibration/refine.py) on the
tiny stores: the plan is made before any run and kept, the runs go to a journal beside the output,
an interrupted refinement runs only what the journal lacks, another budget is refused rather than
mixed, and the report shows both passes and each row's surrogate error against its uncertainty."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
STORES = [str(ROOT / "data/campaigns/diag_aor_tiny.h5"), str(ROOT / "data/campaigns/diag_hopper_tiny.h5")]


def material_file(path: Path):
    """Angle-of-repose and hopper rows (the two quick rigs) made by the tiny nets with lab noise."""
    from pydem.calibration import synthetic
    from pydem.calibration.setup import load_setup
    setup = load_setup(STORES, say=lambda *a: None)
    truth = synthetic.Truth({"friction": 0.5, "rolling_friction": 0.2, "restitution": 0.5}, None, None, None)
    obs, _ = synthetic.surrogate_set_and_means(setup.nets, setup.candidates, truth, np.random.default_rng(3),
                                               synthetic.programme(setup.nets))
    synthetic.to_csv(path, "m", obs, truth, "test_refine")


def diagnose(tmp_path, *extra):
    return subprocess.run([sys.executable, "-m", "pydem", "diagnose", str(tmp_path / "m.csv"), "--material", "m",
                           "--stores", *STORES, "--out", str(tmp_path / "out"), "--workers", "2", *extra],
                          capture_output=True, text=True, cwd=tmp_path, timeout=600)


@pytest.mark.slow
def test_refinement_runs_resume_and_report_both_passes(tmp_path):
    material_file(tmp_path / "m.csv")
    r = diagnose(tmp_path, "--refine", "4")
    assert r.returncode == 0, r.stderr + r.stdout
    folder = tmp_path / "out.refine"
    plan = json.loads((folder / "plan.json").read_text())["runs"]
    journal = [json.loads(x) for x in (folder / "runs.jsonl").read_text().splitlines()]
    assert len(plan) == 4 and sorted(e["index"] for e in journal) == [0, 1, 2, 3]
    assert all("metrics" in e or "error" in e for e in journal)
    gains = [p["gain"] for p in plan if p["gain"] is not None]
    assert len(gains) == 2 and all(g > 0 for g in gains) and gains == sorted(gains, reverse=True)  # greedy: less each
    # the last two repeat the first run (other seeds): the seed scatter where the material is
    assert all(p["why"].startswith("a repeat of run 0") and p["point"] == plan[0]["point"] for p in plan[2:])
    report = (tmp_path / "out/report.md").read_text()
    assert "## Refinement: first and second pass" in report and "surrogate error, first pass" in report
    data = json.loads((tmp_path / "out/diagnosis.json").read_text())["context"]["refinement"]
    assert data["runs"] == 4 and len(data["rows"]) == 11
    # its three tables fit a narrow window (headless Chromium at 500 px, the page's own scroll width)
    from test_report_browser import page_width
    assert page_width(tmp_path / "out/report.html", 500, tmp_path) <= 500
    # interrupted after two runs: the rerun runs the other two only, with the same plan
    (folder / "runs.jsonl").write_text("".join(json.dumps(e) + "\n" for e in journal[:2]))
    r = diagnose(tmp_path, "--refine", "4")
    assert r.returncode == 0, r.stderr
    assert "2 of 4 runs in" in r.stdout and "running 2" in r.stdout
    assert json.loads((folder / "plan.json").read_text())["runs"] == plan
    again = [json.loads(x) for x in (folder / "runs.jsonl").read_text().splitlines()]
    assert sorted(e["index"] for e in again) == [0, 1, 2, 3]
    # another budget is not mixed into this refinement: refused before any work
    r = diagnose(tmp_path, "--refine", "5")
    assert r.returncode == 2 and "holds a refinement made for other rows, budget, stores or design" in r.stderr
    assert "base model" not in r.stdout


def test_refine_budget_is_checked_before_any_work(tmp_path):
    material_file(tmp_path / "m.csv")
    r = diagnose(tmp_path, "--refine", "-3")
    assert r.returncode == 2 and "--refine takes 1..4096 runs" in r.stderr
    r = subprocess.run([sys.executable, "-m", "pydem", "diagnose", str(tmp_path / "m.csv"), "--material", "m",
                        "--stores", *STORES, "--out", str(tmp_path / "out"), "--refine", "2", "--workers", "0"],
                       capture_output=True, text=True, cwd=tmp_path, timeout=600)
    assert r.returncode == 2 and "--workers at least 1" in r.stderr


def test_refinement_runs_on_a_dask_cluster_into_the_same_journal(tmp_path):
    """The plan's runs through a Dask LocalCluster (two tiny hopper runs): the journal gets one line
    per run with its metrics, as the local workers write it."""
    import distributed
    from pydem.calibration.refine import run_plan
    from pydem.calibration.setup import open_stores
    stores = open_stores(STORES)
    point = {"friction": 0.5, "rolling_friction": 0.2, "restitution": 0.5, "wall_friction": 0.5, "size_spread": 0.1,
             "effects.cohesion_sjkr.cohesion_energy_density": 0.0}
    runs = [{"rig": "hopper", "point": point, "conditions": {"slot_width": b}, "fractions": [], "why": "test", "gain": 1.0}
            for b in (0.03, 0.04)]
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        entries = run_plan(runs, stores, tmp_path, 1, say=lambda *a: None, dask=cluster.scheduler_address)
    assert [e["index"] for e in entries] == [0, 1] and all(e["metrics"]["mass_flow_rate"] > 0 for e in entries)
    assert len((tmp_path / "runs.jsonl").read_text().splitlines()) == 2


def test_the_fixed_design_lies_in_the_posterior_box_and_deals_the_tests_in_turn(tmp_path):
    """The alternative plan: Sobol points inside the final model's 95 % intervals, one rig test after
    the other."""
    from pydem.calibration import diagnose as dg
    from pydem.calibration import synthetic
    from pydem.calibration.refine import condition_groups, plan_fixed
    from pydem.calibration.setup import load_setup
    setup = load_setup(STORES, say=lambda *a: None)
    truth = synthetic.Truth({"friction": 0.5, "rolling_friction": 0.2, "restitution": 0.5}, None, None, None)
    obs, _ = synthetic.surrogate_set_and_means(setup.nets, setup.candidates, truth, np.random.default_rng(3),
                                               synthetic.programme(setup.nets))
    d = dg.diagnose("m", obs, setup.nets, setup.ranges, setup.candidates, say=lambda *a: None, detection_limits=False)
    runs = plan_fixed(d, obs, setup.candidates, setup.ranges, 8)
    post = d.base.posterior["parameters"]
    groups = condition_groups(obs)
    assert len(runs) == 8 and [r["rig"] for r in runs] == [groups[k % len(groups)][0] for k in range(8)]
    for r in runs:
        for n, p in post.items():
            assert p["lo"] - 1e-9 <= r["point"][n] <= p["hi"] + 1e-9
        assert r["point"]["wall_friction"] == pytest.approx(r["point"]["friction"])  # neutral: follows friction
