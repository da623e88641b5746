"""What a campaign is: a rig + preset + fixed settings (incl. active effects) + the ranges of the
parameters under study + a seeded space-filling design. Written as TOML by users:

    rig = "ring-shear"          # aor | hopper | ring-shear
    preset = "tiny"
    design = "sobol"            # or "lhs"
    seed = 1
    samples = 256               # design points
    replicates = 1              # runs per design point (different seeds); nets fit the means
    [set]                       # fixed keys, as `pydem rig --set` takes them
    num_threads = 1
    "effects.cohesion_sjkr.cohesion_energy_density" = 2e4
    [ranges]                    # parameter = [low, high]
    friction = [0.05, 1.0]
    rolling_friction = [0.0, 0.6]
    [neutral]                   # optional: held at this value (or another parameter's) but on one axis
    wall_friction = "friction"  # (design.at_neutral: the base model and its one-effect axes)
"""
from __future__ import annotations

import dataclasses
import json
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from ..domain import MAX_SEED
from ..rigs import RIGS, ConfigError, load


class SpecError(ValueError):
    """A campaign specification that cannot run (names the key)."""


@dataclass
class CampaignSpec:
    rig: str
    ranges: dict[str, tuple[float, float]]
    preset: str = "default"
    fixed: dict[str, object] = field(default_factory=dict)
    design: str = "sobol"
    seed: int = 0
    samples: int = 64
    replicates: int = 1
    log_scale: tuple[str, ...] = ()
    neutral: dict[str, object] = field(default_factory=dict)

    def __post_init__(self):
        self.ranges = {k: (float(v[0]), float(v[1])) for k, v in dict(self.ranges).items()}
        self.log_scale = tuple(self.log_scale)
        self.validate()

    def validate(self):
        if self.rig not in RIGS:
            raise SpecError(f"rig: unknown rig {self.rig!r} (known: {', '.join(sorted(RIGS))})")
        if self.design not in ("sobol", "lhs"):
            raise SpecError(f"design: {self.design!r} is not sobol or lhs")
        if not isinstance(self.seed, int) or isinstance(self.seed, bool) or not 0 <= self.seed <= MAX_SEED:
            raise SpecError(f"seed: expected an integer in 0..{MAX_SEED}, got {self.seed!r}")
        if not isinstance(self.samples, int) or self.samples < 1:
            raise SpecError(f"samples: expected a positive integer, got {self.samples!r}")
        if not isinstance(self.replicates, int) or self.replicates < 1:
            raise SpecError(f"replicates: expected a positive integer, got {self.replicates!r}")
        if not self.ranges:
            raise SpecError("ranges: at least one parameter range is needed")
        for k, (lo, hi) in self.ranges.items():
            if not lo < hi:
                raise SpecError(f"ranges.{k}: low {lo:g} must be below high {hi:g}")
            if k in self.log_scale and lo <= 0:
                raise SpecError(f"ranges.{k}: log-scale sampling needs a positive low end, got {lo:g}")
            if k in self.fixed:
                raise SpecError(f"{k}: both fixed (in [set]) and varied (in [ranges])")
        for k, v in self.neutral.items():
            if k not in self.ranges:
                raise SpecError(f"neutral.{k}: not a varied parameter (add it to [ranges])")
            lo, hi = self.ranges[k]
            if isinstance(v, str):
                if v not in self.ranges or v in self.neutral:
                    raise SpecError(f"neutral.{k}: {v!r} is not a varied parameter outside [neutral]")
                if not (lo <= self.ranges[v][0] and self.ranges[v][1] <= hi):
                    raise SpecError(f"neutral.{k}: {v}'s range {self.ranges[v]} leaves {k}'s [{lo:g}, {hi:g}]")
            elif isinstance(v, bool) or not isinstance(v, (int, float)) or not lo <= v <= hi:
                raise SpecError(f"neutral.{k}: expected a number in [{lo:g}, {hi:g}] or a parameter's name, got {v!r}")
        try:  # every key must be a real knob and both ends in its allowed range
            for end in (0, 1):
                self.config({k: v[end] for k, v in self.ranges.items()})
        except ConfigError as exc:
            raise SpecError(str(exc)) from None
        for k, (lo, hi) in self.ranges.items():  # ... and take the values between them (a whole-number knob cannot)
            inner = lo + (hi - lo) * 0.4142135623730951
            try:
                self.config({k: inner})
            except ConfigError as exc:
                raise SpecError(f"ranges.{k}: a design samples values between the ends, and {exc}") from None

    @property
    def names(self) -> list[str]:
        return list(self.ranges)

    def config(self, values: dict[str, float]):
        """The rig configuration of one sample."""
        _, cfg_cls = RIGS[self.rig]
        try:
            overrides = [f"{k}={v}" for k, v in self.fixed.items()] + [f"{k}={v!r}" for k, v in values.items()]
            return load(cfg_cls, self.preset, None, overrides)
        except ValueError as exc:
            raise ConfigError(str(exc)) from None

    def to_json(self) -> str:
        d = dataclasses.asdict(self)  # key order kept: it is the column order
        if not d["neutral"]:
            del d["neutral"]  # a plain design's spec reads as it did before the key existed (store hashes)
        return json.dumps(d)

    @classmethod
    def from_json(cls, text: str) -> "CampaignSpec":
        return cls(**json.loads(text))

    @classmethod
    def from_toml(cls, path: str | Path) -> "CampaignSpec":
        try:
            data = tomllib.loads(Path(path).read_text())
        except (OSError, tomllib.TOMLDecodeError) as exc:
            raise SpecError(f"cannot read campaign spec {path}: {exc}") from None
        known = {"rig", "preset", "design", "seed", "samples", "replicates", "set", "ranges", "log_scale", "neutral"}
        unknown = set(data) - known
        if unknown:
            raise SpecError(f"{path}: unknown keys {sorted(unknown)} (known: {sorted(known)})")
        if "rig" not in data:
            raise SpecError(f"{path}: 'rig' is missing")
        ranges = data.get("ranges", {})
        for k, v in ranges.items():
            if not (isinstance(v, list) and len(v) == 2 and all(isinstance(x, (int, float)) for x in v)):
                raise SpecError(f"{path}: ranges.{k} must be [low, high], got {v!r}")
        return cls(rig=data["rig"], preset=data.get("preset", "default"), design=data.get("design", "sobol"),
                   seed=data.get("seed", 0), samples=data.get("samples", 64),
                   replicates=data.get("replicates", 1), fixed=dict(data.get("set", {})),
                   ranges={k: tuple(v) for k, v in ranges.items()}, log_scale=tuple(data.get("log_scale", ())),
                   neutral=dict(data.get("neutral", {})))
