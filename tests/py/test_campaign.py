"""Campaigns (pydem.campaign): spec validation, deterministic and extendable designs, a real
tiny campaign run locally, survival of kill -9 mid-run (no finished run lost, store readable,
re-run completes it), failures recorded with their message, a Dask LocalCluster run, and the
calibration job end to end on the campaign (training, export, native screening, report)."""
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from pydem.campaign import Campaign, CampaignSpec, CampaignStore, SpecError, StoreError, design_points, simulate
from pydem.campaign.runner import config_drift
from pydem.campaign.store import DONE, FAILED

ROOT = Path(__file__).resolve().parents[2]
TINY_AOR = {"particles": 150, "num_threads": 1, "max_time": 1.5}  # ~2 s per run


def spec(samples=4, **kw):
    return CampaignSpec(rig="aor", preset="tiny", fixed=dict(TINY_AOR), samples=samples, seed=3,
                        ranges={"friction": (0.2, 0.9), "rolling_friction": (0.0, 0.5)}, **kw)


def write_toml(path, samples):
    lines = ['rig = "aor"', 'preset = "tiny"', "seed = 3", f"samples = {samples}", "[set]"]
    lines += [f"{k} = {v}" for k, v in TINY_AOR.items()]
    lines += ["[ranges]", "friction = [0.2, 0.9]", "rolling_friction = [0.0, 0.5]"]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_spec_errors_name_the_key(tmp_path):
    with pytest.raises(SpecError, match="rig: unknown rig 'silo'"):
        CampaignSpec(rig="silo", ranges={"friction": (0.1, 0.5)})
    with pytest.raises(SpecError, match=r"ranges.friction: low 0.5 must be below high 0.1"):
        CampaignSpec(rig="aor", ranges={"friction": (0.5, 0.1)})
    with pytest.raises(SpecError, match="friction = 3 is out of range"):
        CampaignSpec(rig="aor", ranges={"friction": (0.1, 3.0)})
    with pytest.raises(SpecError, match="unknown key 'frictoin'"):
        CampaignSpec(rig="aor", ranges={"frictoin": (0.1, 0.5)})
    bad = tmp_path / "bad.toml"
    bad.write_text('rig = "aor"\n[ranges]\nfriction = [0.1]\n')
    with pytest.raises(SpecError, match=r"ranges.friction must be \[low, high\]"):
        CampaignSpec.from_toml(bad)


@pytest.mark.parametrize("kind", ["sobol", "lhs"])
def test_design_is_deterministic_and_extendable(kind):
    r = {"a": (0.0, 1.0), "b": (10.0, 20.0)}
    first = design_points(kind, r, 0, 16, seed=5, batches=[16])
    grown = design_points(kind, r, 0, 48, seed=5, batches=[16, 32])
    assert np.array_equal(first, grown[:16])  # growing never moves a finished sample
    assert np.array_equal(grown, design_points(kind, r, 0, 48, seed=5, batches=[16, 32]))
    assert grown[:, 1].min() >= 10 and grown[:, 1].max() <= 20
    # space filling: each of 16 strata of the first axis holds exactly one of the first 16 points
    assert sorted(np.floor(first[:, 0] * 16).astype(int)) == list(range(16))


