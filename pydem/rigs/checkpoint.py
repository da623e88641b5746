"""Checkpoints of long rig runs: the domain's HDF5 snapshot (a bitwise restart, docs/snapshot.md)
beside the protocol's own state as JSON, in one directory per run.

<dir>/<rig>.h5 and <dir>/<rig>.json; the JSON is written last, by rename, so a checkpoint
exists only once both are complete, and it carries the signature of the configuration,
parameters and seed it belongs to (a checkpoint of other settings is refused by name).

A snapshot is taken only right after a step, before anything changes the domain (a snapshot of
invalid forces would recompute them, and a run that saves would then differ from one that does
not): the rigs save from Stepper.advance, between the step and the chunk's callback."""
from __future__ import annotations

import json
import os
import time
from pathlib import Path

from .config import describe


class CheckpointStop(Exception):
    """Raised inside a run when it has saved a checkpoint at its `stop_at` time: the rig returns None."""


def signature(rig, params, seed: int) -> str:
    """What a checkpoint must match to be resumed: the configuration (threads aside), the
    parameters, the seed and the rig's protocol version."""
    cfg = {k: v if isinstance(v, (int, float, str, bool)) else str(v) for k, v, _, _ in describe(rig.config)
           if k != "num_threads"}
    return json.dumps({"rig": rig.name, "config": cfg, "params": str(params), "seed": seed, "protocol": rig.protocol},
                      sort_keys=True)


class Checkpoint:
    def __init__(self, directory, name: str, signature: str, every: float = 600.0, stop_at: float | None = None):
        """every: seconds of wall time between saves; stop_at: save and stop at the first chunk
        that reaches this simulated time (a run split across batch jobs)."""
        self.dir = Path(directory)
        self.name, self.signature = name, signature
        self.every, self.stop_at = every, stop_at
        self.snapshot, self.state = self.dir / f"{name}.h5", self.dir / f"{name}.json"
        self.last_save = time.perf_counter()

    def load(self) -> dict | None:
        """The saved state (with "snapshot": the snapshot's path), or None when there is none."""
        if not self.state.exists():
            return None
        try:
            state = json.loads(self.state.read_text())
        except (OSError, ValueError) as exc:
            raise ValueError(f"{self.state}: not a readable checkpoint ({exc}); remove the directory to start afresh") from exc
        if state.get("signature") != self.signature:
            raise ValueError(f"{self.state}: a checkpoint of another configuration, parameter set or seed "
                             f"(remove it, or resume with the settings that made it)")
        if not self.snapshot.exists():
            raise ValueError(f"{self.state}: its snapshot {self.snapshot.name} is missing; remove the directory to start afresh")
        state["snapshot"] = str(self.snapshot)
        return state

    def due(self, sim_time: float) -> bool:
        return (self.stop_at is not None and sim_time >= self.stop_at) or time.perf_counter() - self.last_save >= self.every

    def stopping(self, sim_time: float) -> bool:
        return self.stop_at is not None and sim_time >= self.stop_at

    def save(self, domain, state: dict):
        self.dir.mkdir(parents=True, exist_ok=True)
        tmp = self.dir / f".{self.name}.h5.tmp"
        domain.write_snapshot(tmp)
        os.replace(tmp, self.snapshot)
        tmp = self.dir / f".{self.name}.json.tmp"
        tmp.write_text(json.dumps(dict(state, signature=self.signature)))
        os.replace(tmp, self.state)
        self.last_save = time.perf_counter()

    def remove(self):
        for f in (self.state, self.snapshot):
            f.unlink(missing_ok=True)
