"""Heating a lab can do: a step grammar, the typed ``Protocol`` and its program in tau.

Steps in the style of PyBaMM's ``Experiment`` (heat, cool, hold, rest, bath, trace; until-
conditions) in physical units parsed by :mod:`dosing.quantity`, or as structured JSON
(:func:`parse_step`); every error a ``ParameterError`` naming the step.  Seconds become tau at
the protocol's hottest temperature (eq. timescale).  docs/heating.md, "Planner: the step ..."."""

from __future__ import annotations

import csv
import io
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from solver.errors import ParameterError
from solver.gel import T_MAX, T_MIN
from solver.limits import PROGRAM_STEP_MAX

from ..quantity import kelvin, kelvin_offset, parse, to_unit

RATE_RANGE_K_PER_MIN = (1e-3, 1e6)  # 0.001 K/min (a day per 1.4 K) to 10^6 K/min (~a jump)
DURATION_MAX_S = 1.0e7  # about 116 days
TAU_MAX = PROGRAM_STEP_MAX  # the solver's longest step (solver.limits)
TIME_CONSTANT_RANGE_S = (1e-3, 1e6)
TRACE_MAX_ROWS = 100_000
TRACE_TEMPERATURE_RANGE = (T_MIN, T_MAX)  # 273.15-373.15 K: liquid water

_NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_TAU_TIME = re.compile(rf"^\s*({_NUM})\s*tau\s*$", re.I)
_TAU_RATE = re.compile(rf"^\s*({_NUM})\s*(?:K|kelvin|degC|°C|delta_degC)\s*/\s*tau\s*$", re.I)


# ----------------------------------------------------------------------------- quantities
@dataclass(frozen=True)
class Span:
    """A duration: ``value`` seconds, or ``value`` tau when ``unit`` is 'tau'."""

    value: float
    unit: str = "s"

    def tau(self, tau_s: float | None) -> float:
        """The duration in tau (seconds over ``tau_s``)."""
        if self.unit == "tau":
            return self.value
        if tau_s is None:
            raise ParameterError("dry_radius_um", None, "a finite number > 0 (um; or "
                                 "swollen_radius_um) to turn the protocol's seconds into tau")
        return self.value / tau_s

    def seconds(self, tau_s: float | None) -> float | None:
        """The duration in seconds (None for a tau duration without a timescale)."""
        if self.unit == "s":
            return self.value
        return None if tau_s is None else self.value * tau_s

    @property
    def text(self) -> str:
        """As written in the grammar."""
        return f"{self.value:g} tau" if self.unit == "tau" else _seconds_text(self.value)


def _seconds_text(s: float) -> str:
    if s >= 3600.0 and s % 3600.0 == 0.0:
        return f"{s / 3600.0:g} h"
    if s >= 60.0 and s % 60.0 == 0.0:
        return f"{s / 60.0:g} min"
    return f"{s:g} s"


MAX_QUANTITY_CHARS = 80


class _Where:
    """Names the step of an error: field ``protocol[i].<name>``, reason quoting the text."""

    def __init__(self, index: int, text: str, context: str = "",
                 sub: int | None = None) -> None:
        # a step of a repeat: ``sub`` its place in the repeat (field protocol[i].steps[k]),
        # ``context`` which repetition (" (repeat 2 of 3)")
        self.index, self.text, self.context, self.sub = index, text, context, sub

    def guard(self, value: Any, name: str) -> Any:
        """A quantity string pint may evaluate: no powers (pint computes '9**9**9' exactly,
        for ever) and at most MAX_QUANTITY_CHARS characters."""
        if isinstance(value, str) and ("**" in value or "^" in value
                                       or len(value) > MAX_QUANTITY_CHARS):
            raise self.error(name, value[:MAX_QUANTITY_CHARS], "a number and a unit, e.g. "
                             f"'5 K/min' (no powers; at most {MAX_QUANTITY_CHARS} characters)")
        return value

    def error(self, name: str, value: Any, valid: str) -> ParameterError:
        head = f"protocol[{self.index}]" + ("" if self.sub is None else f".steps[{self.sub}]")
        where = (f"step {self.index}" if self.sub is None else
                 f"step {self.sub} of the repeat in step {self.index}")
        return ParameterError(f"{head}.{name}" if name else head, value, valid,
                              f"in {where}{self.context}: {self.text!r}")

    def temperature(self, value: Any, name: str) -> float:
        self.guard(value, name)
        try:
            t = kelvin(value, name)
        except ParameterError as exc:
            raise self.error(name, value, f"{T_MIN}-{T_MAX} K or 0-100 degC "
                                          f"({exc.valid})") from None
        if not T_MIN <= t <= T_MAX:
            raise self.error(name, value, f"{T_MIN}-{T_MAX} K (0-100 degC, liquid water)")
        return t

    def span(self, value: Any, name: str, lo_s: float = 0.0,
             hi_s: float = DURATION_MAX_S) -> Span:
        valid = (f"{lo_s:g} s < {name} <= {hi_s:g} s (or 0 < {name} <= {TAU_MAX:g} tau); "
                 "units s, min, h or tau")
        self.guard(value, name)
        if isinstance(value, Span):
            span = value
        else:
            m = _TAU_TIME.match(value) if isinstance(value, str) else None
            if m:
                span = Span(float(m.group(1)), "tau")
            else:
                try:
                    span = Span(to_unit(value, "time", name))
                except ParameterError:
                    raise self.error(name, value, valid) from None
        top = TAU_MAX if span.unit == "tau" else hi_s
        if not (math.isfinite(span.value) and span.value > (0.0 if span.unit == "tau" else lo_s)
                and span.value <= top):
            raise self.error(name, value, valid)
        return span

    def rate(self, value: Any, name: str = "rate") -> tuple[float, str]:
        self.guard(value, name)
        lo, hi = RATE_RANGE_K_PER_MIN
        valid = f"{lo:g}-{hi:g} K/min (units K/s, K/min, K/h, degC/min or K/tau)"
        m = _TAU_RATE.match(value) if isinstance(value, str) else None
        if m:
            r, unit = float(m.group(1)), "K/tau"
            ok = math.isfinite(r) and r > 0.0
        else:
            if isinstance(value, str):  # a rate in degC is a difference, not an offset
                value = re.sub(r"(?<!delta_)(degC|°C|℃)", "delta_degC", value)
            try:
                r, unit = to_unit(value, "temperature_rate", name), "K/s"
            except ParameterError:
                raise self.error(name, value, valid) from None
            ok = lo <= 60.0 * r <= hi
        if not ok:
            raise self.error(name, value, valid)
        return r, unit


