"""The campaign store: one HDF5 file with the specification, the provenance, every run's
design point, parameters, seed, status, metrics (value and uncertainty), wall time and failure
message. A design point may be run several times with different seeds (replicates); rows are
runs, `point` says which design point each row measures.

Crash safety: the store is small (kilobytes per hundred runs), so every update writes a complete
new file next to it, flushes it to disk and atomically renames it over the old one. A kill at any
moment leaves either the previous or the new store, never a torn one, and no finished run is
lost once `save` has returned. One writer at a time (a lock file next to the store, removed when
the writer finishes); readers only read: a temporary file left by a killed writer is removed by
the next writer, never by a reader (it may be the live writer's file about to be renamed)."""
from __future__ import annotations

import fcntl
import json
import os
import time
from pathlib import Path

import numpy as np

from .spec import CampaignSpec

FORMAT = "pydem-campaign"
FORMAT_VERSION = 3  # 3: per-dataset checksums; 2: `point` per run (replicates); 1: one run per point
DATASETS = ("parameter_names", "parameters", "seed", "point", "status", "wall_seconds", "finished_at", "error",
            "metric_names", "metric_units", "metrics", "metric_uncertainty")
PENDING, DONE, FAILED = 0, 1, 2
STATUS_NAMES = {PENDING: "pending", DONE: "done", FAILED: "failed"}


def _checksums(f) -> dict[str, str]:
    """SHA-256 (16 hex digits) of every dataset's content as read back, and of the attributes that
    define the store: a flipped bit anywhere in them is found on open and named."""
    import hashlib
    out = {}
    for name in DATASETS:
        if name in f:
            v = f[name][()]
            data = json.dumps(_strings(f[name])).encode() if v.dtype == object else np.ascontiguousarray(v).tobytes()
            out[name] = hashlib.sha256(f"{v.dtype.str} {v.shape}".encode() + data).hexdigest()[:16]
    for key in ("spec", "provenance", "batches"):
        out["attribute " + key] = hashlib.sha256(str(f.attrs[key]).encode()).hexdigest()[:16]
    return out


def _strings(dataset) -> list[str]:
    """An h5py string dataset as Python strings (h5py returns bytes for variable-length strings)."""
    return [x.decode() if isinstance(x, bytes) else str(x) for x in dataset[()]]


class StoreError(RuntimeError):
    """A campaign store that cannot be read, written or locked."""


def physics_of(libdem_version: str) -> str:
    """major.minor of a libdem version: runs of two libdem versions that share it are comparable."""
    return ".".join(libdem_version.split(".")[:2])


def check_same_physics(stores, what: str = "calibrate from") -> str:
    """The stores' common libdem major.minor; a StoreError naming them when they differ (results
    of two contact laws in one data set would be fitted as one model)."""
    seen = {}
    for st in stores:
        seen.setdefault(st.physics, []).append(str(st.path))
    if len(seen) > 1:
        detail = "; ".join(f"libdem {v}: {', '.join(paths)}" for v, paths in sorted(seen.items()))
        raise StoreError(f"cannot {what} campaign stores made with different libdem contact laws ({detail}); "
                         f"re-run the older ones with this libdem")
    return next(iter(seen)) if seen else ""


