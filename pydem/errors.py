"""libdem statuses as Python exceptions (and warnings), carrying the C message."""
import warnings

from ._libdem import ffi, lib


class DemError(Exception):
    """A libdem call failed. `status` is the C status name, the text is libdem's message."""

    def __init__(self, message: str, status: str = "DEM_ERR"):
        super().__init__(message)
        self.status = status


class DemInvalidArgument(DemError, ValueError):
    pass


class DemOverlapError(DemError, ValueError):
    pass


class DemUnknownError(DemError, KeyError):
    """Unknown material, particle, effect or wall."""

    def __str__(self):  # KeyError would quote the message
        return self.args[0]


class DemRunError(DemError, RuntimeError):
    """A run broke: NaN, a particle left the box, runaway overlap, unstable time step."""


class DemIOError(DemError, OSError):
    pass


class DemFormatError(DemError, ValueError):
    """A file is not what it claims to be (STL, snapshot)."""


class DemWarning(UserWarning):
    pass


_BY_STATUS = {
    "DEM_ERR_INVALID_ARGUMENT": DemInvalidArgument,
    "DEM_ERR_NULL": DemInvalidArgument,
    "DEM_ERR_OVERLAP": DemOverlapError,
    "DEM_ERR_UNKNOWN_MATERIAL": DemUnknownError,
    "DEM_ERR_UNKNOWN_PARTICLE": DemUnknownError,
    "DEM_ERR_UNKNOWN_EFFECT": DemUnknownError,
    "DEM_ERR_UNKNOWN_WALL": DemUnknownError,
    "DEM_ERR_OUT_OF_BOUNDS": DemRunError,
    "DEM_ERR_NUMERICAL": DemRunError,
    "DEM_ERR_RUNAWAY_OVERLAP": DemRunError,
    "DEM_ERR_UNSTABLE_TIMESTEP": DemRunError,
    "DEM_ERR_IO": DemIOError,
    "DEM_ERR_FORMAT": DemFormatError,
}


def status_name(status: int) -> str:
    return ffi.string(lib.dem_status_name(status)).decode()


def check(status: int, domain_ptr=None, message: str | None = None) -> int:
    """Raises the exception for a failed status; warns for a positive one; returns it."""
    if status == 0:
        return status
    name = status_name(status)
    if message is None:
        message = ffi.string(lib.dem_domain_last_error(domain_ptr)).decode() if domain_ptr is not None else ""
    if status > 0:
        warnings.warn(f"{name}: {message}", DemWarning, stacklevel=3)
        return status
    raise _BY_STATUS.get(name, DemError)(message or name, name)