# ----------------------------------------------------------------------------- until
UNTIL_KINDS = ("fraction", "mass_ug", "volume_ul", "radius_um")


@dataclass(frozen=True)
class Until:
    """An until-condition: a cumulative dose released since the protocol's start (a
    fraction of the stored fluid, a drug mass in ug, a fluid volume in uL) or the bead's
    radius in um (reached from either side)."""

    kind: str
    value: float

    @property
    def text(self) -> str:
        """As written in the grammar."""
        if self.kind == "fraction":
            return f"{100.0 * self.value:g} % released"
        if self.kind == "mass_ug":
            return f"{self.value:g} ug released"
        if self.kind == "volume_ul":
            return f"{self.value:g} uL released"
        return f"radius {self.value:g} um"

    def to_dict(self) -> dict[str, Any]:
        """Structured form: ``{"fraction": 0.3}``, ``{"mass_ug": 20}``, ..."""
        return {self.kind: self.value}


def _until(value: Any, where: _Where) -> Until:
    valid = ("'<n> % released', '<mass> ug released', '<volume> uL released' or "
             "'radius <r> um' (or {'fraction'|'mass_ug'|'volume_ul'|'radius_um': value})")
    if isinstance(value, Until):
        return value
    if isinstance(value, dict):
        if len(value) != 1 or next(iter(value)) not in UNTIL_KINDS:
            raise where.error("until", value, valid)
        kind, raw = next(iter(value.items()))
        where.guard(raw, f"until.{kind}")
        units = {"fraction": None, "mass_ug": "mass", "volume_ul": "volume",
                 "radius_um": "length"}
        try:
            x = (float(raw) if units[kind] is None
                 else to_unit(raw, units[kind], f"until.{kind}"))
        except (TypeError, ValueError):
            raise where.error(f"until.{kind}", raw, "a finite number > 0") from None
        return _until_checked(kind, x, raw, where)
    if not isinstance(value, str):
        raise where.error("until", value, valid)
    text = where.guard(value, "until").strip()
    m = re.match(r"^radius\s+(?:of\s+)?(.+)$", text, re.I)
    if m:
        try:
            x = to_unit(m.group(1), "length", "until.radius_um")
        except ParameterError:
            raise where.error("until.radius_um", m.group(1), "a length > 0 (um, mm)") from None
        return _until_checked("radius_um", x, value, where)
    m = re.match(r"^(.+?)\s+(?:released|delivered|expelled)$", text, re.I)
    if not m:
        raise where.error("until", value, valid)
    amount = m.group(1).strip()
    pm = re.match(rf"^({_NUM})\s*(%|percent)$", amount, re.I)
    if pm:
        return _until_checked("fraction", float(pm.group(1)) / 100.0, value, where)
    if re.match(rf"^{_NUM}$", amount):
        return _until_checked("fraction", float(amount), value, where)
    q = parse(amount, "until")
    for kind, unit_kind in (("mass_ug", "mass"), ("volume_ul", "volume")):
        try:
            return _until_checked(kind, to_unit(q, unit_kind, kind), value, where)
        except ParameterError:
            continue
    raise where.error("until", value, valid)


def _until_checked(kind: str, x: float, raw: Any, where: _Where) -> Until:
    if kind == "fraction":
        if not (math.isfinite(x) and 0.0 < x < 1.0):
            raise where.error("until.fraction", raw, "0 < fraction < 1 (0-100 % of the "
                                                      "stored fluid, from the protocol's start)")
    elif not (math.isfinite(x) and x > 0.0):
        raise where.error(f"until.{kind}", raw, "a finite number > 0")
    return Until(kind, x)


