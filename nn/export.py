"""Exporting a trained PropertyNet: (a) a text weights file that libdem's MLP routine loads
(`dem_mlp_load`), every number as a C99 hex float so the round trip is exact; (b) a standalone
C99 source/header pair with the weights embedded, for use in other codes (needs only <math.h>).

Weights file (one keyword per line, values separated by spaces):

    dem-mlp 1
    name mu_ie_ps
    unit -                       (- when dimensionless)
    inputs 3 friction rolling_friction restitution
    hidden 12
    input_lo ...                 (inputs values)   input scaling: xs = (x - lo) * (2 / (hi - lo)) - 1
    input_hi ...
    output_lo v
    output_hi v                  output: y = (ys + 1) * ((hi - lo) / 2) + lo
    w1 ...                       (hidden x inputs, row-major)
    b1 ...                       (hidden)
    w2 ...                       (hidden)
    b2 v
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np


@dataclass
class NetArrays:
    """What an exported net is: a name, its inputs with their scaling box, the output scaling
    and the weights of one tanh hidden layer; evaluated in numpy as libdem evaluates it. Made from
    a trained PropertyNet (torch), or held by a cached surrogate (pydem.calibration.surrogates.
    QuantityNet): export and evaluation need no torch."""
    name: str
    unit: str
    input_names: list[str]
    lo: np.ndarray
    hi: np.ndarray
    y_lo: float
    y_hi: float
    w1: np.ndarray   # hidden x inputs
    b1: np.ndarray
    w2: np.ndarray   # hidden
    b2: float
    log_output: bool = False  # y = exp(scaled output): a positive quantity learnt as its log

    @property
    def hidden(self) -> int:
        return int(len(self.b1))

    def scaled(self, x: np.ndarray, clip: bool = False) -> np.ndarray:
        """Inputs mapped to the net's [-1, 1] box (clip: held inside it)."""
        s = (np.atleast_2d(x) - self.lo) * (2.0 / (self.hi - self.lo)) - 1.0
        return np.clip(s, -1.0, 1.0) if clip else s

    def _hidden(self, x: np.ndarray) -> np.ndarray:
        return np.tanh(self.scaled(x) @ self.w1.T + self.b1)

    def _output(self, h: np.ndarray) -> np.ndarray:
        y = (h @ self.w2 + self.b2 + 1.0) * (0.5 * (self.y_hi - self.y_lo)) + self.y_lo
        return np.exp(y) if self.log_output else y

    def __call__(self, x: np.ndarray) -> np.ndarray:
        """x: (m, inputs) -> (m,): what libdem's dem_mlp routine computes, in numpy."""
        return self._output(self._hidden(x))

    def gradient(self, x: np.ndarray) -> np.ndarray:
        """x: (m, inputs) -> (m, inputs): d f / d x (one hidden layer: analytic; one forward pass)."""
        h = self._hidden(x)
        g = ((1.0 - h * h) * self.w2) @ self.w1  # d y_s / d s
        g = g * (2.0 / (self.hi - self.lo)) * (0.5 * (self.y_hi - self.y_lo))
        return g * self._output(h)[:, None] if self.log_output else g


def _hex(values) -> str:
    return " ".join(float(v).hex() for v in np.ravel(values))


def arrays_of(net) -> NetArrays:
    """NetArrays of a PropertyNet (or the NetArrays given)."""
    if isinstance(net, NetArrays):
        return net
    m = net.model
    return NetArrays(net.name, net.unit, list(net.input_names), net.x_scaler.lo, net.x_scaler.hi,
                     float(net.y_scaler.lo[0]), float(net.y_scaler.hi[0]), m.hidden.weight.detach().numpy().copy(),
                     m.hidden.bias.detach().numpy().copy(), m.out.weight.detach().numpy()[0].copy(),
                     float(m.out.bias.detach().numpy()[0]), bool(getattr(net, "log_output", False)))


def weights_text(net) -> str:
    """The "dem-mlp 1" text of a PropertyNet or NetArrays (libdem's dem_mlp_parse reads it)."""
    a = arrays_of(net)
    lines = ["dem-mlp 1", f"name {a.name}", f"unit {a.unit or '-'}",
             f"inputs {len(a.input_names)} {' '.join(a.input_names)}", f"hidden {a.hidden}",
             f"input_lo {_hex(a.lo)}", f"input_hi {_hex(a.hi)}", f"output_lo {_hex(a.y_lo)}", f"output_hi {_hex(a.y_hi)}",
             f"w1 {_hex(a.w1)}", f"b1 {_hex(a.b1)}", f"w2 {_hex(a.w2)}", f"b2 {_hex(a.b2)}"]
    if a.log_output:
        lines.append("output_transform log")
    return "\n".join(lines) + "\n"


