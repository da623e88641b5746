"""Measurement files (docs/measurements.md): CSV, one row a measured value, `#` comment lines.

    material,test,quantity,value,uncertainty,unit,conditions,use,source
    glass_microbeads,ring_shear,mu_ie_s,0.45995,0.00867,,shear_fraction=0.5,calibrate,VSB ...

test: ring_shear | aor | hopper | poured (bulk density of a poured fill: the AoR rig's filled
cylinder); quantity: one of the test's (pydem.quantity_table.TABLE); unit: the quantity's SI unit (or
empty for SI) or a known alternative (converted: g/cm^3, kPa, rad, g/s, ...), anything else is
refused; a value outside the physically possible range is refused (1.55 "kg/m^3" is a
g/cm^3 number);
conditions: `key=value` pairs separated by `;` from quantity_table.CONDITION_UNITS; uncertainty: one standard
uncertainty, empty when not published; use: `calibrate` (screened against) or `compare` (shown
in comparisons only); origin (optional column): `lab` (the default: a lab's measurement, its
uncertainty the lab's repeatability) or `dem` (one DEM run, which also carries that run's seed
scatter). A UTF-8 byte-order mark and CRLF line ends (a spreadsheet's CSV) are
accepted; duplicate rows and physically impossible values are refused. Errors name the file,
line and column."""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path

from .quantity_table import CONDITION_UNITS, RIG_OF_TEST, TABLE

COLUMNS = ["material", "test", "quantity", "value", "uncertainty", "unit", "conditions", "use", "source", "origin"]
USES = ("calibrate", "compare")
# where a value comes from, which decides its noise (docs/diagnosis.md §1): a lab's measurement (its
# uncertainty is the lab's repeatability) or one DEM run (it also carries that run's seed scatter)
ORIGINS = ("lab", "dem")
# limits a file is checked against before anything else (a lab programme is tens of rows of short fields)
MAX_BYTES = 4 * 2 ** 20
MAX_ROWS = 2000
MAX_LINE = 4000


class MeasurementError(ValueError):
    """A malformed measurement file (the message names the line and the column)."""


@dataclass
class Measurement:
    material: str
    test: str
    quantity: str
    value: float
    uncertainty: float  # NaN when not published
    unit: str = ""
    conditions: dict[str, str] = field(default_factory=dict)
    use: str = "calibrate"
    source: str = ""
    line: int = 0
    origin: str = "lab"

    @property
    def rig(self) -> str | None:
        return RIG_OF_TEST.get(self.test)

    @property
    def metric(self) -> str:
        """The rig metric this value is compared with (mu_ie_s at a shear fraction f -> mu_ie_s_<100 f>)."""
        if self.test == "ring_shear" and self.quantity in ("mu_ie_s", "tau_shear") and "shear_fraction" in self.conditions:
            return f"{self.quantity}_{round(100 * float(self.conditions['shear_fraction']))}"
        return self.quantity

    @property
    def label(self) -> str:
        cond = ", ".join(f"{k}={v}" for k, v in self.conditions.items())
        return f"{self.test}:{self.quantity}" + (f" ({cond})" if cond else "")


def _number(text: str, where: str, allow_empty: bool) -> float:
    text = text.strip()
    if text == "" and allow_empty:
        return math.nan
    try:
        v = float(text)
    except ValueError:
        raise MeasurementError(f"{where}: expected a number, got {text!r}") from None
    if not math.isfinite(v):
        raise MeasurementError(f"{where}: {text!r} is not a finite number")
    return v


