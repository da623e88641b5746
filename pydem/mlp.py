"""libdem's MLP inference and native screening from Python (numpy in and out).

    nets = [NativeMLP("build/nets/mu_ie_ps.mlp"), NativeMLP("build/nets/mu_ie_s_50.mlp")]
    keep, pred = screen(nets, targets=[0.434, 0.46], windows=[0.05, 0.05], x=combos, num_threads=2)
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from . import _ffi, _lib
from .errors import check

_ERR = 512


def _call(fn, *args):
    err = _ffi.new("char[]", _ERR)
    st = fn(*args, err, _ERR)
    if st < 0:
        check(st, None, _ffi.string(err).decode(errors="replace"))


class NativeMLP:
    """A net loaded by libdem from a "dem-mlp 1" weights file (nn/export.py)."""

    def __init__(self, path: str | Path | None = None, text: str | None = None):
        """From a weights file, or from the same text in memory (`text=`)."""
        if (path is None) == (text is None):
            raise ValueError("NativeMLP: give a weights file path or its text, not both")
        out = _ffi.new("dem_mlp **")
        if text is not None:
            _call(_lib.dem_mlp_parse, text.encode(), out)
        else:
            _call(_lib.dem_mlp_load, str(path).encode(), out)
        self._ptr = _ffi.gc(out[0], _lib.dem_mlp_free)
        self.path = Path(path) if path is not None else None

    @property
    def name(self) -> str:
        return _ffi.string(_lib.dem_mlp_name(self._ptr)).decode()

    @property
    def unit(self) -> str:
        return _ffi.string(_lib.dem_mlp_unit(self._ptr)).decode()

    @property
    def hidden(self) -> int:
        return _lib.dem_mlp_num_hidden(self._ptr)

    @property
    def input_names(self) -> list[str]:
        return [_ffi.string(_lib.dem_mlp_input_name(self._ptr, i)).decode() for i in range(_lib.dem_mlp_num_inputs(self._ptr))]

    def save(self, path: str | Path):
        _call(_lib.dem_mlp_save, self._ptr, str(path).encode())

    def _rows(self, x) -> np.ndarray:
        x = np.ascontiguousarray(np.atleast_2d(x), dtype=np.float64)
        if x.shape[1] != len(self.input_names):
            raise ValueError(f"{self.name}: expected {len(self.input_names)} inputs per row ({', '.join(self.input_names)}), "
                             f"got {x.shape[1]}")
        return x

    def eval_reference(self, x) -> np.ndarray:
        """Row by row through dem_mlp_eval (libm tanh)."""
        x = self._rows(x)
        return np.array([_lib.dem_mlp_eval(self._ptr, _ffi.from_buffer("double[]", row)) for row in x])

    def __call__(self, x, num_threads: int = 0) -> np.ndarray:
        """All rows at once, blocked and vectorised (dem_mlp_eval_many)."""
        x = self._rows(x)
        y = np.empty(len(x))
        st = _lib.dem_mlp_eval_many(self._ptr, _ffi.from_buffer("double[]", x), len(x),
                                    _ffi.from_buffer("double[]", y), num_threads)
        if st < 0:
            check(st, None, f"{self.name}: evaluation failed")
        return y


def screen(nets: list[NativeMLP], targets, windows, x, num_threads: int = 0, with_predictions: bool = True):
    """Keeps the rows of x whose predictions by every net lie within windows[k] x |targets[k]|
    of targets[k]. Returns (keep mask, predictions n x nets or None)."""
    if not nets:
        raise ValueError("screen: no nets given")
    x = nets[0]._rows(x)
    t = np.ascontiguousarray(targets, dtype=np.float64)
    w = np.ascontiguousarray(np.broadcast_to(windows, t.shape), dtype=np.float64)
    if len(t) != len(nets):
        raise ValueError(f"screen: {len(nets)} nets but {len(t)} targets")
    keep = np.empty(len(x), dtype=np.uint8)
    pred = np.empty((len(x), len(nets))) if with_predictions else None
    arr = _ffi.new("dem_mlp *[]", [n._ptr for n in nets])
    kept = _ffi.new("size_t *")
    _call(_lib.dem_mlp_screen, arr, len(nets), _ffi.from_buffer("double[]", t), _ffi.from_buffer("double[]", w),
          _ffi.from_buffer("double[]", x), len(x), num_threads, _ffi.from_buffer("unsigned char[]", keep),
          _ffi.from_buffer("double[]", pred) if pred is not None else _ffi.NULL, kept)
    return keep.astype(bool), pred