# ----------------------------------------------------------------------------- steps
@dataclass(frozen=True)
class Ramp:
    """A linear ramp from the current temperature to ``to_k`` at ``rate`` (K/s, or K/tau
    when ``rate_unit`` is 'K/tau'); ``kind`` 'heat' or 'cool' (the direction it must go)."""

    kind: str
    to_k: float
    rate: float
    rate_unit: str = "K/s"

    @property
    def text(self) -> str:
        """As written in the grammar."""
        rate = (f"{self.rate:g} K/tau" if self.rate_unit == "K/tau"
                else f"{60.0 * self.rate:g} K/min")
        return f"{self.kind.capitalize()} to {self.to_k:g} K at {rate}"

    def to_dict(self) -> dict[str, Any]:
        """Structured form (plain numbers: K, K/s; or strings with K/tau)."""
        rate: Any = self.rate if self.rate_unit == "K/s" else f"{self.rate:g} K/tau"
        return {"step": self.kind, "to": self.to_k, "rate": rate}

    def rate_tau(self, tau_s: float | None) -> float:
        """The rate in K per tau."""
        if self.rate_unit == "K/tau":
            return self.rate
        return self.rate / Span(1.0).tau(tau_s)  # K/s times tau in s


@dataclass(frozen=True)
class Hold:
    """A jump to ``at_k`` and a hold there ``for`` a duration, ``until`` a condition, or
    (the last step only) for ever; ``kind`` 'hold' or 'rest' (a rest is a hold by name)."""

    kind: str
    at_k: float
    duration: Span | None = None
    until: Until | None = None

    @property
    def text(self) -> str:
        """As written in the grammar."""
        return f"{self.kind.capitalize()} at {self.at_k:g} K{_end_text(self)}"

    def to_dict(self) -> dict[str, Any]:
        """Structured form."""
        return _with_end({"step": self.kind, "at": self.at_k}, self)


@dataclass(frozen=True)
class Bath:
    """A bath at ``at_k`` that the bead's temperature follows with a first-order lag of
    ``time_constant``: T(t) = T_bath + (T_0 - T_bath) exp(-t / tau_b) from the current
    temperature T_0; ``for`` / ``until`` end it (else it lasts, as the last step)."""

    at_k: float
    time_constant: Span
    duration: Span | None = None
    until: Until | None = None
    kind: str = "bath"

    @property
    def text(self) -> str:
        """As written in the grammar."""
        return (f"Bath at {self.at_k:g} K with a time constant of {self.time_constant.text}"
                f"{_end_text(self)}")

    def to_dict(self) -> dict[str, Any]:
        """Structured form."""
        tc: Any = (self.time_constant.value if self.time_constant.unit == "s"
                   else self.time_constant.text)
        return _with_end({"step": "bath", "at": self.at_k, "time_constant": tc}, self)


@dataclass(frozen=True)
class Trace:
    """A measured T(t): ``times_s`` from 0 (the step's start), ``temperatures_k``,
    interpolated linearly; ``name`` where it came from (a file name, or 'trace')."""

    times_s: tuple[float, ...]
    temperatures_k: tuple[float, ...]
    name: str = "trace"
    kind: str = "trace"

    @property
    def text(self) -> str:
        """As written in the grammar (a summary for a trace given as data)."""
        return (f"Trace from {self.name} ({len(self.times_s)} rows, "
                f"{self.times_s[-1]:g} s, {min(self.temperatures_k):g}-"
                f"{max(self.temperatures_k):g} K)")

    @property
    def duration(self) -> Span:
        """The trace's length."""
        return Span(self.times_s[-1] - self.times_s[0])

    until = None

    def to_dict(self) -> dict[str, Any]:
        """Structured form (seconds and kelvin)."""
        return {"step": "trace", "name": self.name, "time": list(self.times_s),
                "temperature": list(self.temperatures_k)}


Step = Ramp | Hold | Bath | Trace


def _end_text(step: Hold | Bath) -> str:
    """' for 2 min', ' until 30 % released', ' for 10 min or until 30 % released' or ''."""
    out = "" if step.duration is None else f" for {step.duration.text}"
    if step.until is not None:
        out += f"{' or' if out else ''} until {step.until.text}"
    return out


def _with_end(d: dict[str, Any], step: Hold | Bath) -> dict[str, Any]:
    if step.duration is not None:
        d["for"] = step.duration.value if step.duration.unit == "s" else step.duration.text
    if step.until is not None:
        d["until"] = step.until.to_dict()
    return d


# ----------------------------------------------------------------------------- traces
_TIME_UNITS = {"s": 1.0, "sec": 1.0, "second": 1.0, "seconds": 1.0, "min": 60.0,
               "minute": 60.0, "minutes": 60.0, "h": 3600.0, "hour": 3600.0, "hours": 3600.0}
_TEMP_UNITS = ("k", "kelvin", "degc", "c", "°c", "celsius")


def _unit_of(header: str) -> str | None:
    """The unit named in a column header: 'time (min)', 'T [degC]', 'time_s', 'T_C'."""
    h = header.strip().lower()
    m = re.search(r"[(\[]\s*([^)\]]+?)\s*[)\]]", h)
    if m:
        return m.group(1)
    m = re.search(r"[_ ]([a-z°]+)$", h)
    return m.group(1) if m else None


