"""The lab-test rigs: static angle of repose, wedge hopper (Schulze ring shear: next)."""
from .aor import AngleOfRepose, AorConfig
from .config import ConfigError, Params, load
from .hopper import TABLE1, Hopper, HopperConfig, beverloo_fit
from .result import Metric, RigResult

RIGS = {"aor": (AngleOfRepose, AorConfig), "hopper": (Hopper, HopperConfig)}

__all__ = ["AngleOfRepose", "AorConfig", "Hopper", "HopperConfig", "TABLE1", "beverloo_fit", "ConfigError", "Params",
           "load", "Metric", "RigResult", "RIGS"]