def test_a_design_on_the_one_effect_axes_holds_the_others_neutral(tmp_path):
    ranges = {"friction": (0.05, 1.0), "rolling_friction": (0.0, 0.5), "wall_friction": (0.05, 1.0),
              "effects.cohesion_sjkr.cohesion_energy_density": (0.0, 1e5)}
    neutral = {"wall_friction": "friction", "effects.cohesion_sjkr.cohesion_energy_density": 0.0}
    c = Campaign.create(tmp_path / "axes.h5", CampaignSpec(rig="aor", preset="tiny", fixed=dict(TINY_AOR), samples=6,
                                                            seed=3, ranges=ranges, neutral=neutral))
    c.grow(12)  # grown: the first six points unchanged, each point's free axis set by its index alone
    c.store.save()
    s = CampaignStore.open(tmp_path / "axes.h5")
    full = design_points("sobol", ranges, 0, 12, 3, [6, 6])
    assert s.spec.neutral == neutral and np.array_equal(s.params[:, :2], full[:, :2])  # base parameters untouched
    for i, row in enumerate(s.params):
        free = i % 3  # 0: none, 1: wall friction, 2: cohesion
        assert row[2] == (full[i, 2] if free == 1 else row[0])
        assert row[3] == (full[i, 3] if free == 2 else 0.0)
    bad = {"rolling_friction": "friction"}  # a linked range must fit: [0.05, 1] leaves [0, 0.5]
    for neutral, words in [({"restitution": 0.5}, "neutral.restitution: not a varied parameter"),
                           (bad, r"neutral.rolling_friction: friction's range \(0.05, 1.0\) leaves"),
                           ({"wall_friction": 2.0}, r"neutral.wall_friction: expected a number in \[0.05, 1\]")]:
        with pytest.raises(SpecError, match=words):
            CampaignSpec(rig="aor", preset="tiny", ranges=ranges, neutral=neutral)


def test_simulate_reports_failures_as_messages():
    out = simulate(spec().to_json(), {"friction": 5.0, "rolling_friction": 0.1}, seed=1)
    assert "error" in out and "friction = 5 is out of range" in out["error"]


def _done_values(path):
    s = CampaignStore.open(path)
    return {i: s.values[i].copy() for i in np.flatnonzero(s.status == DONE)}, s


