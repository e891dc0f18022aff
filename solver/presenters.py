"""Presenters of solver records (xarray, pandas, HTML), registered by the layer above.

Tables, netCDF and notebook views carry units, provenance and the planner's vocabulary, so
they live in ``dosing.export`` / ``dosing.tables``; the solver's records (``FullResult``,
``FitResult``) offer ``to_xarray()``, ``to_dataframe()`` and ``_repr_html_()`` through this
registry, which those modules fill when imported (the accessor pattern of pandas and
xarray).  ``solver`` imports nothing above it: a record asked for a table before the export
layer is loaded says how to load it.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Any

# name -> a callable, or "module:attribute" imported on first use (so registering costs
# nothing: pandas and xarray load only when a table is asked for)
_REGISTRY: dict[str, Callable[..., Any] | str] = {}


def register(**presenters: Callable[..., Any] | str) -> None:
    """Make each named presenter available to the solver's records."""
    _REGISTRY.update(presenters)


def _resolve(name: str) -> Callable[..., Any] | None:
    fn = _REGISTRY.get(name)
    if isinstance(fn, str):
        module, _, attr = fn.partition(":")
        fn = _REGISTRY[name] = getattr(importlib.import_module(module), attr)
    return fn


def presenter(name: str) -> Callable[..., Any]:
    """The registered presenter ``name``; ImportError naming what to import when absent."""
    fn = _resolve(name)
    if fn is None:
        raise ImportError(f"{name} is provided by the planner's export layer: `import "
                          "dosing` (or `import thermogel`) first")
    return fn


def html_or_none(name: str, obj: Any) -> str | None:
    """A notebook's HTML view, or None (the plain repr) when no presenter is loaded."""
    fn = _resolve(name)
    return None if fn is None else fn(obj)
