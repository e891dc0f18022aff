"""Release profiles as a pharmaceutics lab records them: cumulative release against time,
one column per dosage unit (vessel, bead batch, tablet), read and checked once.

A CSV is read with the column rules of ``dosing.fits.csv_tables`` (units from the header: ``time_s``
/ ``time (min)`` / ``t [h]``; ``released`` as a fraction, ``released (%)`` or a mass
``released_ug`` with ``loaded_ug``), extended to replicate units: several release columns,
named ``released_1 (%)``, ``unit 01 (%)``, ``vessel 2 [%]``, ``R3`` or the same release
name repeated.  Values are kept in percent of the load; times in the file's own unit (the
empirical models' parameters are stated in it) and in seconds.

Refused, naming the line and column of a CSV (``REF.csv: line 7, column 3 (unit 2 (%))``)
or the index of an array (``units[1][4]``): a non-number, a time that is negative or does
not increase, a release outside -5 ... 105 %, fewer than 3 time points.
"""

from __future__ import annotations

import csv
import io
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from solver.errors import ParameterError

from .. import quantity
from ..fits.csv_tables import (
    _canonical,
    _delimiter,
    _number,
    _split_unit,
    _trim,
    _unit_factor,
    read_text,
)

MIN_POINTS = 3
PERCENT_RANGE = (-5.0, 105.0)  # a release outside it is a unit or typing error
RELEASED_UNITS = ("fraction", "percent", "ug")
TIME_UNITS = {"s": 1.0, "min": 60.0, "h": 3600.0, "d": 86400.0}
_UNIT_WORDS = ("unit", "vessel", "tablet", "bead", "batch", "replicate", "rep", "sample",
               "r", "u", "v", "n", "")
_REPLICATE = re.compile(r"^(?P<stem>.*?)[\s_#.\-]*(?P<k>\d+)$")


@dataclass
class Profile:
    """One release profile: ``times`` (in ``time_unit``), ``units`` (percent released, one
    column per dosage unit), where each value came from (for the errors)."""

    times: np.ndarray
    units: np.ndarray  # (n_times, n_units), percent of the load
    time_unit: str = "s"
    seconds_per_unit: float = 1.0
    label: str = ""
    lines: list[int] | None = None  # CSV line of each time (None: arrays)
    columns: list[str] = field(default_factory=list)  # time column then each unit's
    notes: list[str] = field(default_factory=list)

    @property
    def time_s(self) -> np.ndarray:
        """The times in s."""
        return self.times * self.seconds_per_unit

    @property
    def n_units(self) -> int:
        """Dosage units (replicate columns)."""
        return int(self.units.shape[1])

    @property
    def mean(self) -> np.ndarray:
        """The mean profile, percent."""
        return self.units.mean(axis=1)

    @property
    def sd(self) -> np.ndarray | None:
        """The units' standard deviation (ddof 1), percent; None for one unit."""
        return self.units.std(axis=1, ddof=1) if self.n_units > 1 else None

    def where(self, i: int | None, j: int | None = None) -> str:
        """Where row ``i`` (its time when ``j`` is None, else unit ``j``) came from."""
        if self.lines is not None:
            line = "" if i is None else f"line {self.lines[i]}, "
            col = 0 if j is None else j + 1
            return f"{self.label}: {line}column {col + 1} ({self.columns[col]})"
        pre = f"{self.label}." if self.label else ""
        if j is None:
            return f"{pre}time" + ("" if i is None else f"[{i}]")
        if self.columns and self.columns[1] == "released":
            return f"{pre}released" + ("" if i is None else f"[{i}]")
        return f"{pre}units[{j}]" + ("" if i is None else f"[{i}]")

    def to_dict(self) -> dict[str, Any]:
        """The profile as read: times, mean, spread, units."""
        sd = self.sd
        return {"label": self.label, "time": self.times.tolist(), "time_unit": self.time_unit,
                "time_s": self.time_s.tolist(), "n_units": self.n_units,
                "mean_percent": self.mean.tolist(),
                "sd_percent": None if sd is None else sd.tolist(),
                "units_percent": self.units.T.tolist(), "notes": list(self.notes)}


