"""Physical quantities at the edges: one unit table, parsed with pint.

Every way in takes a plain number in the field's documented unit, a string with a unit ("50
um", "29 degC", "5 K/min") or a pint ``Quantity``; nothing else converts units by hand.  pint
is imported on first use only (about 0.3 s), so plain numbers pay nothing for it
(docs/speed.md sec. 1)."""

from __future__ import annotations

import math
import re
from functools import lru_cache
from typing import Any

from solver.errors import ParameterError

# The documented unit of each kind of field (the plain-number unit of every way in).
UNITS: dict[str, str] = {
    "temperature": "kelvin",
    "temperature_rate": "kelvin / second",
    "time": "second",
    "length": "micrometer",
    "mesh_length": "nanometer",
    "volume": "microliter",
    "mass": "microgram",
    "concentration": "microgram / microliter",
    "viscosity": "pascal * second",
    "permeability": "meter ** 2",
    "molecular_volume": "meter ** 3",
    "diffusivity": "centimeter ** 2 / second",
}

# Short spellings labs write, in pint's grammar (pint reads "um" as micrometre already).
_ALIASES = (
    ("µ", "u"), ("μ", "u"), ("°C", "degC"), ("ºC", "degC"), ("°F", "degF"),
    ("°K", "K"), ("℃", "degC"),
)


@lru_cache(maxsize=1)
def registry() -> Any:
    """The one pint UnitRegistry (offset units such as degC are allowed in products)."""
    import pint

    ureg = pint.UnitRegistry(autoconvert_offset_to_baseunit=True)
    ureg.formatter.default_format = "~P"
    return ureg


def number(value: Any) -> float:
    """``value`` as a float; NaN for a bool or what ``float`` refuses, so that one range
    check refuses it naming the field."""
    if isinstance(value, bool):
        return math.nan
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


MAX_TEXT = 100  # characters of one quantity string
# pint evaluates powers exactly: "9**9**9 s" would never finish.  A unit may carry a small
# power ("m^2", "cm**2/s"); a number or a bracket raised to a power, a power of more than
# one digit or a chained power is refused before pint sees it.
_BAD_POWER = re.compile(r"(?:[\d.)\]]\s*(?:\*\*|\^))|(?:(?:\*\*|\^)\s*[-+]?\s*"
                        r"(?:\d\s*\d|\d\s*(?:\*\*|\^)|[^\d\s+-]))")


def _normalise(text: str) -> str:
    for old, new in _ALIASES:
        text = text.replace(old, new)
    return text.strip()


def _safe(text: str, value: Any, field: str) -> str:
    if len(text) > MAX_TEXT:
        raise ParameterError(field, value[:40] + "...", f"at most {MAX_TEXT} characters")
    if _BAD_POWER.search(text):
        raise ParameterError(field, value, "a number and a unit; powers only on units, "
                             "of one digit (e.g. 'cm^2/s')")
    return text


def _is_quantity(value: Any) -> bool:
    return hasattr(value, "magnitude") and hasattr(value, "units") and hasattr(value, "to")


def parse(value: Any, field: str) -> Any:
    """A pint Quantity from a string or Quantity (a plain number stays a number)."""
    if _is_quantity(value):
        return value
    if isinstance(value, str):
        ureg = registry()
        text = _safe(_normalise(value), value, field)
        if not text:
            raise ParameterError(field, value, "a number or a quantity with a unit")
        try:
            return ureg.Quantity(text)
        except Exception:  # pint raises many kinds (undefined unit, syntax, ...)
            raise ParameterError(field, value, "a number or a quantity with a unit, e.g. "
                                 "'50 um', '29 degC', '10 min'") from None
    return value


