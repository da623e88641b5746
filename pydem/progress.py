"""Progress lines: one refreshed line on stderr (ProgressLine), and what each long job puts on
it — a rig's simulated time (RunProgress), a campaign's runs (CampaignProgress), a network's
epochs (EpochProgress, one line per epoch through the caller's `say`)."""
from __future__ import annotations

import math
import sys
import time


class ProgressLine:
    """One line rewritten in place (carriage return), at most once per `interval` seconds, ended
    with a newline by done() when anything was shown; quiet shows nothing."""

    def __init__(self, stream=None, interval: float = 0.0, quiet: bool = False):
        self.stream = sys.stderr if stream is None else stream
        self.interval, self.quiet = interval, quiet
        self.last, self.shown = -math.inf, False

    def show(self, text: str):
        now = time.perf_counter()
        if self.quiet or now - self.last < self.interval:
            return
        self.last, self.shown = now, True
        self.stream.write("\r" + text)
        self.stream.flush()

    def done(self):
        if self.shown:
            self.stream.write("\n")
            self.shown = False


class RunProgress(ProgressLine):
    """A rig's progress callback: simulated time, rate and ETA, at most 4 times a second."""

    def __init__(self, stream=None):
        super().__init__(stream, interval=0.25)

    def __call__(self, sim_time: float, planned: float, info: dict):
        wall = max(info.get("wall", 0.0), 1e-9)
        rate = sim_time / wall
        eta = (planned - sim_time) / rate if rate > 0 and planned > sim_time else 0.0
        self.show(f"  t = {sim_time:7.3f} s of <= {planned:.2f} s   {rate:8.4f} s/s   "
                  f"{info.get('steps', 0) / wall / 1e3:7.1f} k steps/s   {info.get('particles', 0)} particles   "
                  f"{info.get('threads', 1)} thread(s)   ETA <= {eta:6.0f} s ")


class CampaignProgress(ProgressLine):
    """A campaign's runs: done/total, rate, ETA of this invocation and failures."""

    def __init__(self, total: int, already: int, stream=None, quiet: bool = False):
        super().__init__(stream, quiet=quiet)
        self.total, self.already = total, already
        self.t0, self.done_runs, self.failed = time.perf_counter(), 0, 0

    def update(self, ok: bool):
        self.done_runs += 1
        self.failed += 0 if ok else 1
        el = time.perf_counter() - self.t0
        rate = self.done_runs / el if el > 0 else 0.0
        left = self.total - self.already - self.done_runs
        eta = left / rate if rate > 0 else math.inf
        self.show(f"  {self.already + self.done_runs}/{self.total} runs   {rate * 60:6.2f} runs/min   "
                  f"ETA {eta / 60:6.1f} min   failures {self.failed} ")

    def close(self):
        self.done()


class EpochProgress:
    """A training's progress callback (nn.training.fit): one line per epoch through `say`."""

    def __init__(self, say=print):
        self.say = say

    def __call__(self, epoch: int, epochs: int, loss: float, val: float, rate: float, left: float):
        self.say(f"  epoch {epoch}/{epochs}  loss {loss:.4g}  validation {val:.4g}  {rate:.0f} frames/s  "
                 f"{left / 60:.1f} min left")