class CampaignStore:
    def __init__(self, path: str | Path, spec: CampaignSpec, provenance: dict):
        self.path = Path(path)
        self.spec, self.provenance = spec, provenance
        self.batches: list[int] = []
        self.params = np.zeros((0, len(spec.names)))
        self.seeds = np.zeros(0, dtype=np.int64)
        self.points = np.zeros(0, dtype=np.int64)
        self.status = np.zeros(0, dtype=np.int8)
        self.wall = np.zeros(0)
        self.finished_at = np.zeros(0)
        self.errors: list[str] = []
        self.metric_names: list[str] = []
        self.metric_units: list[str] = []
        self.values = np.zeros((0, 0))
        self.uncertainty = np.zeros((0, 0))
        self._lock = None

    # ---- size and content ------------------------------------------------------------
    def __len__(self):
        return len(self.seeds)

    @property
    def design_points(self) -> int:
        return int(self.points.max()) + 1 if len(self.points) else 0

    def replicates_of(self) -> np.ndarray:
        """Runs per design point (all statuses)."""
        return np.bincount(self.points, minlength=self.design_points)

    def append(self, params: np.ndarray, seeds: np.ndarray, points: np.ndarray | None = None):
        """Appends runs; `points` None: each row a new design point (a design batch), else the
        design points the rows replicate."""
        n = len(seeds)
        if points is None:
            points = self.design_points + np.arange(n)
            self.batches.append(n)
        self.params = np.vstack([self.params, params])
        self.seeds = np.concatenate([self.seeds, np.asarray(seeds, dtype=np.int64)])
        self.points = np.concatenate([self.points, np.asarray(points, dtype=np.int64)])
        self.status = np.concatenate([self.status, np.zeros(n, dtype=np.int8)])
        self.wall = np.concatenate([self.wall, np.full(n, np.nan)])
        self.finished_at = np.concatenate([self.finished_at, np.full(n, np.nan)])
        self.errors += [""] * n
        self.values = np.vstack([self.values, np.full((n, self.values.shape[1]), np.nan)])
        self.uncertainty = np.vstack([self.uncertainty, np.full((n, self.uncertainty.shape[1]), np.nan)])

    def _column(self, name: str, unit: str) -> int:
        if name not in self.metric_names:
            self.metric_names.append(name)
            self.metric_units.append(unit)
            pad = np.full((len(self), 1), np.nan)
            self.values = np.hstack([self.values, pad])
            self.uncertainty = np.hstack([self.uncertainty, pad.copy()])
        return self.metric_names.index(name)

    def record_done(self, i: int, metrics: dict, wall: float):
        """metrics: {name: (value, uncertainty, unit)}."""
        for name, (v, u, unit) in metrics.items():
            j = self._column(name, unit)
            self.values[i, j], self.uncertainty[i, j] = v, u
        self.status[i], self.wall[i], self.finished_at[i], self.errors[i] = DONE, wall, time.time(), ""

    def record_failure(self, i: int, message: str, wall: float):
        self.status[i], self.wall[i], self.finished_at[i], self.errors[i] = FAILED, wall, time.time(), message

    def pending(self, retry_failed: bool = False) -> list[int]:
        todo = (self.status == PENDING) | ((self.status == FAILED) if retry_failed else False)
        return [int(i) for i in np.flatnonzero(todo)]

    @property
    def rig_protocol(self) -> int:
        """The rig protocol the runs were measured with (stores from before the stamp: 1)."""
        return int(self.provenance.get("rig_protocol", 1))

    @property
    def physics(self) -> str:
        """The contact-law generation the runs were made with: libdem's major.minor version (a
        minor release changes results, e.g. 0.2 the Coulomb cap in damped sliding contacts)."""
        return physics_of(str(self.provenance.get("libdem", "0.1.0")))

    def counts(self) -> dict[str, int]:
        return {name: int((self.status == s).sum()) for s, name in STATUS_NAMES.items()}

    def _metric_index(self, metric: str) -> int:
        if metric not in self.metric_names:
            raise StoreError(f"{self.path}: no metric {metric!r} (has: {', '.join(self.metric_names) or 'none yet'})")
        return self.metric_names.index(metric)

    def table(self, metric: str, only_done: bool = True):
        """(inputs, values, uncertainties) of one metric over the finished runs with a finite value."""
        j = self._metric_index(metric)
        ok = np.isfinite(self.values[:, j]) & ((self.status == DONE) if only_done else True)
        return self.params[ok], self.values[ok, j], self.uncertainty[ok, j]

    def point_table(self, metric: str, rows: np.ndarray | None = None):
        """One metric per design point: (inputs, mean over the point's finished replicates,
        replicate count, pooled replicate standard deviation of one run (nan without replicates)).
        rows: a (runs,) mask of the runs that count besides (default: every finished one)."""
        j = self._metric_index(metric)
        ok = np.isfinite(self.values[:, j]) & (self.status == DONE)
        if rows is not None:
            ok &= rows
        x_runs, y_runs = self.params[ok], self.values[ok, j]
        pts = self.points[ok]
        uniq, inverse, counts = np.unique(pts, return_inverse=True, return_counts=True)
        means = np.bincount(inverse, weights=y_runs) / counts
        x = np.empty((len(uniq), x_runs.shape[1]))
        x[inverse] = x_runs
        dev2 = (y_runs - means[inverse]) ** 2
        dof = int((counts - 1).sum())
        pooled_sd = float(np.sqrt(dev2.sum() / dof)) if dof > 0 else float("nan")
        return x, means, counts, pooled_sd

    # ---- file ------------------------------------------------------------------------
    def lock(self):
        """Exclusive writer lock; a second `campaign run` on the same store stops with an error.
        The writer alone cleans up what an earlier, killed writer left (its temporary files);
        readers never delete or modify anything."""
        lock_path = str(self.path) + ".lock"
        for _ in range(10):
            fh = open(lock_path, "a+")
            try:
                fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                fh.close()
                raise StoreError(f"{self.path} is being written by another campaign process (lock {lock_path})") from None
            try:  # the file may have been removed by a writer that finished meanwhile: lock the live one
                same = os.fstat(fh.fileno()).st_ino == os.stat(lock_path).st_ino
            except FileNotFoundError:
                same = False
            if same:
                self._lock = fh
                break
            fh.close()
        else:
            raise StoreError(f"{self.path}: could not take the writer lock {lock_path}")
        for stale in self.path.parent.glob(f".{self.path.name}.tmp-*"):  # a save interrupted by a kill
            stale.unlink(missing_ok=True)

    def unlock(self):
        """Releases the writer lock and removes the lock file (removed while still held, so no
        other writer can hold a lock on a file that is gone)."""
        if self._lock is not None:
            try:
                os.unlink(str(self.path) + ".lock")
            except FileNotFoundError:
                pass
            fcntl.flock(self._lock, fcntl.LOCK_UN)
            self._lock.close()
            self._lock = None

    def save(self):
        import h5py
        tmp = self.path.with_name(f".{self.path.name}.tmp-{os.getpid()}")
        with h5py.File(tmp, "w") as f:
            f.attrs["format"], f.attrs["format_version"] = FORMAT, FORMAT_VERSION
            f.attrs["spec"] = self.spec.to_json()
            f.attrs["provenance"] = json.dumps(self.provenance, sort_keys=True, default=str)
            f.attrs["batches"] = json.dumps(self.batches)
            f.attrs["saved_at"] = time.time()
            f.create_dataset("parameter_names", data=np.array(self.spec.names, dtype=object), dtype=h5py.string_dtype())
            f.create_dataset("parameters", data=self.params)
            f.create_dataset("seed", data=self.seeds)
            f.create_dataset("point", data=self.points)
            f.create_dataset("status", data=self.status)
            f.create_dataset("wall_seconds", data=self.wall)
            f.create_dataset("finished_at", data=self.finished_at)
            f.create_dataset("error", data=np.array(self.errors, dtype=object), dtype=h5py.string_dtype())
            f.create_dataset("metric_names", data=np.array(self.metric_names, dtype=object), dtype=h5py.string_dtype())
            f.create_dataset("metric_units", data=np.array(self.metric_units, dtype=object), dtype=h5py.string_dtype())
            f.create_dataset("metrics", data=self.values)
            f.create_dataset("metric_uncertainty", data=self.uncertainty)
            f.attrs["checksums"] = json.dumps(_checksums(f))
            f.flush()
            os.fsync(f.id.get_vfd_handle())
        os.replace(tmp, self.path)
        dirfd = os.open(self.path.parent, os.O_RDONLY)
        try:
            os.fsync(dirfd)
        finally:
            os.close(dirfd)

    @classmethod
    def open(cls, path: str | Path) -> "CampaignStore":
        import h5py
        path = Path(path)
        if not path.exists():
            raise StoreError(f"{path}: no such campaign store")
        try:
            with h5py.File(path, "r") as f:
                if f.attrs.get("format") != FORMAT:
                    raise StoreError(f"{path}: not a pydem campaign store (format attribute {f.attrs.get('format')!r})")
                if int(f.attrs["format_version"]) > FORMAT_VERSION:
                    raise StoreError(f"{path}: store format {f.attrs['format_version']} is newer than this pydem reads")
                if "checksums" in f.attrs and int(f.attrs["format_version"]) >= 3:  # none before format 3
                    stored, now = json.loads(f.attrs["checksums"]), _checksums(f)
                    bad = [k for k in sorted(set(stored) | set(now)) if stored.get(k) != now.get(k)]
                    if bad:
                        raise StoreError(f"{path}: damaged store: {', '.join(bad)} no longer match(es) the checksum "
                                         f"written with it (a flipped bit on disk or in a copy); restore it from a "
                                         f"good copy")
                s = cls(path, CampaignSpec.from_json(f.attrs["spec"]), json.loads(f.attrs["provenance"]))
                s.batches = json.loads(f.attrs["batches"])
                s.params = f["parameters"][()]
                s.seeds, s.status = f["seed"][()], f["status"][()]
                # stores from before replicates: one run per design point
                s.points = f["point"][()] if "point" in f else np.arange(len(s.seeds), dtype=np.int64)
                s.wall, s.finished_at = f["wall_seconds"][()], f["finished_at"][()]
                s.errors = _strings(f["error"])
                s.metric_names = _strings(f["metric_names"])
                s.metric_units = _strings(f["metric_units"])
                s.values, s.uncertainty = f["metrics"][()], f["metric_uncertainty"][()]
        except StoreError:
            raise
        except (OSError, KeyError, ValueError, json.JSONDecodeError) as exc:
            raise StoreError(f"{path}: unreadable campaign store ({type(exc).__name__}: {exc})") from None
        n = len(s.seeds)
        if not (s.params.shape == (n, len(s.spec.names)) and len(s.status) == n and s.values.shape[0] == n
                and len(s.points) == n and sum(s.batches) == s.design_points and len(s.errors) == n):
            raise StoreError(f"{path}: inconsistent campaign store (array lengths disagree)")
        return s