def to_unit(value: Any, kind: str, field: str) -> float:
    """``value`` as a float in the documented unit of ``kind`` (see ``UNITS``): plain numbers are
    taken as in that unit, strings and pint Quantities converted.  A wrong dimension ("50 K" for a
    length) or a non-finite value raises a ``ParameterError`` naming ``field``."""
    unit = UNITS[kind]
    q = parse(value, field)
    if _is_quantity(q):
        if not dict(q.unit_items()):  # a bare number ("308") is in the documented unit
            out = float(q.magnitude)
        elif q.dimensionless:  # "500 percent", "10 radian": a unit, of no dimension
            raise ParameterError(field, str(value), f"a quantity of dimension {unit} (got "
                                 f"'{q.units}', which has none)")
        else:
            try:
                out = float(q.to(unit).magnitude)
            except Exception:
                raise ParameterError(field, str(value),
                                     f"a quantity of dimension {unit} "
                                     f"(got {q.dimensionality})") from None
    elif isinstance(value, bool):
        raise ParameterError(field, value, f"a number in {unit} or a quantity with a unit")
    else:
        try:
            out = float(q)
        except (TypeError, ValueError):
            raise ParameterError(field, value,
                                 f"a number in {unit} or a quantity with a unit") from None
    if not math.isfinite(out):
        raise ParameterError(field, value, "a finite value")
    return out


def kelvin(value: Any, field: str = "temperature") -> float:
    """A temperature in K from K, degC ("29 degC") or a Quantity."""
    return to_unit(value, "temperature", field)


def seconds(value: Any, field: str = "time") -> float:
    """A duration in s from s, min, h ("10 min") or a Quantity."""
    return to_unit(value, "time", field)


def micrometres(value: Any, field: str = "length") -> float:
    """A length in um from um, mm, nm ("50 um") or a Quantity."""
    return to_unit(value, "length", field)


def kelvin_offset(unit: str) -> float:
    """What to add to a temperature in ``unit`` ('K' or 'degC') to get kelvin (affine
    temperature units: the one place this offset is known)."""
    return to_unit(f"0 {unit}", "temperature", "temperature_unit")


# A field's kind from its name: the request fields name their unit (t_start, dry_radius_um,
# viscosity_pa_s, ...); suffixes are tried in order (longest first where they overlap).
_FIELD_NAMES: dict[str, str] = {
    "t_start": "temperature", "t_end": "temperature", "temperature": "temperature",
    "t_min": "temperature", "t_max": "temperature", "temperature_k": "temperature",
}
_FIELD_SUFFIXES: tuple[tuple[str, str], ...] = (
    ("_ug_per_ul", "concentration"), ("_cm2_s", "diffusivity"), ("_pa_s", "viscosity"),
    ("_k_per_s", "temperature_rate"), ("_um", "length"), ("_nm", "mesh_length"),
    ("_ul", "volume"), ("_ug", "mass"), ("_m2", "permeability"), ("_m3", "molecular_volume"),
    ("_seconds", "time"), ("_s", "time"),
)


@lru_cache(maxsize=512)  # a request's every field, every request: names are few
def field_kind(name: str) -> str | None:
    """The kind of physical quantity (a key of ``UNITS``) a request field named ``name``
    holds, from its name ('dry_radius_um' -> 'length'), or None for other fields."""
    key = name.lower()
    if key in _FIELD_NAMES:
        return _FIELD_NAMES[key]
    for suffix, kind in _FIELD_SUFFIXES:
        if key.endswith(suffix):
            return kind
    return None


def _edge_one(value: Any, kind: str, field: str) -> Any:
    if not (isinstance(value, str) or _is_quantity(value)):
        return value
    try:
        q = parse(value, field)
    except ParameterError:
        return value  # not a quantity ('water', a typo): the field's own check answers
    if _is_quantity(q) and q.dimensionless:
        return value  # a bare number in a string stays a string (strict models refuse it)
    return to_unit(q, kind, field)


def from_edge(field: str, value: Any) -> Any:
    """A request value with its unit converted to the field's documented unit (a float),
    when the field is physical (:func:`field_kind`) and the value a string with a unit or
    a pint Quantity (lists element-wise); anything else is returned unchanged for the
    field's own validation.  A wrong dimension ("50 K" for a radius) raises a
    ``ParameterError`` naming the field."""
    kind = field_kind(field)
    if kind is None:
        return value
    if isinstance(value, (list, tuple)):
        return type(value)(_edge_one(v, kind, f"{field}[{i}]") for i, v in enumerate(value))
    return _edge_one(value, kind, field)
