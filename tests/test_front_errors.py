"""Where the front model applies, and clear errors (never NaN) where it does not."""

import math

import pytest

from solver import ANB, HHT
from solver.errors import NotApplicableError, ParameterError
from solver.front import front_applicability, front_trajectory
from solver.front import levels as levels_module


@pytest.mark.parametrize(
    ("gel", "t0", "t1", "word"),
    [
        (ANB, 308, 302, "does not shrink"),   # swelling
        (HHT, 308, 304, "does not shrink"),
        (HHT, 304, 307.6, "smooth"),          # T_end short of the coexistence region
        (ANB, 302, 303, "smooth"),            # T_end below the fold: no transition
        (ANB, 302, 312, "spinodal"),
        (ANB, 302, 302, "does not shrink"),   # no jump
    ],
)
def test_not_applicable_cases(gel, t0: float, t1: float, word: str) -> None:
    ok, reason = front_applicability(gel, t0, t1)
    assert not ok and word in reason
    with pytest.raises(NotApplicableError, match=word):
        front_trajectory(gel, t0, t1)


def test_front_and_delayed_front_apply() -> None:
    for gel, t0, t1 in ((ANB, 302, 308), (HHT, 304, 308)):
        ok, reason = front_applicability(gel, t0, t1)
        assert ok and "coexistence" in reason
    ok, reason = front_applicability(ANB, 302, 306)
    assert ok and "approximate" in reason
    res = front_trajectory(ANB, 302, 306)
    assert res.diagnostics["behaviour"] == "delayed_front"


def test_shrunken_level_not_below_core(monkeypatch: pytest.MonkeyPatch) -> None:
    levels_module._assess_cached.cache_clear()
    monkeypatch.setattr(levels_module, "shrunken_level", lambda gel, t: 0.99)
    try:
        ok, reason = front_applicability(ANB, 302, 308)
        assert not ok and "not below" in reason
    finally:
        levels_module._assess_cached.cache_clear()


def test_bad_temperature_is_a_parameter_error() -> None:
    with pytest.raises(ParameterError, match="t_end"):
        front_trajectory(ANB, 302, 400)


def test_dose_beyond_reach() -> None:
    res = front_trajectory(ANB, 302, 308)
    lo, hi = res.radius_range
    for a in (1.05, 2.5, float("nan")):
        with pytest.raises(ValueError, match=f"{lo:.6g} <= a <= {hi:.6g}"):
            res.time_to_radius(a)
    with pytest.raises(ParameterError, match="target_radius"):
        front_trajectory(ANB, 302, 308, target_radius=1.0)
    short = front_trajectory(ANB, 302, 308, until=0.05)
    with pytest.raises(ValueError, match="radius"):
        short.time_to_radius(1.5)  # reached only after t = 0.05
    with pytest.raises(ParameterError, match="t"):
        short.state_at(0.06)


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"until": 0.0}, "until"),
        ({"until": -1.0}, "until"),
        ({"until": 0.005, "start": (0.01, 2.0, 1.8)}, "until"),
        ({"every": 0.0}, "every"),
        ({"every": 1e-9}, "every"),
        ({"n": 1}, "n"),
        ({"start": (0.01, 2.5, 1.8)}, "start.a"),       # larger than the initial radius
        ({"start": (0.01, 1.05, 0.5)}, "start.a"),      # past the centre
        ({"start": (-1.0, 2.0, 1.8)}, "start.t0"),
        ({"start": (0.01, 2.0)}, "start"),
        ({"start": (0.01, 2.0, 2.1), "conservative": False}, "start.front"),
    ],
)
def test_invalid_inputs(kwargs: dict, field: str) -> None:
    with pytest.raises(ParameterError, match=field):
        front_trajectory(ANB, 302, 308, **kwargs)


def test_no_nan_anywhere() -> None:
    res = front_trajectory(HHT, 304, 308, every=0.01)
    d = res.to_json_dict()
    for key in ("t", "radius", "front"):
        assert all(math.isfinite(v) for v in d[key])
    assert d["flux"][0] is None and all(math.isfinite(v) for v in d["flux"][1:])


def test_correction_is_refused_with_the_reason() -> None:
    with pytest.raises(ParameterError, match="not kept"):
        front_trajectory(ANB, 302, 308, correction=True)
