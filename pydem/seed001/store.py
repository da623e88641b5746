"""The frame store of seed 001's study: labelled hopper frames (the rig draws them, pydem.rigs.frames
crops and greys them), stored as compressed uint8 arrays in one HDF5 file, one group per case,
each frame labelled with its time, the remaining discharge time and the number ratio of remaining
particles (NRRP). A case group is written whole or not at all, so a killed campaign resumes with
the cases it lacks. And what a stored frame shows of each sphere species (species_masks)."""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..rigs.frames import COARSE_GREYS, FINE_GREYS, WALL_GREY


def species_masks(frames: np.ndarray) -> np.ndarray:
    """(n, H, W) uint8 grey frames of the hopper rig -> bool (n, 2, H, W): [fine, coarse] — the
    pixels only a fine sphere's disk, and only a coarse one's, can have (FINE_GREYS,
    COARSE_GREYS; the wall grey left out). What the front view shows of each species."""
    f = np.asarray(frames)
    if f.dtype != np.uint8 or f.ndim != 3:
        raise ValueError(f"species_masks: (n, H, W) uint8 grey frames are needed, got {f.dtype} {f.shape}")
    fine = (f >= FINE_GREYS[0]) & (f <= FINE_GREYS[1])
    coarse = (f >= COARSE_GREYS[0]) & (f <= COARSE_GREYS[1]) & (f != WALL_GREY)
    return np.stack([fine, coarse], axis=1)


class FrameStore:
    """frames/<case>: dataset `frames` (n, 224, 224) uint8 (gzip, one frame per chunk) and
    `time`, `remaining_time`, `nrrp` (n,); attributes: the case's discharge time and parameters."""

    def __init__(self, path: str | os.PathLike):
        self.path = Path(path)

    def cases(self) -> list[str]:
        import h5py
        if not self.path.exists():
            return []
        with h5py.File(self.path, "r") as f:
            return sorted(k for k in f.get("frames", {}) if f["frames"][k].attrs.get("complete", False))

    def write_case(self, case: str, frames: np.ndarray, time: np.ndarray, discharge_time: float, nrrp: np.ndarray,
                   attrs: dict | None = None):
        """One case, whole: written under a temporary name and renamed, so a reader (or a resumed
        campaign) never sees half a case."""
        import h5py
        frames = np.asarray(frames, np.uint8)
        if frames.ndim != 3 or len(frames) != len(time) or len(time) != len(nrrp):
            raise ValueError(f"write_case {case}: frames (n, H, W) with n times and n NRRP values are needed")
        with h5py.File(self.path, "a") as f:
            g = f.require_group("frames")
            tmp = f"{case}.partial"
            if tmp in g:
                del g[tmp]
            c = g.create_group(tmp)
            c.create_dataset("frames", data=frames, chunks=(1,) + frames.shape[1:], compression="gzip",
                             compression_opts=4, shuffle=True)
            c.create_dataset("time", data=np.asarray(time, float))
            c.create_dataset("remaining_time", data=float(discharge_time) - np.asarray(time, float))
            c.create_dataset("nrrp", data=np.asarray(nrrp, float))
            c.attrs["discharge_time"] = float(discharge_time)
            for k, v in (attrs or {}).items():
                c.attrs[k] = v
            c.attrs["complete"] = True
            if case in g:
                del g[case]
            g.move(tmp, case)
            if case in f.get("failed", {}):  # run again and stored: no longer a failure
                del f["failed"][case]

    def write_failure(self, case: str, reason: str, attrs: dict | None = None):
        """A case that ran and could not be stored (a runaway overlap, a bed that did not empty),
        kept with its reason under failed/<case> so a rerun reports it instead of losing it."""
        import h5py
        with h5py.File(self.path, "a") as f:
            g = f.require_group("failed")
            if case in g:
                del g[case]
            c = g.create_group(case)
            c.attrs["reason"] = reason
            for k, v in (attrs or {}).items():
                c.attrs[k] = v

    def failures(self) -> dict:
        """{case: its attributes, "reason" among them} of the failures kept (write_failure)."""
        import h5py
        if not self.path.exists():
            return {}
        with h5py.File(self.path, "r") as f:
            return {k: dict(g.attrs) for k, g in f.get("failed", {}).items()}

    def attrs_of(self, case: str) -> dict:
        """A stored case's attributes, without reading its frames."""
        import h5py
        with h5py.File(self.path, "r") as f:
            return dict(f["frames"][case].attrs)

    def read_case(self, case: str) -> dict:
        import h5py
        with h5py.File(self.path, "r") as f:
            c = f["frames"][case]
            return {k: c[k][()] for k in ("frames", "time", "remaining_time", "nrrp")} | dict(c.attrs)
