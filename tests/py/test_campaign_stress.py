"""A campaign under fire: `campaign status` polled continuously while single workers and the
campaign itself are killed at random moments (bounded: a few kills, under a minute). Checks
that every run ever seen finished stays in the store with the same result, that the store
always opens, that killed campaigns leave no worker processes behind, that a lost worker costs
one retried run and never the campaign, and that no lock or temporary file is left at the end."""
import os
import random
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from pydem.campaign import Campaign, CampaignStore, StoreError
from pydem.campaign.store import DONE

from test_campaign import ROOT, write_toml


def children_of(pid: int) -> list[int]:
    kids = []
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                fields = (d / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid:
                kids.append(int(d.name))
    return kids


def alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def start_campaign(toml, store):
    return subprocess.Popen([sys.executable, "-m", "pydem", "campaign", "run", str(toml), "--store", str(store),
                             "--workers", "2"], cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


@pytest.mark.slow
def test_kills_and_polling_lose_nothing(tmp_path):
    rng = random.Random(11)
    toml = write_toml(tmp_path / "c.toml", samples=10)
    store = tmp_path / "c.h5"
    seen: dict[int, tuple] = {}  # run -> metrics row, as first seen finished by a reader
    stop = threading.Event()
    poll_errors, polls = [], [0]

    def poll():
        while not stop.is_set():
            if store.exists():
                try:
                    s = CampaignStore.open(store)
                except StoreError as exc:
                    poll_errors.append(str(exc))
                    continue
                for i in np.flatnonzero(s.status == DONE):
                    seen.setdefault(int(i), tuple(np.round(s.values[i], 12)))
                polls[0] += 1
            time.sleep(0.01)

    poller = threading.Thread(target=poll, daemon=True)
    poller.start()
    worker_kills = campaign_kills = 0
    # the first worker kill is certain, at the n-th poll that sees workers (0.6-2.4 s into their
    # life): left to the 4 % draws alone, a fast machine sometimes finished with none
    first_kill_poll, kid_polls = rng.randint(3, 12), 0
    orphans = []
    t_end = time.time() + 150
    try:
        for attempt in range(6):
            proc = start_campaign(toml, store)
            kill_campaign_at = None
            while proc.poll() is None and time.time() < t_end:
                time.sleep(0.2)
                # the campaign is killed (twice in all) a random moment after the readers saw a
                # few more runs finish: never after it has finished, however fast the machine
                if kill_campaign_at is None and campaign_kills < 2 and len(seen) >= 2 + 3 * campaign_kills:
                    kill_campaign_at = time.time() + rng.uniform(0.2, 1.5)
                kids = [k for k in children_of(proc.pid) if alive(k)]
                kid_polls += bool(kids)
                if worker_kills < 3 and kids and (rng.random() < 0.04 or (worker_kills == 0 and kid_polls >= first_kill_poll)):
                    os.kill(rng.choice(kids), signal.SIGKILL)  # as the out-of-memory killer would
                    worker_kills += 1
                if kill_campaign_at and time.time() > kill_campaign_at:
                    orphans += kids
                    proc.kill()
                    campaign_kills += 1
                    break
            proc.wait(timeout=60)
            out = proc.stdout.read()
            if proc.returncode == 0:
                break
            assert proc.returncode == -signal.SIGKILL, out  # only our kills may stop it
    finally:
        stop.set()
        poller.join()
    assert proc.returncode == 0, "campaign did not finish within the time bound"
    time.sleep(2.0)
    assert not [k for k in orphans if alive(k)], "workers of a killed campaign are still running"
    assert not poll_errors, poll_errors[:3]
    assert polls[0] > 50
    final = Campaign.open(store).store
    counts = final.counts()  # a run whose worker was killed twice is recorded failed, with the reason
    assert counts["pending"] == 0 and counts["done"] + counts["failed"] == 10 and counts["failed"] <= 1, counts
    assert all("worker process died" in final.errors[i] for i in np.flatnonzero(final.status != DONE))
    for i, row in seen.items():  # every run a reader saw finished is there, unchanged
        assert final.status[i] == DONE and tuple(np.round(final.values[i], 12)) == row
    assert not list(tmp_path.glob(".c.h5.tmp-*")) and not (tmp_path / "c.h5.lock").exists()
    assert worker_kills >= 1 and campaign_kills >= 1


def test_a_result_larger_than_the_pipe_reaches_the_parent():
    """A worker's result far beyond the pipe's 64 KiB buffer (a hopper's frames are megabytes) is
    read while the worker is still sending it: before, the worker blocked in its send and the
    parent waited for it to exit, for ever. Run in a child with a time limit, so a deadlock fails."""
    code = ("import numpy as np\nfrom pydem.campaign.workers import run_local\ngot = {}\n"
            "run_local({0: ((2_000_000,),), 1: ((10,),), 2: ((300_000,),)}, np.ones, 2, lambda i, r: got.update({i: r.sum()}))\n"
            "assert got == {0: 2e6, 1: 10.0, 2: 3e5}, got\nprint('ok')\n")
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120,
                       env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert r.returncode == 0 and "ok" in r.stdout, r.stderr[-2000:]
