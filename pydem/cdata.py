"""How Python values cross into libdem: numpy arrays checked and laid out as C arrays (no copy
when they already are), pointers into them, and definition structs filled from libdem's own
defaults. The Domain and its walls both pass data this way."""
from __future__ import annotations

import numpy as np

from ._libdem import ffi
from .errors import DemInvalidArgument


def as_c_array(values, dtype, shape_tail: tuple, name: str, n: int | None = None) -> np.ndarray:
    """C-contiguous array of dtype with shape (n, *shape_tail); no copy when already so. An
    integer dtype refuses values that are not whole numbers (a triangle index 2.5 is an error,
    never truncated)."""
    if np.issubdtype(np.dtype(dtype), np.integer):
        raw = np.asarray(values)
        if raw.dtype.kind not in "iub":
            f = raw.astype(np.float64)
            if not np.all(np.isfinite(f)) or np.any(f != np.round(f)):
                raise DemInvalidArgument(f"{name} must be whole numbers, got {f[(~np.isfinite(f)) | (f != np.round(f))][:3]}",
                                         "DEM_ERR_INVALID_ARGUMENT")
    a = np.ascontiguousarray(values, dtype=dtype)
    if shape_tail and a.ndim == 1 and a.size == int(np.prod(shape_tail)) and n in (None, 1):
        a = a.reshape((1, *shape_tail))
    if a.shape[1:] != shape_tail or (n is not None and a.shape[0] != n):
        want = f"({n if n is not None else 'n'}{''.join(', ' + str(s) for s in shape_tail)})"
        raise DemInvalidArgument(f"{name} must have shape {want}, got {a.shape}", "DEM_ERR_INVALID_ARGUMENT")
    return a


def c_pointer(a: np.ndarray, ctype: str):
    return ffi.from_buffer(ctype, a)


def c_definition(maker, ctype: str, **given):
    """A libdem definition struct: the library's defaults (its dem_default_*_def maker: libdem
    owns every default), then the values given; None keeps the default."""
    s = ffi.new(ctype, maker())
    for key, value in given.items():
        if value is None:
            continue
        field = getattr(s, key)
        if isinstance(field, ffi.CData) and ffi.typeof(field).kind == "array":  # lo, hi, gravity, ...
            for a, x in enumerate(value):
                field[a] = x
        else:
            setattr(s, key, value)
    return s
