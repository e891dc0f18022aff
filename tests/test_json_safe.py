"""The one JSON cleaner (solver/json_safe.py)."""

from __future__ import annotations

import json
import math

import numpy as np

from solver.json_safe import json_safe


def test_strict_json_from_numpy_and_non_finite_values() -> None:
    obj = {1: np.float64(math.nan), "a": np.arange(3), "b": (np.int64(2), np.bool_(True)),
           "c": [math.inf, -math.inf, 1.5], "d": object}
    out = json_safe(obj)
    assert json.loads(json.dumps(out, allow_nan=False)) == out
    assert out["1"] is None and out["a"] == [0, 1, 2] and out["b"] == [2, True]
    assert out["c"] == [None, None, 1.5] and out["d"].startswith("<class")


def test_large_arrays_are_summarised_on_request() -> None:
    assert json_safe(np.zeros((10, 10)), max_array=64) == "array(10, 10)"
    assert json_safe(np.zeros(4), max_array=64) == [0.0] * 4