def _temperature_unit(unit: str | None, field: str) -> str:
    if unit is not None and not isinstance(unit, str):
        raise ParameterError(field, unit, "K or degC (a string)")
    u = (unit or "K").strip().lower().replace("deg c", "degc")
    if u in ("k", "kelvin"):
        return "K"
    if u in ("degc", "c", "°c", "celsius", "deg_c"):
        return "degC"
    raise ParameterError(field, unit, "K or degC")


def _time_scale(unit: str | None, field: str) -> float:
    if unit is not None and not isinstance(unit, str):
        raise ParameterError(field, unit, "s, min or h (a string)")
    u = (unit or "s").strip().lower()
    if u not in _TIME_UNITS:
        raise ParameterError(field, unit, "s, min or h")
    return _TIME_UNITS[u]


def trace_from_csv(text: str, time_unit: str | None = None,
                   temperature_unit: str | None = None, name: str = "trace",
                   index: int = 0) -> Trace:
    """A :class:`Trace` from CSV text: two columns, time and temperature, an optional header
    naming the units ('time (min),T (degC)', 'time_s,T_K'); ``time_unit`` s/min/h and
    ``temperature_unit`` K/degC override it (defaults s and K).  Refused, naming the line
    and the column: time not increasing, a value that is not a finite number, a temperature
    outside 273.15-373.15 K, more than 100,000 rows, fewer than 2."""
    where = _Where(index, f"Trace from {name}")
    if not isinstance(text, str):
        raise where.error("trace", type(text).__name__, "CSV text")
    # any line ending (CR alone too); a field over csv's limit is refused, not a crash
    text = text.replace("\r\n", "\n").replace("\r", "\n")
    try:
        rows = list(csv.reader(io.StringIO(text)))
    except csv.Error as exc:
        raise where.error("trace", f"CSV text ({exc})", "CSV text with a time and a "
                          "temperature column, a number in each cell") from None
    rows = [(k + 1, r) for k, r in enumerate(rows) if r and any(c.strip() for c in r)
            and not r[0].lstrip().startswith("#")]
    if not rows:
        raise where.error("trace", name, "CSV text with a time and a temperature column")
    header = None
    first = rows[0][1]
    try:
        float(first[0])
    except ValueError:
        header = first
        rows = rows[1:]
    if len(rows) > TRACE_MAX_ROWS:
        raise where.error("trace", f"{len(rows)} rows", f"2-{TRACE_MAX_ROWS} rows")
    if len(rows) < 2:
        raise where.error("trace", f"{len(rows)} rows", f"2-{TRACE_MAX_ROWS} rows")
    tu = time_unit or (_unit_of(header[0]) if header else None)
    ku = temperature_unit or (_unit_of(header[1]) if header and len(header) > 1 else None)
    try:
        scale = _time_scale(tu, "trace.time_unit")
        kunit = _temperature_unit(ku, "trace.temperature_unit")
    except ParameterError as exc:
        raise where.error(exc.field, exc.value, exc.valid) from None
    offset = kelvin_offset(kunit)
    short = next((line for line, r in rows if len(r) < 2), None)
    if short is not None:
        raise where.error("trace", f"line {short}", "two columns: time, temperature")
    cols = []
    for col in (0, 1):  # whole columns at once (100,000 rows in milliseconds)
        cells = [r[col] for _, r in rows]
        try:
            cols.append(np.array(cells, dtype=float))
        except ValueError:
            for (line, _), cell in zip(rows, cells, strict=True):
                try:
                    float(cell)
                except ValueError:
                    raise where.error("trace", f"line {line}, column {col + 1} "
                                      f"({'time' if col == 0 else 'temperature'}): "
                                      f"{cell[:40]!r}", "a finite number") from None
            raise
    return _trace_checked(cols[0] * scale, cols[1] + offset, name, where,
                          [line for line, _ in rows], kunit)


def _trace_checked(times: np.ndarray, temps: np.ndarray, name: str, where: _Where,
                   lines: Sequence[int] | None = None, kunit: str = "K") -> Trace:
    if times.size > TRACE_MAX_ROWS or times.size < 2:
        raise where.error("trace", f"{times.size} rows", f"2-{TRACE_MAX_ROWS} rows")
    lines = list(lines) if lines is not None else [k + 1 for k in range(times.size)]
    lo, hi = TRACE_TEMPERATURE_RANGE
    with np.errstate(invalid="ignore"):  # the first bad row, in the order rows are read
        bad = (~np.isfinite(times) | ~np.isfinite(temps) | (temps < lo) | (temps > hi)
               | np.concatenate([[False], ~(np.diff(times) > 0.0)]))
    first = np.flatnonzero(bad)
    for j in first[:1].tolist():
        for col, x in ((1, times[j]), (2, temps[j])):
            if not math.isfinite(x):
                raise where.error("trace", f"line {lines[j]}, column {col} "
                                  f"({'time' if col == 1 else 'temperature'}): {x}",
                                  "a finite number")
        if not lo <= temps[j] <= hi:
            shown = temps[j] - kelvin_offset(kunit)
            raise where.error("trace", f"line {lines[j]}, column 2 (temperature): {shown:g} "
                              f"{kunit}", f"{lo}-{hi} K (0-100 degC; name the unit in the "
                              "header, e.g. 'T (degC)', or give temperature_unit)")
        if j and not times[j] > times[j - 1]:
            raise where.error("trace", f"line {lines[j]}, column 1 (time): {times[j]:g} s "
                              f"after {times[j - 1]:g} s", "strictly increasing times")
    t = times - times[0]
    return Trace(tuple(map(float, t)), tuple(map(float, temps)), name)


