"""What a rig run returns: metrics with uncertainty, time series, frames, and how the run went."""
from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np


@dataclass
class Metric:
    value: float
    uncertainty: float  # one standard error (block averages) or a fit's standard error
    unit: str = ""
    note: str = ""

    def __str__(self):
        u = f" ± {self.uncertainty:.3g}" if self.uncertainty == self.uncertainty and self.uncertainty > 0 else ""
        return f"{self.value:.5g}{u} {self.unit}".rstrip()


@dataclass
class RigResult:
    rig: str
    metrics: dict[str, Metric] = field(default_factory=dict)
    series: dict[str, np.ndarray] = field(default_factory=dict)
    frames: list[str] = field(default_factory=list)
    info: dict = field(default_factory=dict)  # particle count, steps, wall time, settings
    provenance: dict = field(default_factory=dict)  # config, parameters, seed, versions (set by the caller)
    images: np.ndarray | None = None  # frames kept in memory (hopper, images=True): (n, 224, 224) uint8, not saved

    def summary(self) -> str:
        lines = [f"{self.rig}: {self.info.get('particles', '?')} particles, {self.info.get('steps', '?')} steps, "
                 f"{self.info.get('wall_seconds', float('nan')):.1f} s wall"]
        for k, m in self.metrics.items():
            lines.append(f"  {k:28s} {m}" + (f"   ({m.note})" if m.note else ""))
        return "\n".join(lines)

    def to_dict(self) -> dict:
        return {"rig": self.rig, "metrics": {k: dataclasses.asdict(m) for k, m in self.metrics.items()},
                "info": self.info, "frames": self.frames, "provenance": self.provenance}

    def save(self, path: str | Path):
        """HDF5 (.h5: metrics as attributes, series as datasets) or JSON (anything else)."""
        path = Path(path)
        if path.suffix in (".h5", ".hdf5"):
            import h5py
            with h5py.File(path, "w") as f:
                f.attrs["rig"] = self.rig
                f.attrs["info"] = json.dumps(self.info, default=str)
                f.attrs["provenance"] = json.dumps(strict_json(self.provenance), default=str)
                g = f.create_group("metrics")
                for k, m in self.metrics.items():
                    g.attrs[k] = m.value
                    g.attrs[k + "_uncertainty"] = m.uncertainty
                    g.attrs[k + "_unit"] = m.unit
                s = f.create_group("series")
                for k, v in self.series.items():
                    s.create_dataset(k, data=np.asarray(v))
                f.create_dataset("frames", data=np.array(self.frames, dtype=object), dtype=h5py.string_dtype())
        else:
            path.write_text(json.dumps(strict_json(self.to_dict()), indent=1, default=str, allow_nan=False))


def strict_json(obj):
    """NaN and infinities -> None (JSON has no NaN), numpy scalars -> Python numbers."""
    if isinstance(obj, (np.floating, np.integer)):
        obj = obj.item()
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: strict_json(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [strict_json(v) for v in obj]
    return obj


def block_average(x, n_blocks: int = 5) -> tuple[float, float]:
    """Mean and its standard error from n_blocks contiguous block means (correlated samples)."""
    x = np.asarray(x, dtype=float)
    if x.size == 0:
        return math.nan, math.nan
    n_blocks = max(1, min(n_blocks, x.size))
    means = np.array([b.mean() for b in np.array_split(x, n_blocks)])
    sem = means.std(ddof=1) / math.sqrt(n_blocks) if n_blocks > 1 else math.nan
    return float(x.mean()), float(sem)
