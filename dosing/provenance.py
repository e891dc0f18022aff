"""What made an answer: the resolved request with its units, and the code's version.

Every JSON answer and export carries ``request`` (as resolved: defaults filled, units in
``request["units"]``) and ``version`` (:func:`version_info`: package, ``git describe``, the
solver's code digest that keys the validation cache).  A leaf: it imports nothing of the
planner at import time (docs/results.md)."""

from __future__ import annotations

import subprocess
from collections.abc import Mapping
from functools import lru_cache
from pathlib import Path
from typing import Any

# the short unit of each kind of physical field (dosing.quantity.UNITS, as written in docs)
SHORT_UNITS: dict[str, str] = {
    "temperature": "K", "temperature_rate": "K/s", "time": "s", "length": "um",
    "mesh_length": "nm", "volume": "uL", "mass": "ug", "concentration": "ug/uL",
    "viscosity": "Pa s", "permeability": "m^2", "molecular_volume": "m^3",
    "diffusivity": "cm^2/s",
}


def unit_of(name: str) -> str | None:
    """The unit a request field named ``name`` is given in ('t_start' -> 'K',
    'dry_radius_um' -> 'um'), or None for a dimensionless or non-physical field."""
    from .quantity import field_kind

    kind = field_kind(name)
    return None if kind is None else SHORT_UNITS.get(kind)


def _units(value: Any, prefix: str, out: dict[str, str]) -> None:
    if isinstance(value, Mapping):
        for k, v in value.items():
            key = f"{prefix}{k}"
            if v is not None and not isinstance(v, (Mapping, list)):
                u = unit_of(str(k))
                if u is not None:
                    out[key] = u
            _units(v, key + ".", out)
    elif isinstance(value, list):
        for v in value:
            if isinstance(v, Mapping):
                _units(v, prefix.rstrip(".") + "[]." if prefix else "[].", out)


def resolved(values: Mapping[str, Any]) -> dict[str, Any]:
    """``values`` (a request with its defaults filled) with ``units``: the unit of every
    physical field given (nested fields by dotted path), e.g. ``{"t_start": "K"}``."""
    out = {k: v for k, v in values.items() if k != "units"}
    units: dict[str, str] = {}
    _units(out, "", units)
    out["units"] = units
    return out


@lru_cache(maxsize=1)
def package_version() -> str:
    """thermogel's installed version, or 'unknown' when run from an uninstalled tree."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("thermogel")
    except PackageNotFoundError:
        return "unknown"


@lru_cache(maxsize=1)
def code_version() -> str:
    """thermogel's package version, plus ``git describe --always --dirty`` of the checkout
    the code runs from when there is one (e.g. '0.1.0+981cd97-dirty')."""
    v = package_version()
    try:
        here = Path(__file__).resolve().parent
        git = subprocess.run(["git", "describe", "--always", "--dirty", "--tags"], cwd=here,
                             capture_output=True, text=True, timeout=5, check=False)
        if git.returncode == 0 and git.stdout.strip():
            v += "+" + git.stdout.strip()
    except (OSError, subprocess.SubprocessError):
        pass
    return v


@lru_cache(maxsize=1)
def version_info() -> dict[str, str]:
    """``{"package", "code", "solver"}``: the package version, the code version (package
    + git describe of a checkout) and the digest of the full solver's sources (the
    validation cache's key, dosing.runs.scenario.code_version)."""
    from .runs.scenario import code_version as solver_digest

    return {"package": package_version(), "code": code_version(), "solver": solver_digest()}


def stamp(answer: dict[str, Any], request: Mapping[str, Any] | None) -> dict[str, Any]:
    """``answer`` with ``request`` (resolved, with units) and ``version`` added; an answer
    that carries its own resolved request (dosing.question's) keeps it, its units added."""
    own = answer.get("request")
    if isinstance(own, Mapping):
        answer["request"] = resolved(own)
    elif "request" not in answer:
        answer["request"] = None if request is None else resolved(request)
    if "version" not in answer:
        answer["version"] = version_info()
    return answer