def _trace_step(d: dict[str, Any], where: _Where) -> Trace:
    name = str(d.get("name") or "trace")[:MAX_QUANTITY_CHARS]
    if "csv" in d:
        try:
            return trace_from_csv(str(d["csv"]), d.get("time_unit"), d.get("temperature_unit"),
                                  name, where.index)
        except ParameterError:
            raise
    if "time" not in d or "temperature" not in d:
        raise where.error("trace", sorted(d), "'csv' text, or 'time' and 'temperature' lists")
    try:
        times = np.asarray(d["time"], dtype=float) * _time_scale(d.get("time_unit"),
                                                                 "trace.time_unit")
        kunit = _temperature_unit(d.get("temperature_unit"), "trace.temperature_unit")
        temps = np.asarray(d["temperature"], dtype=float) + kelvin_offset(kunit)
    except ParameterError as exc:
        raise where.error(exc.field, exc.value, exc.valid) from None
    except (TypeError, ValueError):
        raise where.error("trace", name, "lists of numbers 'time' and 'temperature'") from None
    if times.ndim != 1 or times.shape != temps.shape:
        raise where.error("trace", name, "'time' and 'temperature' lists of one length")
    return _trace_checked(times, temps, name, where, kunit=kunit)


# ----------------------------------------------------------------------------- parsing
_T = r"(?P<T>.+?)"
# a step's end: 'for D', 'until X', or 'for D or until X' (whichever comes first)
_ENDS = (r"(?:\s+for\s+(?P<dur>.+?)(?:\s+or\s+until\s+(?P<until>.+))?"
         r"|\s+until\s+(?P<until_only>.+))")
_REPEAT = re.compile(r"^(?:repeat\s+)?(?P<n>[-+]?\d+)\s*(?:x|×|\*|times)\s*:?\s*"
                     r"\((?P<body>.*)\)$", re.I)
REPEAT_MAX = 100
_PATTERNS = (
    ("ramp", re.compile(rf"^(?P<kind>heat|cool)\s+(?:up\s+|down\s+)?to\s+{_T}\s+at\s+"
                        r"(?P<rate>.+)$", re.I)),
    ("bath", re.compile(rf"^bath\s+at\s+{_T}\s+with\s+(?:a\s+)?time\s+constant\s+(?:of\s+)?"
                        rf"(?P<tc>.+?){_ENDS}?$", re.I)),
    ("hold", re.compile(rf"^(?P<kind>hold|rest)\s+at\s+{_T}{_ENDS}?$", re.I)),
    ("trace", re.compile(r"^trace\s+(?:from\s+)?(?P<path>.+)$", re.I)),
)
GRAMMAR = ("'Heat to 308 K at 5 K/min', 'Cool to 302 K at 2 K/min', 'Hold at 308 K for 2 min', "
           "'Hold at 308 K until 30 % released', 'Hold at 308 K for 10 min or until 30 % "
           "released', 'Rest at 302 K for 10 min', 'Bath at 308 K with a time constant of "
           "30 s', 'Trace from run.csv', '3 x (Heat to 308 K at 5 K/min; Hold at 308 K for "
           "2 min; Cool to 302 K at 5 K/min)', or a structured step {'step': 'heat'|'cool'|"
           "'hold'|'rest'|'bath'|'trace'|'repeat', ...}")


PATHS_REFUSED = ("the trace as data: {'step': 'trace', 'csv': '<CSV text>'} or 'time' and "
                 "'temperature' lists; file paths are refused here (the service never reads "
                 "a file a request names)")


@dataclass(frozen=True)
class Origin:
    """Where a protocol's step came from: item ``index`` of the steps as given, and in a
    repeat its place ``sub`` and repetition ``rep`` of ``times``."""

    index: int
    sub: int | None = None
    rep: int = 1
    times: int = 1

    def where(self, text: str) -> _Where:
        """The error namer of this step."""
        ctx = "" if self.sub is None else f" (repeat {self.rep} of {self.times})"
        return _Where(self.index, text, ctx, self.sub)


def _non_finite(value: Any) -> bool:
    """True when a structured step holds a NaN or an infinite number (at any depth)."""
    if isinstance(value, float):
        return not math.isfinite(value)
    if isinstance(value, dict):
        return any(_non_finite(v) for v in value.values())
    if isinstance(value, (list, tuple)):
        return any(_non_finite(v) for v in value)
    return False


