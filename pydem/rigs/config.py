"""Rig configurations: dataclasses whose fields carry unit, allowed range and a line of help;
presets, TOML loading, `key=value` overrides, validation that names the key and the range."""
from __future__ import annotations

import dataclasses
import os
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..domain import effects as registry


def default_threads() -> int:
    """OpenMP threads of a rig run unless its config says otherwise: OMP_NUM_THREADS when set
    (users and batch systems set it), else the cores this process may use. libdem's thread
    governor runs the steps on fewer threads while that measures faster — a busy machine, a
    system too small for the team — so asking for every core no longer costs: a 2-thread run
    beside a busy process takes about its 1-thread time (studies/JOURNAL.md, "Threads that measure
    themselves"). Campaigns run one thread per run, several runs side by side."""
    text = os.environ.get("OMP_NUM_THREADS", "").split(",")[0].strip()
    try:
        return max(1, int(text))
    except ValueError:
        return os.cpu_count() or 1  # as the campaign runner counts cores


class ConfigError(ValueError):
    """A bad configuration: unknown key, wrong type, value out of range."""


def knob(default, lo=None, hi=None, unit: str = "", doc: str = "", choices=None):
    """A config field with its allowed range (inclusive) or choices; a type or a list as the
    default becomes a factory (fresh per instance)."""
    meta = {"lo": lo, "hi": hi, "unit": unit, "doc": doc, "choices": choices}
    if isinstance(default, type):
        return field(default_factory=default, metadata=meta)
    if isinstance(default, list):
        return field(default_factory=lambda: list(default), metadata=meta)
    return field(default=default, metadata=meta)


@dataclass
class Params:
    """The DEM micro parameters under calibration (seed 000): particle–particle and
    particle–wall contact constants, solid properties, and optional effects by name."""
    friction: float = knob(0.5, 0.0, 2.0, "", "sliding friction mu_s, particle-particle")
    rolling_friction: float = knob(0.1, 0.0, 1.0, "", "rolling friction mu_r, particle-particle")
    restitution: float = knob(0.5, 0.05, 1.0, "", "coefficient of restitution e, particle-particle")
    wall_friction: float = knob(0.5, 0.0, 2.0, "", "sliding friction particle-wall")
    wall_rolling_friction: float = knob(0.1, 0.0, 1.0, "", "rolling friction particle-wall")
    wall_restitution: float = knob(0.5, 0.05, 1.0, "", "restitution particle-wall")
    rolling_model: str = knob("epsd2", doc="rolling resistance model", choices=("cdt", "epsd", "epsd2"))
    density: float = knob(2500.0, 100.0, 20000.0, "kg/m^3", "solid density")
    youngs_modulus: float = knob(5e6, 1e5, 1e11, "Pa", "Young's modulus (reduced for speed, as usual in DEM)")
    poisson_ratio: float = knob(0.25, 0.0, 0.49, "", "Poisson ratio")
    effects: dict = knob(dict, doc="optional effects: {name: {parameter: value}}, e.g. cohesion_sjkr")


def _fields(obj):
    return {f.name: f for f in dataclasses.fields(obj)}


def _coerce(value: Any, default: Any, key: str):
    if isinstance(default, bool):
        if isinstance(value, str):
            if value.lower() in ("1", "true", "yes", "on"):
                return True
            if value.lower() in ("0", "false", "no", "off"):
                return False
            raise ConfigError(f"{key}: expected true/false, got {value!r}")
        return bool(value)
    if isinstance(default, (int, float)) and not isinstance(default, bool):
        if isinstance(value, bool):  # TOML `true` is not 1.0
            raise ConfigError(f"{key}: expected a number, got {value!r}")
        try:
            v = float(value)
        except (TypeError, ValueError):
            raise ConfigError(f"{key}: expected a number, got {value!r}") from None
        if isinstance(default, int):
            if not v.is_integer():
                raise ConfigError(f"{key}: expected a whole number, got {value!r}")
            return int(v)
        return v
    if isinstance(default, (list, tuple)):
        if isinstance(value, str):
            value = [x for x in value.replace("[", "").replace("]", "").split(",") if x.strip()]
        return type(default)(_coerce(x, default[0] if default else 0.0, key) for x in value)
    return value if not isinstance(default, str) else str(value)


def _locate(cfg, key: str):
    """Where `key` lives: ("effect", effect name, its parameter's registry entry) or ("field",
    the object holding it (the config or its params), the field name); a ConfigError naming
    the problem when there is no such key."""
    parts = key.split(".")
    if parts[0] == "effects" or (parts[0] == "params" and len(parts) > 1 and parts[1] == "effects"):
        parts = parts[1:] if parts[0] == "params" else parts
        if len(parts) != 3:
            raise ConfigError(f"{key}: effects are set as effects.<effect>.<parameter>=value")
        spec = next((e for e in registry() if e["name"] == parts[1]), None)
        if spec is None:
            raise ConfigError(f"{key}: unknown effect {parts[1]!r} (known: {', '.join(e['name'] for e in registry())})")
        param = next((q for q in spec["params"] if q["name"] == parts[2]), None)
        if param is None:
            raise ConfigError(f"{key}: effect {parts[1]!r} has parameters {[q['name'] for q in spec['params']]}")
        return "effect", parts[1], param
    target, name = cfg, parts[-1]
    if parts[0] == "params" and len(parts) == 2:
        target = cfg.params
    elif len(parts) != 1:
        raise ConfigError(f"unknown key {key!r}")
    elif name not in _fields(cfg) and name in _fields(cfg.params):
        target = cfg.params
    if name not in _fields(target) or name == "params":
        known = sorted(set(_fields(cfg)) - {"params"}) + sorted(_fields(cfg.params))
        raise ConfigError(f"unknown key {key!r}; known keys: {', '.join(known)}")
    return "field", target, name


