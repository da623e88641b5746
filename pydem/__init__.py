"""pydem — the Python front-end of libdem: numpy in and out, the lab-test rigs, a command line.

    import pydem
    dom = pydem.Domain(lo=(0, 0, 0), hi=(0.1, 0.1, 0.1))
"""
__version__ = "0.2.1"

import os as _os

# OpenMP threads spin briefly (10^4 rounds, microseconds) at a barrier, then sleep. Sleeping at
# once (OMP_WAIT_POLICY=passive) made a small rig run on 2 threads slower than on 1 (hopper
# `default`: 8.0 s against 5.5 s; with the short spin 3.5 s); spinning long made a 2-thread run
# beside a busy process 2x slower than 1 thread. The busy machine is now libdem's thread
# governor's job (it drops to fewer threads while they measure faster; studies/JOURNAL.md, "A busy
# machine"). Set before libdem loads libgomp; an explicit OMP_WAIT_POLICY or GOMP_SPINCOUNT wins.
if "OMP_WAIT_POLICY" not in _os.environ and "GOMP_SPINCOUNT" not in _os.environ:
    _os.environ["GOMP_SPINCOUNT"] = "10000"

try:
    from ._libdem import ffi as _ffi, lib as _lib
except ImportError as exc:  # the compiled binding is built by `make pydem`
    raise ImportError(f"pydem's compiled binding is missing or broken ({exc}); run `make pydem` in the repository") from exc


def _check_versions():
    runtime = _ffi.string(_lib.dem_version_string()).decode()
    header = f"{_lib.DEM_VERSION_MAJOR}.{_lib.DEM_VERSION_MINOR}.{_lib.DEM_VERSION_PATCH}"
    if runtime != header or runtime.split(".")[:2] != __version__.split(".")[:2]:
        raise ImportError(
            f"version mismatch: libdem {runtime} (headers {header}) vs pydem {__version__}; rebuild with `make pydem`")
    return runtime


LIBDEM_VERSION = _check_versions()

from .errors import (DemError, DemFormatError, DemInvalidArgument, DemIOError, DemOverlapError,  # noqa: E402
                     DemRunError, DemUnknownError, DemWarning)
from .domain import Domain, effects  # noqa: E402
from .walls import MeshWall, PlaneWall  # noqa: E402

__all__ = ["Domain", "effects", "MeshWall", "PlaneWall", "DemError", "DemFormatError", "DemInvalidArgument",
           "DemIOError", "DemOverlapError", "DemRunError", "DemUnknownError", "DemWarning", "LIBDEM_VERSION"]
