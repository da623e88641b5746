"""Running a campaign: every sample goes through the pure function `simulate`, locally in a
process pool (default) or on a Dask cluster; each finished run is saved to the store at once."""
from __future__ import annotations

import os
import sys
import time
import traceback
from pathlib import Path

import numpy as np

from ..progress import CampaignProgress
from ..provenance import provenance
from ..rigs import RIGS
from ..rigs.config import describe
from .design import at_neutral, design_points
from .spec import CampaignSpec
from .store import DONE, FAILED, STATUS_NAMES, CampaignStore, StoreError, physics_of


def simulate(spec_json: str, values: dict[str, float], seed: int) -> dict:
    """One rig run: parameters in, metrics out ({name: (value, uncertainty, unit)}), or the
    error message, with its wall and CPU seconds (the worker process's: a run is one thread, so its
    CPU time does not count other work on the machine). Pure (depends on its arguments only); runs
    in a worker process."""
    t0, c0 = time.perf_counter(), time.process_time()
    try:
        spec = CampaignSpec.from_json(spec_json)
        cfg = spec.config(values)
        if "num_threads" not in spec.fixed:
            cfg.num_threads = 1  # parallelism comes from running samples side by side
        result = RIGS[spec.rig][0](cfg).run(seed=seed)
        metrics = {k: (float(m.value), float(m.uncertainty), m.unit) for k, m in result.metrics.items()
                   if isinstance(m.value, (int, float))}
        return {"metrics": metrics, "wall": time.perf_counter() - t0, "cpu": time.process_time() - c0}
    except Exception as exc:  # recorded in the store; the campaign goes on
        last = traceback.extract_tb(exc.__traceback__)[-1] if exc.__traceback__ else None
        where = f" (at {Path(last.filename).name}:{last.lineno})" if last else ""
        return {"error": f"{type(exc).__name__}: {exc}{where}", "wall": time.perf_counter() - t0,
                "cpu": time.process_time() - c0}


def sample_seed(campaign_seed: int, index: int) -> int:
    return int(np.random.SeedSequence([campaign_seed, index]).generate_state(1)[0])


def resolved_config(spec) -> dict:
    """Every knob of the rig as this code resolves the spec's preset and fixed settings (at the
    centre of the ranges; the varied keys and the thread count left out), so a store says what
    "preset default" meant when it was run."""
    centre = {k: 0.5 * (lo + hi) for k, (lo, hi) in spec.ranges.items()}
    return {key: (value if isinstance(value, (int, float, str, bool)) else str(value))
            for key, value, _, _ in describe(spec.config(centre)) if key not in spec.ranges
            and key.split(".")[-1] not in spec.ranges}


# knobs that do not change a run's physics: threads, frames, and max_overlap_ratio, which only
# stops a blown-up run (every run that stays below it is the same; a run that stops leaves no values)
NOT_PHYSICS = {"num_threads", "frame_interval", "max_overlap_ratio"}


def config_drift(store) -> dict[str, tuple]:
    """{knob: (value when the store was run, value now)} for every knob whose resolution of the
    store's preset has changed since, apart from NOT_PHYSICS (so a raised blow-up bound lets a
    store retry its stopped runs). Knobs added after the store was run are left out: a new knob's
    default keeps the rig as it was."""
    then = store.provenance.get("rig_config")
    if not then:
        return {}
    now = resolved_config(store.spec)
    return {k: (then[k], now.get(k)) for k in sorted(then) if k not in NOT_PHYSICS and then[k] != now.get(k)}


