"""Crossing roots of sampled curves (solver/crossing.py), checked directly."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from solver.crossing import first_fall, hermite_root


def test_first_fall_is_exact_on_piecewise_linear_data() -> None:
    t = np.array([0.0, 1.0, 2.0, 3.0])
    v = np.array([3.0, 2.0, 0.0, -1.0])
    assert first_fall(t, v, 1.0) == pytest.approx(1.5, abs=1e-15)
    assert first_fall(t, v, 2.0) == 1.0            # on a sample
    assert first_fall(t, v, 5.0) == 0.0            # already below at the start
    assert math.isnan(first_fall(t, v, -2.0))      # never


def test_first_fall_takes_the_first_of_several_crossings() -> None:
    t = np.arange(5.0)
    v = np.array([1.0, 0.0, 1.0, 0.0, 1.0])
    assert first_fall(t, v, 0.5) == pytest.approx(0.5)


@given(st.floats(0.05, 0.95), st.floats(-3, 3), st.floats(-3, 3))
def test_hermite_root_recovers_a_cubic_crossing(s0: float, c2: float, c3: float) -> None:
    """For a(t) = (t - t*) + c2 (t - t*)^2 + c3 (t - t*)^3 monotone on [0, 1], the Hermite
    interpolant through its end values and slopes is a itself: the root is t*."""
    t0, t1, ts = 0.0, 1.0, s0

    def a(t: float) -> float:
        x = t - ts
        return x + c2 * x * x + c3 * x ** 3

    def da(t: float) -> float:
        x = t - ts
        return 1 + 2 * c2 * x + 3 * c3 * x * x

    grid = np.linspace(t0, t1, 201)
    if min(da(x) for x in grid) <= 0.05:  # keep a monotone, so the root is unique
        return
    root = hermite_root(t0, t1, a(t0), a(t1), da(t0), da(t1), 0.0)
    assert root == pytest.approx(ts, abs=1e-12)


def test_hermite_root_on_a_falling_radius() -> None:
    """A falling curve (the dose case): a(t) = 2 - t on [1, 1.5] reaches 0.8 at t = 1.2."""
    assert hermite_root(1.0, 1.5, 1.0, 0.5, -1.0, -1.0, 0.8) == pytest.approx(1.2, abs=1e-12)
