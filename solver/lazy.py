"""Names of a package resolved on first use (PEP 562), written once for every package.

``__getattr__ = lazy_names(__name__, {"simulate": ".run", ...}, globals())`` in a package's
``__init__`` imports the module that defines a name only when the name is first read, so
importing the package pays for nothing it does not use (docs/speed.md).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Any


def lazy_names(package: str, where: dict[str, str],
               namespace: dict[str, Any]) -> Callable[[str], Any]:
    """A module ``__getattr__``: ``name`` -> ``getattr(import_module(where[name]), name)``,
    kept in ``namespace`` after the first use."""

    def __getattr__(name: str) -> Any:
        module = where.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module, package), name)
        namespace[name] = value
        return value

    return __getattr__