def test_kill_9_mid_run_loses_nothing_and_resumes(tmp_path):
    store = tmp_path / "c.h5"
    toml = write_toml(tmp_path / "c.toml", samples=8)
    cmd = [sys.executable, "-m", "pydem", "campaign", "run", str(toml), "--store", str(store), "--workers", "2", "--quiet"]
    proc = subprocess.Popen(cmd, cwd=ROOT, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.time() + 120
    while time.time() < deadline:
        time.sleep(0.2)
        try:
            if CampaignStore.open(store).counts()["done"] >= 2:
                break
        except StoreError:
            pass  # not created yet
    os.killpg(proc.pid, signal.SIGKILL)  # the coordinator and its workers, mid-run
    proc.wait()
    before, s = _done_values(store)
    assert 2 <= len(before) < 8, "kill landed too late to test anything"
    r = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    after, s = _done_values(store)
    assert len(after) == 8 and s.counts() == {"pending": 0, "done": 8, "failed": 0}
    for i, v in before.items():  # finished runs kept, not re-run
        assert np.array_equal(v, after[i], equal_nan=True)
    assert not list(tmp_path.glob(".c.h5.tmp-*"))
    # status and export from the command line
    st = subprocess.run([sys.executable, "-m", "pydem", "campaign", "status", str(store)], cwd=ROOT,
                        capture_output=True, text=True)
    assert "done 8, failed 0, pending 0" in st.stdout and "provenance" in st.stdout
    subprocess.run([sys.executable, "-m", "pydem", "campaign", "export", str(store), "--csv", str(tmp_path / "c.csv")],
                   cwd=ROOT, check=True, capture_output=True)
    assert len((tmp_path / "c.csv").read_text().splitlines()) == 9


def test_extend_failures_lock_and_corrupt_store(tmp_path):
    c = Campaign.create(tmp_path / "s.h5", spec(samples=2))
    with pytest.raises(StoreError, match="exists already"):
        Campaign.create(tmp_path / "s.h5", spec(samples=2))
    c.store.record_failure(1, "DemRunError: particle 7 left the domain", 0.5)
    c.store.save()
    c.grow(4)
    counts = c.run(workers=2, points=2, quiet=True)  # of the first two points only 0 is pending; the failure stays
    assert counts == {"pending": 2, "done": 1, "failed": 1} and CampaignStore.open(tmp_path / "s.h5").status.tolist() == [DONE, FAILED, 0, 0]
    counts = c.run(workers=2, max_runs=1, quiet=True)
    assert counts == {"pending": 1, "done": 2, "failed": 1}
    s = CampaignStore.open(tmp_path / "s.h5")
    assert s.errors[1].startswith("DemRunError") and s.status[1] == FAILED and len(s) == 4
    assert np.array_equal(s.params[:2], design_points("sobol", spec().ranges, 0, 2, 3))
    # runs measured again after a rig fix: only those, whatever their status, their results
    # replaced (this rig is deterministic: the same values), the session noting which
    before = s.values.copy()
    counts = Campaign.open(tmp_path / "s.h5").run(workers=1, rerun=[1, 0], quiet=True)
    s2 = CampaignStore.open(tmp_path / "s.h5")
    assert counts == {"pending": 1, "done": 3, "failed": 0} and s2.status.tolist()[:3] == [DONE, DONE, DONE]
    assert np.array_equal(s2.values[0], before[0], equal_nan=True) and s2.finished_at[0] > s.finished_at[0]
    assert s2.status[3] == 0 and s2.provenance["sessions"][-1]["rerun"] == [0, 1]
    with pytest.raises(StoreError, match="no run 7 to run again"):
        Campaign.open(tmp_path / "s.h5").run(rerun=[7], quiet=True)
    other = Campaign.open(tmp_path / "s.h5")
    other.store.lock()
    with pytest.raises(StoreError, match="being written by another"):
        Campaign.open(tmp_path / "s.h5").run(quiet=True)
    other.store.unlock()
    # a store measured under another definition of the metrics is not extended silently
    assert c.store.provenance["rig_protocol"] == 1
    c.store.provenance["rig_protocol"] = 0
    c.store.save()
    with pytest.raises(StoreError, match="protocol 0, this code measures with protocol 1"):
        Campaign.open(tmp_path / "s.h5").run(quiet=True)
    # nor one whose preset has changed since it was run (the angle of repose's lift speed, say)
    c.store.provenance["rig_protocol"] = 1
    c.store.provenance["rig_config"]["lift_speed"] = 0.05
    c.store.save()
    with pytest.raises(StoreError, match="'tiny' preset has changed.*lift_speed: 0.05 then, 0.1 now"):
        Campaign.open(tmp_path / "s.h5").run(quiet=True)
    # a knob that changes no run's physics (the blow-up bound, frames, threads) is no drift: a
    # raised bound lets a store retry the runs it stopped
    c.store.provenance["rig_config"]["lift_speed"] = 0.1
    c.store.provenance["rig_config"].update(max_overlap_ratio=0.3, frame_interval=0.01)
    assert config_drift(c.store) == {}
    (tmp_path / "junk.h5").write_bytes(b"\x89HDF\r\n\x1a\n" + b"\0" * 100)
    with pytest.raises(StoreError, match="unreadable campaign store"):
        CampaignStore.open(tmp_path / "junk.h5")


def test_replicates_grow_by_replicate_and_average_per_point(tmp_path):
    with pytest.raises(SpecError, match="replicates: expected a positive integer"):
        spec(replicates=0)
    c = Campaign.create(tmp_path / "r.h5", spec(samples=3))
    c.grow(replicates=2)
    s = c.store
    # replicate-major: a partly run extension is still a complete design
    assert list(s.points) == [0, 1, 2, 0, 1, 2] and np.array_equal(s.params[3:], s.params[:3])
    assert len(set(s.seeds.tolist())) == 6 and s.spec.replicates == 2
    c.grow(5)  # new points get every replicate, existing rows never move
    assert list(s.points) == [0, 1, 2, 0, 1, 2, 3, 4, 3, 4] and s.design_points == 5
    assert np.array_equal(s.params[6:8], design_points("sobol", spec().ranges, 3, 5, 3, [3, 2]))
    for i, v in enumerate([1.0, 2.0, 3.0, 2.0, 2.0, 5.0, 7.0, 9.0]):  # rows 8, 9 (point 3, 4 again) stay pending
        s.record_done(i, {"m": (v, 0.0, "")}, 1.0)
    s.save()
    s = CampaignStore.open(tmp_path / "r.h5")
    assert "design points with 0 finished run(s): 0, 1 finished run(s): 2, 2 finished run(s): 3" in \
        Campaign.open(tmp_path / "r.h5").status_text()
    x, y, counts, sd = s.point_table("m")
    assert np.array_equal(y, [1.5, 2.0, 4.0, 7.0, 9.0]) and list(counts) == [2, 2, 2, 1, 1]
    assert np.array_equal(x, s.params[[0, 1, 2, 6, 7]])
    # pooled sd of one run: deviations +-0.5, 0, +-1 over 3 degrees of freedom
    assert sd == pytest.approx(np.sqrt((2 * 0.25 + 2 * 1.0) / 3), rel=1e-12)
    # a store written before replicates (format 1, no `point`) reads as one run per point
    import h5py
    with h5py.File(tmp_path / "r.h5", "a") as f:
        del f["point"]
        f.attrs["format_version"] = 1
        f.attrs["batches"] = json.dumps([10])
    assert list(CampaignStore.open(tmp_path / "r.h5").points) == list(range(10))


def test_dask_local_cluster(tmp_path):
    import distributed  # a real dependency (scripts/requirements.txt): never skipped
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        c = Campaign.create(tmp_path / "d.h5", spec(samples=2))
        counts = c.run(dask=cluster.scheduler_address, quiet=True)
    assert counts["done"] == 2
    s = CampaignStore.open(tmp_path / "d.h5")
    assert np.all(np.isfinite(s.values[:, s.metric_names.index("angle_of_repose")]))


def test_an_unreachable_dask_scheduler_is_named():
    """The campaigns' and the refinement's shared Dask runner (workers.run_dask) names the address
    it cannot reach, and runs nothing."""
    from pydem.campaign.workers import WorkerStartError, run_dask
    got = []
    with pytest.raises(WorkerStartError, match="cannot reach the Dask scheduler at 'tcp://127.0.0.1:9'"):
        run_dask("tcp://127.0.0.1:9", {0: ("spec", {}, 1)}, simulate, lambda i, r: got.append(i), "t", timeout="1s")
    assert got == []


def test_status_states_throughput_and_time_left(tmp_path, monkeypatch):
    """Runs per hour = workers x 3600 / mean wall time of the finished runs (the mean: slow runs
    cost their whole time); the pending runs' time left follows from it."""
    monkeypatch.setattr(os, "cpu_count", lambda: 2)  # two 1-thread workers by default
    c = Campaign.create(tmp_path / "t.h5", spec(samples=5))
    c.store.record_done(0, {"angle_of_repose": (30.0, 0.5, "deg")}, 100.0)
    c.store.record_done(1, {"angle_of_repose": (31.0, 0.5, "deg")}, 300.0)  # mean 200 s: 36 runs/h on 2 workers
    c.store.save()
    text = Campaign.open(tmp_path / "t.h5").status_text()
    assert "throughput: 36.0 runs/h" in text and "2 worker(s) of 1 thread(s)" in text
    assert "the 3 pending in about 0.1 h" in text  # 3 / 36 h


def test_a_flipped_bit_in_a_store_is_refused_by_name(tmp_path):
    """A store carries a checksum of every dataset (format 3): one byte flipped in a copy's run
    times (a wall time of -92,474 s once trained silently) is refused on open, naming the
    dataset; the intact copy opens. Stores from before format 3 (no checksums) still open."""
    import h5py
    ROOT = Path(__file__).resolve().parents[2]
    old = CampaignStore.open(ROOT / "data/campaigns/aor_tiny.h5")
    old.path = tmp_path / "sealed.h5"
    old.save()
    with h5py.File(old.path, "r") as f:
        assert "checksums" in f.attrs and int(f.attrs["format_version"]) == 3
        offset = f["wall_seconds"].id.get_offset()
    good = CampaignStore.open(old.path)
    assert np.array_equal(good.wall, old.wall) and np.array_equal(good.values, old.values, equal_nan=True)
    raw = bytearray(old.path.read_bytes())
    raw[offset + 5] ^= 0x40
    bad = tmp_path / "flipped.h5"
    bad.write_bytes(bytes(raw))
    with pytest.raises(StoreError, match="damaged store: wall_seconds no longer match"):
        CampaignStore.open(bad)
    r = subprocess.run([sys.executable, "-m", "pydem", "campaign", "status", str(bad)], capture_output=True, text=True)
    assert r.returncode != 0 and "Traceback" not in r.stderr and "damaged store: wall_seconds" in r.stderr