def load(path: str | Path, material: str | None = None) -> list[Measurement]:
    """All rows (or those of one material); raises MeasurementError naming line and column."""
    path = Path(path)
    try:
        size = path.stat().st_size
        if size > MAX_BYTES:
            raise MeasurementError(f"{path}: {size / 2 ** 20:.1f} MiB; a measurement file is at most "
                                   f"{MAX_BYTES // 2 ** 20} MiB (a lab programme is tens of rows)")
        lines = path.read_text(encoding="utf-8-sig").splitlines()  # a BOM and CRLF are a spreadsheet's
    except (OSError, UnicodeDecodeError) as exc:
        raise MeasurementError(f"{path}: cannot read ({exc})") from None
    numbered = [(i + 1, ln) for i, ln in enumerate(lines) if ln.strip() and not ln.lstrip().startswith("#")]
    if not numbered:
        raise MeasurementError(f"{path}: no header and no rows")
    if len(numbered) - 1 > MAX_ROWS:
        raise MeasurementError(f"{path}: {len(numbered) - 1} rows; at most {MAX_ROWS} are read (the diagnosis's cost "
                               f"grows with the rows squared: split the file by material)")
    for lineno, ln in numbered:
        if len(ln) > MAX_LINE:
            raise MeasurementError(f"{path}:{lineno}: a line of {len(ln)} characters; at most {MAX_LINE}")
    try:
        rows = list(csv.reader([ln for _, ln in numbered]))
    except csv.Error as exc:  # a NUL byte, a field past csv's own limit
        raise MeasurementError(f"{path}: not a CSV file ({exc})") from None
    header = [h.strip() for h in rows[0]]
    missing = [c for c in COLUMNS[:5] if c not in header]
    if missing:
        raise MeasurementError(f"{path}:{numbered[0][0]}: header lacks column(s) {', '.join(missing)} "
                               f"(expected {','.join(COLUMNS)})")
    unknown = [c for c in header if c not in COLUMNS]
    if unknown:
        raise MeasurementError(f"{path}:{numbered[0][0]}: unknown column(s) {', '.join(unknown)}")
    out, seen = [], {}
    for (lineno, _), row in zip(numbered[1:], rows[1:]):
        if len(row) != len(header):
            raise MeasurementError(f"{path}:{lineno}: {len(row)} fields, the header has {len(header)}")
        rec = dict(zip(header, (x.strip() for x in row)))
        where = lambda col: f"{path}:{lineno}, column '{col}'"  # noqa: E731
        for col in ("material", "test", "quantity"):
            if not rec[col]:
                raise MeasurementError(f"{where(col)}: empty")
        test, quantity = rec["test"], rec["quantity"]
        if test not in TABLE:
            raise MeasurementError(f"{where('test')}: unknown test {test!r} (known: {', '.join(TABLE)})")
        if quantity not in TABLE[test]:
            raise MeasurementError(f"{where('quantity')}: test {test} has no quantity {quantity!r} "
                                   f"(known: {', '.join(TABLE[test])})")
        spec = TABLE[test][quantity]
        si_unit, units, (vmin, vmax) = spec.unit, spec.units, spec.range
        unit_text = rec.get("unit", "").strip()
        factor = 1.0 if unit_text == "" else units.get(unit_text, units.get(unit_text.lower()))  # empty: SI
        if factor is None:
            raise MeasurementError(f"{where('unit')}: {quantity} in {unit_text!r} is not understood "
                                   f"(give {si_unit or 'no unit'}; also accepted: {', '.join(u for u in units if u) or 'none'})")
        value = _number(rec["value"], where("value"), False) * factor
        unc = _number(rec["uncertainty"], where("uncertainty"), True) * factor
        if unc == unc and unc <= 0:
            raise MeasurementError(f"{where('uncertainty')}: must be positive (or empty when unknown), got {unc:g}")
        if not vmin <= value <= vmax or (vmin == 0.0 and value == 0.0 and not spec.zero_ok):
            u_txt = f" {si_unit}" if si_unit else ""
            raise MeasurementError(f"{where('value')}: {quantity} = {value:g}{u_txt} is outside the physically "
                                   f"possible range ({vmin:g}, {vmax:g}]{u_txt}")
        conditions = {}
        for item in filter(None, (s.strip() for s in rec.get("conditions", "").split(";"))):
            if "=" not in item:
                raise MeasurementError(f"{where('conditions')}: expected key=value, got {item!r}")
            k, v = item.split("=", 1)
            if k.strip() not in CONDITION_UNITS:
                raise MeasurementError(f"{where('conditions')}: unknown condition {k.strip()!r} "
                                       f"(known: {', '.join(CONDITION_UNITS)})")
            conditions[k.strip()] = v.strip()
        if "shear_fraction" in conditions:
            f = _number(conditions["shear_fraction"], where("conditions") + " shear_fraction", False)
            if not 0 < f <= 1:
                raise MeasurementError(f"{where('conditions')}: shear_fraction {f:g} must lie in (0, 1]")
        use = rec.get("use", "") or "calibrate"
        if use not in USES:
            raise MeasurementError(f"{where('use')}: {use!r} is not one of {', '.join(USES)}")
        origin = rec.get("origin", "") or "lab"
        if origin not in ORIGINS:
            raise MeasurementError(f"{where('origin')}: {origin!r} is not one of {', '.join(ORIGINS)} (lab: a lab's "
                                   f"measurement, the default; dem: one DEM run)")
        m = Measurement(rec["material"], test, quantity, value, unc, si_unit, conditions, use, rec.get("source", ""), lineno,
                        origin)
        key = (m.material, test, quantity, tuple(sorted(conditions.items())))
        if key in seen:
            raise MeasurementError(f"{path}:{lineno}: duplicate of line {seen[key]} (same material, test, quantity "
                                   f"and conditions)")
        seen[key] = lineno
        if material is None or m.material == material:
            out.append(m)
    if material is not None and not out:
        known = sorted({r[header.index("material")] for r in rows[1:] if len(r) == len(header)})
        raise MeasurementError(f"{path}: no rows for material {material!r} (materials: {', '.join(known)})")
    return out