def check(p: Profile) -> Profile:
    """Refuse what no analysis can use (module doc), naming the line and column."""
    n = p.times.size
    if n < MIN_POINTS:
        where = p.where(None) if not p.lines else (
            f"{p.label}: lines {p.lines[0]}-{p.lines[-1]}, column 1 ({p.columns[0]})")
        raise ParameterError(where, f"{n} time points",
                             f"at least {MIN_POINTS} time points")
    for i in range(n):
        if not np.isfinite(p.times[i]):
            raise ParameterError(p.where(i), "empty", "a number")
        if p.times[i] < 0:
            raise ParameterError(p.where(i), float(p.times[i]), "times >= 0")
        if i and p.times[i] <= p.times[i - 1]:
            raise ParameterError(p.where(i), float(p.times[i]),
                                 f"times increasing down the column (after "
                                 f"{p.times[i - 1]:g} {p.time_unit})",
                                 "time does not increase")
    lo, hi = PERCENT_RANGE
    for i in range(n):
        for j in range(p.n_units):
            v = float(p.units[i, j])
            if not np.isfinite(v):
                raise ParameterError(p.where(i, j), "empty", "a number")
            if v < lo or v > hi:
                raise ParameterError(p.where(i, j), round(v, 6),
                                     f"{lo:g} ... {hi:g} % of the load (a fraction, "
                                     "'released (%)', or a mass with loaded_ug)",
                                     "released more than the load" if v > hi else "")
    return p


def time_unit_of(unit: str) -> tuple[str, float]:
    """(name, seconds per unit) of a time unit as written ('min', 'minutes', 'h', ...)."""
    u = (unit or "s").strip()
    if u in TIME_UNITS:
        return u, TIME_UNITS[u]
    secs = quantity.seconds(f"1 {u}", "time_unit")
    name = next((k for k, v in TIME_UNITS.items() if abs(v - secs) < 1e-9 * v), u)
    return name, float(secs)


def from_arrays(time: Any, released: Any = None, units: Any = None, *,
                time_unit: str = "s", released_unit: str = "fraction",
                loaded_ug: float | None = None, label: str = "") -> Profile:
    """A checked profile from arrays: one ``released`` profile, or ``units`` (one list per
    dosage unit, each at every time), in ``released_unit`` ('fraction', 'percent', 'ug'
    with ``loaded_ug``); ``label`` prefixes the field names of errors."""
    pre = f"{label}." if label else ""
    if (released is None) == (units is None):
        raise ParameterError(f"{pre}released", None, "one of released (a profile) or units "
                             "(one profile per dosage unit)")
    if released_unit not in RELEASED_UNITS:
        raise ParameterError(f"{pre}released_unit", released_unit,
                             " or ".join(map(repr, RELEASED_UNITS)))
    name, secs = time_unit_of(time_unit)
    t = np.asarray(time, dtype=float).reshape(-1)
    cols = [np.asarray(released, dtype=float).reshape(-1)] if units is None else [
        np.asarray(u, dtype=float).reshape(-1) for u in units]
    if not cols:
        raise ParameterError(f"{pre}units", "[]", "at least one dosage unit")
    for j, c in enumerate(cols):
        if c.size != t.size:
            where = f"{pre}released" if units is None else f"{pre}units[{j}]"
            raise ParameterError(where, f"{c.size} values for {t.size} times",
                                 "one value per time")
    y = np.column_stack(cols) * _scale(released_unit, loaded_ug, f"{pre}loaded_ug")
    p = Profile(t, y, name, secs, label, None,
                ["time", "released" if units is None else "units"])
    return check(p)


def _scale(unit: str, loaded_ug: float | None, where: str) -> float:
    """Percent per value of ``unit``."""
    if unit == "percent":
        return 1.0
    if unit == "fraction":
        return 100.0
    if loaded_ug is None or not np.isfinite(loaded_ug) or loaded_ug <= 0:
        raise ParameterError(where, loaded_ug, "a finite number > 0 (ug loaded) to turn a "
                             "released mass into a fraction")
    return 100.0 / float(loaded_ug)


def _column(head: str) -> tuple[str | None, str | None]:
    """(canonical name, unit) of a header cell: time, released, or a replicate unit's
    release column ('released_2 (%)', 'unit 01 (%)', 'R3')."""
    canon, unit = _canonical(head, ("time", "released"))
    if canon is not None:
        return canon, unit
    base, unit = _split_unit(head)
    m = _REPLICATE.match(base.strip().lower())
    if m is None:
        return None, None
    stem = re.sub(r"[\s\-]+", "_", m.group("stem")).strip("_")
    if stem in _UNIT_WORDS:
        return "released", unit
    canon, suffix = _canonical(stem + (f" ({unit})" if unit else ""), ("released",))
    return (canon, unit if unit is not None else suffix) if canon else (None, None)