def _repeat_of(value: Any, index: int) -> tuple[int, list[Any]] | None:
    """(times, steps) of a repeat item ('3 x (a; b; c)' or {'step': 'repeat', 'times': 3,
    'steps': [...]}), else None."""
    if isinstance(value, dict):
        if str(value.get("step", value.get("type", ""))).lower() != "repeat":
            return None
        where = _Where(index, str(value))
        extra = sorted(set(value) - {"step", "type", "times", "steps"})
        if extra:
            raise where.error(extra[0], value[extra[0]], "one of steps, times")
        n, body = value.get("times"), value.get("steps")
        if isinstance(body, (str, dict)):
            body = [body]
        if not isinstance(body, list):
            raise where.error("steps", body, "a list of 1 or more steps to repeat")
    elif isinstance(value, str):
        m = _REPEAT.match(" ".join(value.split()))
        if m is None:
            return None
        where = _Where(index, " ".join(value.split()))
        n = int(m.group("n"))
        body = [b.strip() for b in m.group("body").split(";")]
    else:
        return None
    if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= REPEAT_MAX:
        raise where.error("times", n, f"a whole number of repeats, 1-{REPEAT_MAX}")
    if not body or any(b == "" or b is None for b in body):
        raise where.error("steps", body, "1 or more steps separated by ';', none empty: "
                                         "'3 x (Heat to 308 K at 5 K/min; Hold at 308 K for "
                                         "2 min; Cool to 302 K at 5 K/min)'")
    return n, body


def expand_steps(raw: Sequence[Any], files: bool = True) -> tuple[list[Step], list[Origin]]:
    """The steps as given, each repeat written out ('3 x (a; b)' -> a, b, a, b, a, b), with
    where each came from; a repeated step must end on a duration ('for 2 min', optionally
    'or until ...': a bare until-condition would be met at once from the second repeat on)."""
    steps: list[Step] = []
    origins: list[Origin] = []
    for i, value in enumerate(raw):
        rep = _repeat_of(value, i)
        if rep is None:
            steps.append(parse_step(value, i, files))
            origins.append(Origin(i))
            continue
        n, body = rep
        inner = []
        for k, b in enumerate(body):
            if _repeat_of(b, i) is not None:
                raise _Where(i, str(b), sub=k).error("", b, "a step (no repeat in a repeat)")
            st = parse_step(b, i, files, sub=k)
            if isinstance(st, (Hold, Bath)) and st.duration is None:
                raise Origin(i, k, 1, n).where(st.text).error(
                    "for", None, "a duration ('for 2 min', optionally 'or until 30 % "
                                 "released') in a repeated step: a bare until-condition is "
                                 "met at once from the second repeat on")
            inner.append(st)
        for r in range(n):
            steps += inner
            origins += [Origin(i, k, r + 1, n) for k in range(len(inner))]
    return steps, origins


def parse_step(value: Any, index: int = 0, files: bool = True,
               sub: int | None = None) -> Step:
    """One step from its text, a structured dict or a step object; ``files`` allows
    'Trace from <path>' to read a CSV file (Python and the CLI; HTTP sends the CSV text);
    ``sub``: its place in the repeat of step ``index`` (errors name it)."""
    if isinstance(value, (Ramp, Hold, Bath, Trace)):
        return value
    if isinstance(value, dict):
        return _from_dict(value, index, sub)
    if not isinstance(value, str):
        raise ParameterError(f"protocol[{index}]" + ("" if sub is None else f".steps[{sub}]"),
                             value, GRAMMAR)
    text = " ".join(value.split())
    where = _Where(index, text, sub=sub)
    for kind, pat in _PATTERNS:
        m = pat.match(text)
        if not m:
            continue
        g = m.groupdict()
        if kind == "ramp":
            rate, unit = where.rate(g["rate"])
            return Ramp(g["kind"].lower(), where.temperature(g["T"], "to"), rate, unit)
        until = g.get("until") or g.get("until_only")
        if kind == "hold":
            return Hold(g["kind"].lower(), where.temperature(g["T"], "at"),
                        where.span(g["dur"], "for") if g.get("dur") else None,
                        _until(until, where) if until else None)
        if kind == "bath":
            return Bath(where.temperature(g["T"], "at"),
                        where.span(g["tc"], "time_constant", *TIME_CONSTANT_RANGE_S),
                        where.span(g["dur"], "for") if g.get("dur") else None,
                        _until(until, where) if until else None)
        path = g["path"].strip()
        if not files:
            raise where.error("trace", path[:MAX_QUANTITY_CHARS], PATHS_REFUSED)
        try:
            with open(path, encoding="utf-8") as fh:
                body = fh.read()
        except OSError as exc:
            raise where.error("trace", path, f"a readable CSV file ({exc.strerror})") from None
        return trace_from_csv(body, name=path, index=index)
    raise where.error("", value, GRAMMAR)


