"""Reading the tables labs write: swelling, shrinking and release curves from CSV text.

Accepted (``docs/fitting.md``, templates in ``dosing/data/``):

* delimiters ``,`` ``;`` or tab (with ``;`` a decimal comma is read too: ``30,5;1,21``);
* a header row or none; ``#`` lines are comments; a UTF-8 byte-order mark is skipped;
* column names with a unit in brackets, after a slash or as a suffix: ``temperature_C``,
  ``T (degC)``, ``Temperature [K]``, ``diameter_um``, ``d (mm)``, ``radius (a.u.)``,
  ``time_min``, ``t [h]``; units are converted with ``dosing.quantity`` (pint): temperatures
  to K, times to s, lengths to um; an arbitrary unit (``a.u.``, ``au``, ``arb``, ``px``)
  is kept as written (a swelling or kinetics fit has a free size scale);
* a temperature without a unit is K when every value exceeds 200, else degC;
* without a header, the columns are (temperature or time, size as a radius[, weight]).

Errors are ``ParameterError`` naming ``line L, column C (name)``.  A file larger than
``MAX_BYTES`` is refused from its size, before it is read.
"""

from __future__ import annotations

import csv
import io
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from solver.errors import ParameterError

from .. import quantity

MAX_BYTES = 4 * 1024 * 1024  # 4 MiB: ~100 000 rows; a measured curve is a few kB

# recognised column names (lower case, spaces and '-' as '_') -> canonical name
_NAMES = {
    "temperature": ("temperature", "temp", "t", "theta"),
    "time": ("time", "t", "elapsed", "elapsed_time"),
    "radius": ("radius", "r", "size", "bead_radius"),
    "diameter": ("diameter", "d", "diam", "bead_diameter", "hydrodynamic_diameter", "dh"),
    "volume_ratio": ("volume_ratio", "v/v0", "v_v0", "volume", "swelling_ratio",
                     "volume_swelling_ratio"),
    "released": ("released", "release", "fraction_released", "cumulative_release",
                 "cumulative_released", "fraction", "mass_released", "amount_released",
                 "drug_released"),
    "weight": ("weight", "w"),
}
_ARBITRARY = {"a.u.", "au", "a.u", "arb", "arb.", "arb._units", "arbitrary", "arbitrary_units",
              "px", "pixel", "pixels", "rel", "rel.", "relative", "-", ""}
_TEMPERATURE_UNITS = {"c": "degC", "degc": "degC", "celsius": "degC", "deg_c": "degC",
                      "k": "K", "kelvin": "K"}
_FRACTION_UNITS = {"%": 0.01, "percent": 0.01, "fraction": 1.0, "": 1.0, "-": 1.0,
                   "1": 1.0}
_UNIT_RE = re.compile(r"^(?P<name>.*?)\s*(?:\((?P<p>[^)]*)\)|\[(?P<b>[^\]]*)\]"
                      r"|/\s*(?P<s>[^/]+))\s*$")


@dataclass
class Table:
    """Columns (canonical name -> values in K, s, um, or as written), how each was read, and
    notes for the report."""

    columns: dict[str, np.ndarray]
    units: dict[str, str]
    notes: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """How the file was read (for the fit report)."""
        return {"columns": list(self.columns), "units": dict(self.units),
                "notes": list(self.notes), "rows": int(len(next(iter(self.columns.values()))))}


def read_text(source: str | Path) -> tuple[str, str]:
    """(text, label) from a path or the CSV text itself, refusing big files before reading."""
    if isinstance(source, str) and "\n" in source:
        if len(source.encode("utf-8", "replace")) > MAX_BYTES:
            raise ParameterError("file", f"{len(source)} characters",
                                 f"a CSV of at most {MAX_BYTES // 1024 // 1024} MiB")
        return source.lstrip("\ufeff"), "text"
    p = Path(source)
    if not p.is_file():
        raise ParameterError("file", str(source), "a readable CSV file")
    size = p.stat().st_size
    if size > MAX_BYTES:
        raise ParameterError("file", f"{source} ({size / 1024 / 1024:.1f} MiB)",
                             f"a CSV of at most {MAX_BYTES // 1024 // 1024} MiB (a measured "
                             "curve is a few kB): refused before reading")
    try:
        return p.read_text(encoding="utf-8-sig"), str(source)
    except (OSError, UnicodeDecodeError) as exc:
        raise ParameterError("file", str(source), "a readable UTF-8 CSV file",
                             str(exc)) from None


