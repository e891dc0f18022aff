"""Crossing times of sampled curves (shared by full-solver results and stored runs)."""

from __future__ import annotations

import math

import numpy as np


def first_fall(t: np.ndarray, values: np.ndarray, level: float) -> float:
    """First time ``values`` (sampled at ``t``) falls to ``level`` (linear in between), or
    NaN if it never does."""
    below = np.nonzero(values <= level)[0]
    if below.size == 0:
        return math.nan
    j = int(below[0])
    if j == 0 or values[j - 1] == values[j]:
        return float(t[j])
    return float(t[j - 1] + (values[j - 1] - level) / (values[j - 1] - values[j])
                 * (t[j] - t[j - 1]))