def _from_dict(d: dict[str, Any], index: int, sub: int | None = None) -> Step:
    kind = str(d.get("step", d.get("type", ""))).lower()
    where = _Where(index, str(d), sub=sub)
    allowed = {"heat": {"to", "rate"}, "cool": {"to", "rate"},
               "hold": {"at", "for", "until"}, "rest": {"at", "for", "until"},
               "bath": {"at", "time_constant", "for", "until"},
               "trace": {"name", "csv", "time", "temperature", "time_unit",
                         "temperature_unit"}}
    if kind not in allowed:
        raise where.error("step", d.get("step"), "'heat', 'cool', 'hold', 'rest', 'bath', "
                                                 "'trace'" + (" or 'repeat'" if sub is None
                                                              else " (no repeat in a repeat)"))
    extra = sorted(set(d) - allowed[kind] - {"step", "type"})
    if extra:
        raise where.error(extra[0], d[extra[0]], "one of " + ", ".join(sorted(allowed[kind])))
    for need in {"heat": ("to", "rate"), "cool": ("to", "rate"), "hold": ("at",),
                 "rest": ("at",), "bath": ("at", "time_constant"), "trace": ()}[kind]:
        if d.get(need) is None:
            raise where.error(need, None, "required for a " + kind + " step")
    if kind in ("heat", "cool"):
        rate, unit = where.rate(d["rate"])
        return Ramp(kind, where.temperature(d["to"], "to"), rate, unit)
    end = {"duration": where.span(d["for"], "for") if d.get("for") is not None else None,
           "until": _until(d["until"], where) if d.get("until") is not None else None}
    if kind in ("hold", "rest"):
        return Hold(kind, where.temperature(d["at"], "at"), **end)
    if kind == "bath":
        return Bath(where.temperature(d["at"], "at"),
                    where.span(d["time_constant"], "time_constant", *TIME_CONSTANT_RANGE_S),
                    **end)
    return _trace_step(d, where)


# ----------------------------------------------------------------------------- protocol
@dataclass(frozen=True)
class Piece:
    """One step of the program in tau: the temperature from ``t0`` to ``t1`` (K) over
    ``duration`` tau, by ``shape`` 'hold' (at t1), 'ramp' (linear), 'bath' (lag with
    ``time_constant`` tau) or 'trace' (``times`` in tau from the piece's start, ``temps``)."""

    shape: str
    t0: float
    t1: float
    duration: float | None
    time_constant: float | None = None
    times: tuple[float, ...] = ()
    temps: tuple[float, ...] = ()
    until: Until | None = None
    step: int = 0

    def temperature(self, s: np.ndarray) -> np.ndarray:
        """T at times ``s`` (tau from the piece's start)."""
        s = np.asarray(s, dtype=float)
        if self.shape == "hold":
            return np.full(s.shape, self.t1)
        if self.shape == "ramp":
            d = self.duration or 0.0
            return self.t0 + (self.t1 - self.t0) * np.clip(s / d if d > 0 else 1.0, 0.0, 1.0)
        if self.shape == "bath":
            return self.t1 + (self.t0 - self.t1) * np.exp(-s / self.time_constant)
        return np.interp(s, self.times, self.temps)