def _delimiter(lines: list[str]) -> str:
    first = next((ln for ln in lines if ln.strip() and not ln.lstrip().startswith("#")), "")
    if "\t" in first:
        return "\t"
    if ";" in first:
        return ";"
    return ","


def _number(cell: str, decimal_comma: bool) -> float:
    c = cell.strip()
    if decimal_comma:
        c = c.replace(",", ".")
    return float(c) if c else math.nan


def _split_unit(header: str) -> tuple[str, str | None]:
    h = header.strip().strip('"').strip()
    m = _UNIT_RE.match(h)
    if m and m.group("name"):
        unit = next(g for g in (m.group("p"), m.group("b"), m.group("s")) if g is not None)
        name = m.group("name")
        if name.lower() in ("v", "m", "mt") and m.group("s") is not None:  # V/V0, Mt/Minf
            return h, None
        return name.strip(), unit.strip()
    return h, None


def _canonical(name: str, wanted: tuple[str, ...]) -> tuple[str | None, str | None]:
    """(canonical column, unit suffix) of a header cell, or (None, None)."""
    base, unit = _split_unit(name)
    key = re.sub(r"[\s\-]+", "_", base.strip().lower())
    for canon in wanted:
        if key in _NAMES[canon]:
            return canon, unit
    if unit is None and "_" in key:  # suffix unit: temperature_C, diameter_um, time_min
        stem, suffix = key.rsplit("_", 1)
        for canon in wanted:
            if stem in _NAMES[canon]:
                return canon, suffix
    return None, None


def _unit_factor(canon: str, unit: str | None, col: str) -> tuple[Any, str]:
    """A converter values -> documented unit for one column, and the unit as read."""
    u = (unit or "").strip()
    ul = u.lower().replace(" ", "_")
    if canon == "temperature":
        if not u:
            return None, ""  # decided from the values
        pint_unit = _TEMPERATURE_UNITS.get(ul.replace("°", ""), u)
        a = quantity.kelvin(f"0 {pint_unit}", col)
        b = quantity.kelvin(f"1 {pint_unit}", col) - a
        return (lambda x: a + b * x), pint_unit
    if canon in ("radius", "diameter"):
        if ul in _ARBITRARY:
            return (lambda x: x), u or "as written"
        f = quantity.micrometres(f"1 {u}", col)
        return (lambda x: f * x), u
    if canon == "time":
        if not u:
            return (lambda x: x), "s"
        f = quantity.seconds(f"1 {u}", col)
        return (lambda x: f * x), u
    if canon == "released":
        if ul in _FRACTION_UNITS:
            f = _FRACTION_UNITS[ul]
            return (lambda x: f * x), u or "fraction"
        f = quantity.to_unit(f"1 {u}", "mass", col)
        return (lambda x: f * x), f"{u} (as ug)"
    if ul in _ARBITRARY:  # volume_ratio, weight
        return (lambda x: x), u or "as written"
    raise ParameterError(col, unit, "no unit (a ratio)")