class Campaign:
    def __init__(self, store: CampaignStore):
        self.store = store

    @classmethod
    def create(cls, path: str | Path, spec: CampaignSpec) -> "Campaign":
        path = Path(path)
        if path.exists():
            raise StoreError(f"{path} exists already: run it again to continue, or choose another name")
        prov = provenance()
        prov["rig_protocol"] = RIGS[spec.rig][0].protocol
        prov["rig_config"] = resolved_config(spec)
        store = CampaignStore(path, spec, prov)
        c = cls(store)
        c.grow(spec.samples, spec.replicates)
        store.save()
        return c

    @classmethod
    def open(cls, path: str | Path) -> "Campaign":
        return cls(CampaignStore.open(path))

    def grow(self, total: int | None = None, replicates: int | None = None):
        """Extends the design to `total` design points and/or runs every point `replicates` times
        (existing runs and results unchanged). New rows run replicate by replicate, so a partly
        run extension is a complete design with fewer replicates."""
        s, spec = self.store, self.store.spec
        n0 = s.design_points
        if total is not None and total > n0:
            batches = s.batches + [total - n0]
            pts = design_points(spec.design, spec.ranges, n0, total, spec.seed, batches, spec.log_scale)
            if spec.neutral:
                pts = at_neutral(pts, spec.names, spec.neutral, n0)
            s.append(pts, self._seeds(total - n0))
            spec.samples = total
        want = max(replicates or 1, spec.replicates)
        have = s.replicates_of()
        first = np.unique(s.points, return_index=True)[1]
        for r in range(1, want):
            short = np.flatnonzero(have <= r)
            if len(short):
                s.append(s.params[first[short]], self._seeds(len(short)), points=short)
                have[short] += 1
        spec.replicates = want

    def _seeds(self, n: int) -> np.ndarray:
        """Seeds of the next n rows: one per run, so replicates differ."""
        start = len(self.store)
        return np.array([sample_seed(self.store.spec.seed, i) for i in range(start, start + n)])

    def run(self, workers: int | None = None, dask: str | None = None, retry_failed: bool = False,
            max_runs: int | None = None, quiet: bool = False, points: int | None = None,
            rerun: list[int] | None = None) -> dict[str, int]:
        """Runs the pending samples (and failed ones with retry_failed); saves after each. `points`:
        only the runs of the first `points` design points (a Sobol design's first 2^k points are
        balanced: replicate them before extending them), the rest stay pending. `rerun`: only these
        runs (store indices), whatever their status, their results replaced by this code's — a rig
        fix that changes what some finished runs measure (same parameters and seeds; the session
        records which)."""
        s = self.store
        if rerun is not None:
            bad = [i for i in rerun if not 0 <= i < len(s)]
            if bad:
                raise StoreError(f"{s.path}: no run {bad[0]} to run again (the store has runs 0-{len(s) - 1})")
        rig_cls = RIGS[s.spec.rig][0]
        made_with = s.rig_protocol
        if made_with != rig_cls.protocol:
            raise StoreError(f"{s.path}: its runs were measured with {s.spec.rig} protocol {made_with}, this code measures "
                             f"with protocol {rig_cls.protocol} (see the rig's `protocol` note); adding runs would mix two "
                             f"definitions of the metrics in one data set. Start a new store, or continue it from commit "
                             f"{s.provenance.get('git_commit', 'unknown')}.")
        drift = config_drift(s)
        if drift:
            raise StoreError(f"{s.path}: the {s.spec.preset!r} preset has changed since this store was run ("
                             + "; ".join(f"{k}: {a} then, {b} now" for k, (a, b) in drift.items())
                             + "): adding runs would mix two rigs in one data set. Start a new store, or continue it "
                             f"from commit {s.provenance.get('git_commit', 'unknown')}.")
        from .. import LIBDEM_VERSION
        if s.physics != physics_of(LIBDEM_VERSION):
            raise StoreError(f"{s.path}: its runs were made with libdem {s.provenance.get('libdem', '0.1.0')}, this is "
                             f"libdem {LIBDEM_VERSION}, whose contact law gives different results (CHANGELOG.md); adding "
                             f"runs would mix two models in one data set. Start a new store.")
        s.lock()
        try:
            if rerun is not None:
                todo = sorted(set(int(i) for i in rerun))[:max_runs]
            else:
                todo = [i for i in s.pending(retry_failed) if points is None or s.points[i] < points][:max_runs]
            if not todo:
                return s.counts()
            now = provenance()  # every session that adds runs is recorded (code version, machine)
            s.provenance.setdefault("sessions", []).append(
                {k: now[k] for k in ("git_commit", "host", "machine", "created", "command")} | {"pending": len(todo)}
                | ({"rerun": todo} if rerun is not None else {}))
            s.save()  # a grown design and this session are on disk before any run starts
            spec_json = s.spec.to_json()
            if rerun is not None:  # finished runs that this invocation leaves alone
                already = int(np.count_nonzero(s.status != 0) - np.count_nonzero(s.status[todo] != 0))
            else:
                already = int((s.status == DONE).sum() + ((s.status == FAILED).sum() if not retry_failed else 0))
            progress = CampaignProgress(already + len(todo), already, quiet=quiet)  # ETA of this invocation
            args = {i: (spec_json, dict(zip(s.spec.names, map(float, s.params[i]))), int(s.seeds[i])) for i in todo}
            try:
                if dask:
                    self._run_dask(dask, args, progress)
                else:
                    self._run_local(workers, args, progress)
            finally:
                progress.close()
            return s.counts()
        finally:
            s.unlock()

    def _finish(self, i: int, out: dict, progress: CampaignProgress):
        if "error" in out:
            self.store.record_failure(i, out["error"], out["wall"])
        else:
            self.store.record_done(i, out["metrics"], out["wall"])
        self.store.save()
        progress.update("error" not in out)

    def default_workers(self) -> int:
        """Runs side by side by default: one per core for the runs' thread count (on 2 cores two
        1-thread runs beat one 2-thread run: studies/JOURNAL.md, campaign throughput)."""
        threads = int(self.store.spec.fixed.get("num_threads", 1))
        return max(1, (os.cpu_count() or 1) // threads)

    def _run_local(self, workers, args, progress):
        from .workers import WorkerStartError, run_local
        workers = workers or self.default_workers()

        def say(msg):
            sys.stderr.write(f"\n  {msg}\n")

        try:
            run_local(args, simulate, min(workers, len(args)), lambda i, out: self._finish(i, out, progress), say)
        except WorkerStartError as exc:
            raise StoreError(f"{self.store.path}: {exc}") from None

    def _run_dask(self, address, args, progress):
        from .workers import WorkerStartError, run_dask
        try:
            run_dask(address, args, simulate, lambda i, out: self._finish(i, out, progress), "pydem-sample")
        except WorkerStartError as exc:
            raise StoreError(str(exc)) from None

    def status_text(self) -> str:
        s = self.store
        c = s.counts()
        spec = s.spec
        lines = [f"campaign {s.path}: rig {spec.rig} (preset {spec.preset}), design {spec.design} seed {spec.seed}",
                 f"  design points {s.design_points} x {spec.replicates} replicate(s) = {len(s)} runs: done {c['done']}, "
                 f"failed {c['failed']}, pending {c['pending']}"]
        done = s.status == DONE
        if spec.replicates > 1 and done.any():  # how far each replicate round has got
            finished = np.bincount(s.points[done], minlength=s.design_points)
            lines.append("  design points with " + ", ".join(f"{k} finished run(s): {int((finished == k).sum())}"
                                                         for k in range(int(finished.max()) + 1)))
        if done.any():
            w = s.wall[done]
            lines.append(f"  wall time per run: median {np.median(w):.1f} s, total {w.sum() / 3600:.2f} h of worker time")
            workers = self.default_workers()
            rate = workers * 3600.0 / float(np.mean(w))  # the mean, not the median: slow runs cost their full time
            left = f", the {c['pending']} pending in about {c['pending'] / rate:.1f} h" if c["pending"] else ""
            lines.append(f"  throughput: {rate:.1f} runs/h at the recorded mean run time with {workers} worker(s) of "
                         f"{int(spec.fixed.get('num_threads', 1))} thread(s) (the default here){left}")
        lines.append("  ranges: " + ", ".join(f"{k} [{lo:g}, {hi:g}]" for k, (lo, hi) in spec.ranges.items()))
        if spec.fixed:
            lines.append("  fixed: " + ", ".join(f"{k}={v}" for k, v in spec.fixed.items()))
        lines.append("  metrics: " + (", ".join(s.metric_names) or "none yet") +
                     f" (rig protocol {s.rig_protocol}; this code: {RIGS[spec.rig][0].protocol})")
        for i in np.flatnonzero(s.status == FAILED)[:10]:
            lines.append(f"  failed #{i}: {s.errors[i]}")
        p = s.provenance
        lines.append(f"  provenance: pydem {p.get('pydem')} libdem {p.get('libdem')} commit {p.get('git_commit')} "
                     f"on {p.get('host')} ({p.get('machine')}), {p.get('created')}")
        lines.append(f"  command: {p.get('command')}")
        return "\n".join(lines)

    def export_csv(self, path: str | Path):
        s = self.store
        import csv
        with open(path, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["index", "point", "seed", "status"] + s.spec.names + s.metric_names
                       + [m + "_uncertainty" for m in s.metric_names] + ["wall_seconds", "error"])
            for i in range(len(s)):
                w.writerow([i, int(s.points[i]), int(s.seeds[i]), STATUS_NAMES[int(s.status[i])]]
                           + [repr(float(x)) for x in s.params[i]] + [repr(float(x)) for x in s.values[i]]
                           + [repr(float(x)) for x in s.uncertainty[i]] + [repr(float(s.wall[i])), s.errors[i]])