def set_value(cfg, key: str, value: Any):
    """Sets `key` (a field of the config, `params.<field>`, a Params field name, or
    `effects.<effect>.<parameter>`) from a string or a value, then checks its range."""
    kind, where, what = _locate(cfg, key)
    if kind == "effect":
        v = _coerce(value, 0.0, key)
        if not what["min"] <= v <= what["max"]:  # libdem's own range (dem_effect_param_range), checked before any run
            unit = f" {what['unit']}" if what["unit"] else ""
            raise ConfigError(f"{key} = {v:g}{unit} is outside libdem's range [{what['min']:g}, {what['max']:g}]{unit}")
        cfg.params.effects.setdefault(where, {})[what["name"]] = v
        return
    target, name = where, what
    setattr(target, name, _coerce(value, getattr(target, name), key))
    check_field(target, _fields(target)[name], key)
    hook = getattr(target, "on_set", None)
    if hook is not None:
        hook(name)


def get_value(cfg, key: str) -> Any:
    """The value of `key` (the keys set_value() takes) in a configuration; an effect parameter of
    an effect that is not switched on reads as the parameter's neutral value (off)."""
    kind, where, what = _locate(cfg, key)
    if kind == "effect":
        return cfg.params.effects.get(where, {}).get(what["name"], what["neutral"])
    return getattr(where, what)


def check_field(obj, f, key: str | None = None):
    v, m, key = getattr(obj, f.name), f.metadata, key or f.name
    if m.get("choices") is not None and v not in m["choices"]:
        raise ConfigError(f"{key} = {v!r} is not allowed; choose one of {', '.join(map(str, m['choices']))}")
    vals = v if isinstance(v, (list, tuple)) else [v]
    for x in vals:
        if not isinstance(x, (int, float)):
            continue
        if x != x:
            raise ConfigError(f"{key} is NaN")
        if (m.get("lo") is not None and x < m["lo"]) or (m.get("hi") is not None and x > m["hi"]):
            raise ConfigError(f"{key} = {x:g} is out of range [{m['lo']:g}, {m['hi']:g}] {m.get('unit', '')}".rstrip())


def validate(cfg):
    for obj in (cfg, cfg.params):
        for f in dataclasses.fields(obj):
            if f.name != "params":
                check_field(obj, f)


def _preset(cls, name):
    try:
        return cls.preset(name)
    except ValueError as exc:  # an unknown preset: the rig's message lists the known ones
        raise ConfigError(str(exc)) from None


def load(cls, preset: str = "default", path: str | Path | None = None, overrides: list[str] | None = None):
    """A rig config: the preset, then the TOML file's keys (top level and [params],
    [effects.<name>] tables), then `key=value` overrides; validated."""
    cfg = _preset(cls, preset)
    explicit: dict[str, str] = {}  # key -> where it was given

    def apply(key, value, where):
        """set_value, refusing a key (such as the hopper's `case`) that would silently overwrite keys
        given before it."""
        before = {n: getattr(cfg, n) for n in _fields(cfg) if n != "params"} | \
                 {f"params.{n}": getattr(cfg.params, n) for n in _fields(cfg.params)}
        set_value(cfg, key, value)
        after = {n: getattr(cfg, n) for n in _fields(cfg) if n != "params"} | \
                {f"params.{n}": getattr(cfg.params, n) for n in _fields(cfg.params)}
        name = key.split(".")[-1]
        clobbered = [k for k in after if after[k] != before[k] and k.split(".")[-1] != name
                     and k.split(".")[-1] in explicit]
        if clobbered:
            k = clobbered[0].split(".")[-1]
            raise ConfigError(f"{key}={value} sets {k} = {after[clobbered[0]]!r}, overriding {k} given before it "
                              f"({explicit[k]}); give {key} first, then the keys that change it")
        explicit[name] = where

    if path is not None:
        try:
            data = tomllib.loads(Path(path).read_text())
        except (OSError, tomllib.TOMLDecodeError) as exc:
            raise ConfigError(f"cannot read config {path}: {exc}") from None
        if "preset" in data:
            cfg = _preset(cls, data.pop("preset"))
        for key, value in data.items():
            if key in ("params", "effects") and isinstance(value, dict):
                for k2, v2 in value.items():
                    if isinstance(v2, dict):
                        for k3, v3 in v2.items():
                            set_value(cfg, f"effects.{k2}.{k3}", v3)
                    else:
                        apply(f"params.{k2}", v2, str(path))
            else:
                apply(key, value, str(path))
    for item in overrides or []:
        if "=" not in item:
            raise ConfigError(f"--set expects key=value, got {item!r}")
        k, v = item.split("=", 1)
        apply(k.strip(), v.strip(), f"--set {item}")
    validate(cfg)
    return cfg


def describe(cfg) -> list[tuple[str, Any, str, str]]:
    """(key, value, unit, help) for every knob: for --help texts and reports."""
    rows = []
    for obj, prefix in ((cfg, ""), (cfg.params, "params.")):
        for f in dataclasses.fields(obj):
            if f.name != "params":
                rows.append((prefix + f.name, getattr(obj, f.name), f.metadata.get("unit", ""), f.metadata.get("doc", "")))
    return rows