def read_table(source: str | Path, first: str, sizes: tuple[str, ...]) -> Table:
    """Read a lab's CSV (module doc): ``first`` ('temperature', 'time') and one of ``sizes``
    (canonical names), optional weight."""
    text, label = read_text(source)
    lines = text.splitlines()
    delim = _delimiter(lines)
    decimal_comma = delim in (";", "\t")
    try:
        rows = [(i, r) for i, r in enumerate(csv.reader(io.StringIO(text), delimiter=delim),
                                              start=1)
                if r and any(c.strip() for c in r) and not r[0].lstrip().startswith("#")]
    except csv.Error as exc:
        raise ParameterError("file", label[:80], "a CSV file", str(exc)) from None
    if not rows:
        raise ParameterError("file", "empty", f"a CSV with a {first} and a size column "
                             f"({', '.join(sizes)})")
    rows = [(i, _trim(r)) for i, r in rows]
    first_line, head = rows[0]
    notes: list[str] = []
    try:
        [_number(c, decimal_comma) for c in head]
        has_header = False
    except ValueError:
        has_header = True
    wanted = (first, *sizes, "weight")
    if has_header:
        names: list[str] = []
        units: list[str | None] = []
        for j, h in enumerate(head):
            canon, unit = _canonical(h, wanted)
            if canon is None:
                raise ParameterError(f"line {first_line}, column {j + 1}", h.strip(),
                                     f"a column name: {first}, one of {', '.join(sizes)}, "
                                     "optional weight, each with an optional unit, e.g. "
                                     f"{_example(first, sizes)}",
                                     f"unknown column name(s) {h.strip()!r}")
            if canon in names:
                raise ParameterError(f"line {first_line}, column {j + 1}", h.strip(),
                                     "each column once")
            names.append(canon)
            units.append(unit)
        body = rows[1:]
    else:
        if len(head) not in (2, 3):
            raise ParameterError(f"line {first_line}", delim.join(head),
                                 f"a header row, or 2-3 columns ({first}, size as a radius"
                                 "[, weight])")
        names = [first, sizes[0], "weight"][:len(head)]
        units = [None] * len(head)
        body = rows
        notes.append(f"no header: columns read as {', '.join(names)}")
    if first not in names:
        raise ParameterError(f"line {first_line}", delim.join(head), f"a {first} column")
    found = [n for n in names if n in sizes]
    if len(found) != 1:
        raise ParameterError(f"line {first_line}", delim.join(head),
                             f"exactly one size column among {', '.join(sizes)}")
    raw: dict[str, list[float]] = {n: [] for n in names}
    for i, row in body:
        if len(row) != len(names):
            raise ParameterError(f"line {i}", delim.join(row),
                                 f"{len(names)} values ({', '.join(names)})")
        for j, (n, cell) in enumerate(zip(names, row, strict=True)):
            try:
                raw[n].append(_number(cell, decimal_comma))
            except ValueError:
                label_j = head[j].strip() if has_header else n
                raise ParameterError(f"line {i}, column {j + 1} ({label_j})", cell.strip(),
                                     "a number") from None
    if not body:
        raise ParameterError("file", label[:80], "data rows below the header")
    cols: dict[str, np.ndarray] = {}
    read_units: dict[str, str] = {}
    for j, n in enumerate(names):
        col = f"column {j + 1} ({head[j].strip() if has_header else n})"
        conv, u = _unit_factor(n, units[j], col)
        x = np.array(raw[n], dtype=float)
        if n == "temperature" and conv is None:
            conv, u = _unit_factor(n, "K" if np.nanmin(x) > 200.0 else "degC", col)
            notes.append(f"temperature without a unit read as {u} (values "
                         f"{np.nanmin(x):.4g}-{np.nanmax(x):.4g})")
        cols[n] = np.asarray(conv(x), dtype=float)
        read_units[n] = u
    return Table(cols, read_units, notes)


def _trim(row: list[str]) -> list[str]:
    """Trailing empty cells (a spreadsheet's "300;1.2;") dropped."""
    out = list(row)
    while out and not out[-1].strip():
        out.pop()
    return out


def _example(first: str, sizes: tuple[str, ...]) -> str:
    if first == "temperature":
        return "'temperature_C', 'T (K)', 'diameter_um', 'radius (a.u.)'"
    if sizes == ("released",):
        return "'time_h', 'released (%)', 'released_ug'"
    return "'time_s', 't (min)', 'diameter_um'"
