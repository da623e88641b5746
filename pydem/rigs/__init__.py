"""The lab-test rigs: static angle of repose, (more to come: Schulze ring shear, wedge hopper)."""
from .aor import AngleOfRepose, AorConfig
from .config import ConfigError, Params, load
from .result import Metric, RigResult

RIGS = {"aor": (AngleOfRepose, AorConfig)}

__all__ = ["AngleOfRepose", "AorConfig", "ConfigError", "Params", "load", "Metric", "RigResult", "RIGS"]