@dataclass(frozen=True)
class Protocol:
    """A heating protocol from ``t_start`` (K): typed steps, validated on construction.  ``steps``
    are step texts, structured dicts or step objects; a Heat must go up and a Cool down from the
    temperature before it; a bare Hold or Bath (no ``for`` / ``until``) may only be the last.
    After the last step the bead holds at the last temperature."""

    t_start: float
    steps: tuple[Step, ...]
    files: bool = field(default=True, compare=False, repr=False)

    def __post_init__(self) -> None:
        t0 = kelvin(self.t_start, "t_start")
        if not T_MIN <= t0 <= T_MAX:
            raise ParameterError("t_start", self.t_start, f"{T_MIN}-{T_MAX} K")
        object.__setattr__(self, "t_start", t0)
        raw = [self.steps] if isinstance(self.steps, (str, dict)) else list(self.steps or ())
        if not raw:
            raise ParameterError("protocol", self.steps, "at least one step: " + GRAMMAR)
        if len(raw) > 1000:
            raise ParameterError("protocol", f"{len(raw)} steps", "1-1000 steps")
        for i, value in enumerate(raw):  # non-strict JSON first, wherever it sits (a 422
            if _non_finite(value):       # names the step that holds it)
                raise ParameterError(f"protocol[{i}]", "NaN or Infinity", "finite numbers")
        expanded, origins = expand_steps(raw, self.files)
        if len(expanded) > 1000:
            raise ParameterError("protocol", f"{len(expanded)} steps with the repeats written "
                                 "out", "1-1000 steps")
        steps = tuple(expanded)
        cur = t0
        for i, st in enumerate(steps):
            where = origins[i].where(st.text)
            if isinstance(st, Ramp):
                if st.kind == "heat" and not st.to_k > cur:
                    raise where.error("to", st.to_k, f"above {cur:g} K (a heat goes up from "
                                                     "the temperature before it)")
                if st.kind == "cool" and not st.to_k < cur:
                    raise where.error("to", st.to_k, f"below {cur:g} K (a cool goes down from "
                                                     "the temperature before it)")
            if isinstance(st, (Hold, Bath)) and st.duration is None and st.until is None \
                    and i < len(steps) - 1:
                raise where.error("for", None, "a duration ('for 2 min') or a condition "
                                               "('until 30 % released'), except in the last step")
            cur = _end_temperature(st, cur)
        object.__setattr__(self, "steps", steps)

    @classmethod
    def parse(cls, t_start: Any, steps: Any, files: bool = True) -> Protocol:
        """A protocol from a start temperature and steps (texts, dicts or objects)."""
        if isinstance(steps, Protocol):
            return steps
        return cls(t_start, steps, files)

    @property
    def texts(self) -> list[str]:
        """The steps as grammar strings."""
        return [s.text for s in self.steps]

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form: the start temperature and the structured steps."""
        return {"t_start": self.t_start, "steps": [s.to_dict() for s in self.steps],
                "text": self.texts}

    @property
    def final_temperature(self) -> float:
        """The temperature the bead holds at after the last step."""
        cur = self.t_start
        for st in self.steps:
            cur = _end_temperature(st, cur)
        return cur

    @property
    def hottest(self) -> float:
        """The highest temperature the protocol reaches (its T_end, tau's reference)."""
        cur, top = self.t_start, self.t_start
        for st in self.steps:
            top = max(top, max(st.temperatures_k) if isinstance(st, Trace) else
                      st.to_k if isinstance(st, Ramp) else st.at_k)
            cur = _end_temperature(st, cur)
        return top

    @property
    def until_steps(self) -> list[int]:
        """Indices of the steps that end on a condition."""
        return [i for i, s in enumerate(self.steps) if getattr(s, "until", None) is not None]

    def with_durations(self, durations: dict[int, float]) -> Protocol:
        """This protocol with until-steps ``i`` given fixed durations (tau) instead."""
        steps = list(self.steps)
        for i, d in durations.items():
            steps[i] = replace(steps[i], duration=Span(float(d), "tau"), until=None)
        return Protocol(self.t_start, tuple(steps))

    def program(self, tau_s: float | None) -> list[Piece]:
        """The steps in tau (seconds over ``tau_s``), each from the temperature the step
        before ends at; an until-step's duration is None (found by the planner)."""
        out, cur = [], self.t_start
        for i, st in enumerate(self.steps):
            end = _end_temperature(st, cur)
            if isinstance(st, Ramp):
                out.append(Piece("ramp", cur, st.to_k, abs(st.to_k - cur) / st.rate_tau(tau_s),
                                 step=i))
            elif isinstance(st, Hold):
                out.append(Piece("hold", cur, st.at_k, None if st.duration is None else
                                 st.duration.tau(tau_s), until=st.until, step=i))
            elif isinstance(st, Bath):
                out.append(Piece("bath", cur, st.at_k, None if st.duration is None else
                                 st.duration.tau(tau_s), st.time_constant.tau(tau_s),
                                 until=st.until, step=i))
            else:
                times = tuple(Span(t).tau(tau_s) for t in st.times_s)
                out.append(Piece("trace", cur, end, times[-1], times=times,
                                 temps=st.temperatures_k, step=i))
            cur = end
        return out

    def windows(self, tau_s: float | None) -> list[tuple[float, float | None]]:
        """The heating windows in tau: spans (start, end) in which the temperature is above
        ``t_start`` (end None: up to an until-step or for ever; after the last step)."""
        out: list[tuple[float, float | None]] = []
        t: float | None = 0.0
        hot_since: float | None = None
        for p in self.program(tau_s):
            top = p.t1 if p.shape == "hold" else max(p.t1, p.t0, *(p.temps or (p.t1,)))
            hot = top > self.t_start
            if hot and hot_since is None and t is not None:
                hot_since = t
            if not hot and hot_since is not None:
                out.append((hot_since, t))
                hot_since = None
            t = None if t is None or p.duration is None else t + p.duration
        if hot_since is not None:
            out.append((hot_since, None))
        return out


def check_physical(protocol: Protocol, tau_s: float | None) -> None:
    """Each step's duration given in tau, bounded by its physical value once tau is known
    (within DURATION_MAX_S, as one given in seconds; issue 40, R8), after the solver's own
    rules (``dosing.heating.program.check_program``, which calls this last)."""
    if tau_s is None:
        return
    for i, st in enumerate(protocol.steps):
        where = _Where(i, st.text)
        for name in ("duration", "time_constant"):
            span = getattr(st, name, None)
            field = "for" if name == "duration" else name
            if isinstance(span, Span) and span.unit == "tau":
                secs = span.value * tau_s
                if not 0.0 < secs <= DURATION_MAX_S:
                    raise where.error(field, f"{span.value:g} tau = {secs:.3g} s (tau = "
                                      f"{tau_s:.3g} s)",
                                      f"0 s < {field} <= {DURATION_MAX_S:g} s")


def _end_temperature(st: Step, cur: float) -> float:
    if isinstance(st, Ramp):
        return st.to_k
    if isinstance(st, Hold):
        return st.at_k
    if isinstance(st, Trace):
        return st.temperatures_k[-1]
    if st.duration is None or st.duration.unit != st.time_constant.unit:
        return st.at_k  # lasts (or ends on a condition): the end is found by the run
    return st.at_k + (cur - st.at_k) * math.exp(-st.duration.value / st.time_constant.value)


def reference_text(t_ref: float) -> str:
    """How the protocol's seconds become tau (stated in every answer)."""
    return (f"seconds -> tau through one timescale, tau at the protocol's hottest temperature "
            f"T_ref = {t_ref:g} K (eq. timescale)")
