"""Plain data as strict JSON: the one cleaner of results, diagnostics and answers."""

from __future__ import annotations

import math
from typing import Any

import numpy as np


def json_safe(obj: Any, max_array: int | None = None) -> Any:
    """A JSON-ready copy of ``obj``: numpy arrays and scalars become Python lists and
    numbers, non-finite floats None, mapping keys strings, unknown objects their repr.
    ``max_array``: an array with more elements is summarised as ``'array(shape)'``."""
    if isinstance(obj, dict):
        return {str(k): json_safe(v, max_array) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v, max_array) for v in obj]
    if isinstance(obj, np.ndarray):
        if max_array is not None and obj.size > max_array:
            return f"array{obj.shape}"
        return json_safe(obj.tolist(), max_array)
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if isinstance(obj, (str, int, float, bool)) or obj is None:
        return obj
    return repr(obj)
