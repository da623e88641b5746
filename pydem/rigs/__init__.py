"""The lab-test rigs: Schulze ring shear tester, static angle of repose, wedge hopper."""
from .aor import AngleOfRepose, AorConfig
from .config import ConfigError, Params, load
from .hopper import TABLE1, Hopper, HopperConfig, beverloo_fit
from .result import Metric, RigResult
from .ring_shear import RingShear, RingShearConfig

RIGS = {"aor": (AngleOfRepose, AorConfig), "hopper": (Hopper, HopperConfig), "ring-shear": (RingShear, RingShearConfig)}

__all__ = ["AngleOfRepose", "AorConfig", "RingShear", "RingShearConfig", "Hopper", "HopperConfig", "TABLE1", "beverloo_fit", "ConfigError", "Params",
           "load", "Metric", "RigResult", "RIGS"]