def write_weights(net, path: str | Path) -> Path:
    path = Path(path)
    path.write_text(weights_text(net))
    return path


def read_weights(path: str | Path):
    """The inverse of write_weights (exact): a PropertyNet (needs torch)."""
    import torch
    from .mlp import MLP, PropertyNet, Scaler
    fields = {}
    for n, line in enumerate(Path(path).read_text().splitlines(), 1):
        parts = line.split()
        if parts:
            fields[parts[0]] = parts[1:]
    if fields.get("dem-mlp") != ["1"]:
        raise ValueError(f"{path}: not a dem-mlp 1 weights file")
    nin, names = int(fields["inputs"][0]), fields["inputs"][1:]
    hidden = int(fields["hidden"][0])
    f = {k: np.array([float.fromhex(v) for v in fields[k]]) for k in
         ("input_lo", "input_hi", "output_lo", "output_hi", "w1", "b1", "w2", "b2")}
    model = MLP(nin, hidden)
    with torch.no_grad():
        model.hidden.weight.copy_(torch.from_numpy(f["w1"].reshape(hidden, nin)))
        model.hidden.bias.copy_(torch.from_numpy(f["b1"]))
        model.out.weight.copy_(torch.from_numpy(f["w2"].reshape(1, hidden)))
        model.out.bias.copy_(torch.from_numpy(f["b2"]))
    unit = fields["unit"][0] if fields.get("unit") and fields["unit"][0] != "-" else ""
    return PropertyNet(fields["name"][0], names, Scaler(f["input_lo"], f["input_hi"]),
                       Scaler(f["output_lo"], f["output_hi"]), model, unit,
                       log_output=fields.get("output_transform") == ["log"])


def c_identifier(name: str) -> str:
    ident = re.sub(r"[^0-9A-Za-z_]", "_", name)
    return ident if ident and not ident[0].isdigit() else "net_" + ident


def write_c(net, directory: str | Path, prefix: str = "mlp_") -> tuple[Path, Path]:
    """<prefix><name>.h / .c: `double <prefix><name>(const double x[N])` in physical units
    (net: a PropertyNet or NetArrays)."""
    net = arrays_of(net)
    ident = prefix + c_identifier(net.name)
    w = {"w1": net.w1, "b1": net.b1, "w2": net.w2, "b2": np.array([net.b2])}
    nin, hid = len(net.input_names), net.hidden
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    guard = ident.upper() + "_H"
    header = f"""/* {ident}: MLP surrogate of '{net.name}'{f' [{net.unit}]' if net.unit else ''}, exported by pydem (nn/export.py).
 * Inputs (physical units, in this order): {', '.join(net.input_names)}.
 * Trained on inputs within: {', '.join(f'{n} [{lo:g}, {hi:g}]' for n, lo, hi in zip(net.input_names, net.lo, net.hi))};
 * outside that box it extrapolates. C99, needs <math.h> (link with -lm). */
#ifndef {guard}
#define {guard}
#define {ident.upper()}_INPUTS {nin}
#ifdef __cplusplus
extern "C" {{
#endif
double {ident}(const double x[{nin}]);
#ifdef __cplusplus
}}
#endif
#endif
"""

    def arr(name, values, per_line=4):
        vals = [float(v).hex() for v in np.ravel(values)]
        rows = [", ".join(vals[i:i + per_line]) for i in range(0, len(vals), per_line)]
        return f"static const double {name}[{len(vals)}] = {{\n    " + ",\n    ".join(rows) + "\n};\n"

    source = f"""/* {ident}: generated by pydem nn/export.py; weights as exact hex floats. */
#include "{ident}.h"
#include <math.h>

{arr('input_lo', net.lo)}{arr('input_hi', net.hi)}{arr('w1', w['w1'])}{arr('b1', w['b1'])}{arr('w2', w['w2'])}
double {ident}(const double x[{nin}])
{{
    const double output_lo = {float(net.y_lo).hex()}, output_hi = {float(net.y_hi).hex()};
    const double b2 = {float(w['b2'][0]).hex()};
    double xs[{nin}], y = b2;
    int i, j;
    for (i = 0; i < {nin}; ++i)
        xs[i] = (x[i] - input_lo[i]) * (2.0 / (input_hi[i] - input_lo[i])) - 1.0;
    for (j = 0; j < {hid}; ++j) {{
        double z = b1[j];
        for (i = 0; i < {nin}; ++i)
            z += w1[j * {nin} + i] * xs[i];
        y += w2[j] * tanh(z);
    }}
    y = (y + 1.0) * ((output_hi - output_lo) / 2.0) + output_lo;
    return {"exp(y)" if net.log_output else "y"};
}}
"""
    h, c = directory / f"{ident}.h", directory / f"{ident}.c"
    h.write_text(header)
    c.write_text(source)
    return h, c