def read_profile(source: str | Path, loaded_ug: float | None = None,
                 label: str | None = None) -> Profile:
    """A checked profile from a lab's CSV (module doc): a path or the CSV text."""
    text, where = read_text(source)
    label = label or (Path(where).name if where != "text" else "data")
    lines = text.splitlines()
    delim = _delimiter(lines)
    comma = delim in (";", "\t")
    try:
        rows = [(i, _trim(r)) for i, r in enumerate(csv.reader(io.StringIO(text),
                                                                delimiter=delim), start=1)
                if r and any(c.strip() for c in r) and not r[0].lstrip().startswith("#")]
    except csv.Error as exc:
        raise ParameterError(label, "not CSV", "a CSV file", str(exc)) from None
    if not rows:
        raise ParameterError(label, "empty", "a CSV with a time and a release column")
    head_line, head = rows[0]
    try:
        [_number(c, comma) for c in head]
        has_header = False
    except ValueError:
        has_header = True
    if has_header:
        kinds = [_column(h) for h in head]
        for j, (k, _) in enumerate(kinds):
            if k is None:
                raise ParameterError(f"{label}: line {head_line}, column {j + 1}",
                                     head[j].strip(), "time (first), then one release "
                                     "column per dosage unit, each with a unit, e.g. "
                                     "'time_min', 'released (%)' or 'unit 1 (%)', 'unit 2 "
                                     "(%)'", "unknown column name")
        if kinds[0][0] != "time" or any(k == "time" for k, _ in kinds[1:]):
            raise ParameterError(f"{label}: line {head_line}, column 1", head[0].strip(),
                                 "one time column, first")
        names = [h.strip() for h in head]
        body = rows[1:]
    else:
        kinds = [("time", None)] + [("released", None)] * (len(head) - 1)
        names = ["time"] + [f"released {j}" for j in range(1, len(head))]
        body = rows
    if len(kinds) < 2:
        raise ParameterError(f"{label}: line {head_line}", delim.join(head),
                             "a time column and at least one release column")
    t_conv, t_unit = _unit_factor("time", kinds[0][1], names[0])
    units_read = []
    convs = []
    for j in range(1, len(kinds)):
        conv, u = _unit_factor("released", kinds[j][1], f"{label}: column {j + 1}")
        if units_read and u != units_read[0]:
            raise ParameterError(f"{label}: line {head_line}, column {j + 1} ({names[j]})",
                                 u, f"the unit of the other release columns ({units_read[0]})")
        units_read.append(u)
        convs.append(conv)
    raw = np.full((len(body), len(kinds)), np.nan)
    for r, (i, row) in enumerate(body):
        if len(row) != len(kinds):
            raise ParameterError(f"{label}: line {i}", delim.join(row),
                                 f"{len(kinds)} values ({', '.join(names)})")
        for j, cell in enumerate(row):
            try:
                raw[r, j] = _number(cell, comma)
            except ValueError:
                raise ParameterError(f"{label}: line {i}, column {j + 1} ({names[j]})",
                                     cell.strip(), "a number") from None
    mass = "as ug" in units_read[0]
    y = np.column_stack([convs[j](raw[:, j + 1]) for j in range(len(convs))])
    if mass:
        y = y * _scale("ug", loaded_ug, "loaded_ug")
    else:
        y = y * 100.0  # the converters give fractions
    unit_name, secs = time_unit_of(t_unit if kinds[0][1] else "s")
    notes = [f"time in {unit_name}", f"release read as {units_read[0]}",
             f"{y.shape[1]} dosage unit(s)"]
    if not has_header:
        notes.append("no header: time in s, release as a fraction")
    p = Profile(raw[:, 0] * (float(t_conv(1.0)) / secs), y, unit_name, secs, label,
                [i for i, _ in body], names, notes)
    return check(p)


def same_grid(ref: Profile, test: Profile, tol: float = 1e-6) -> None:
    """Refuse two profiles whose times differ, naming the first differing line."""
    if ref.times.size != test.times.size:
        i = min(ref.times.size, test.times.size)
        longer = ref if ref.times.size > test.times.size else test
        raise ParameterError(longer.where(i), f"{ref.times.size} and {test.times.size} times",
                             "the same time points in both profiles (the FDA f2 compares "
                             "the profiles at the same times)", "unequal time grids")
    a, b = ref.time_s, test.time_s
    bad = np.nonzero(np.abs(a - b) > tol * np.maximum(1.0, np.abs(a)))[0]
    if bad.size:
        i = int(bad[0])
        raise ParameterError(test.where(i), f"{test.times[i]:g} {test.time_unit}",
                             f"{ref.times[i]:g} {ref.time_unit}, the time of {ref.where(i)}",
                             "unequal time grids")
