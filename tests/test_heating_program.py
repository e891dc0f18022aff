"""Temperature programs (solver/heating.py): validation naming the step and field, the
compiled T(t) and dT/dt, and the mobility factor's size (docs/heating.md)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from solver.errors import ParameterError
from solver.heating import (
    UNTIL_LIMIT,
    Bath,
    Hold,
    Program,
    Radius,
    Ramp,
    Released,
    Trace,
    mobility_factor,
    temperature_rate,
)


def test_compiled_program_evaluates_every_kind_of_step() -> None:
    prog = Program((Ramp(308.0, 60.0), Hold(308.0, 0.2), Bath(302.0, 0.05, duration=0.3),
                    Trace((0.0, 0.1, 0.3), (303.0, 305.0, 304.0))))
    t = np.array([0.0, 0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.55, 0.65, 0.8, 0.9, 5.0])
    got = prog.temperature(302.0, t)
    bath = 302.0 + 6.0 * np.exp(-(t[5:8] - 0.3) / 0.05)
    want = [302.0, 305.0, 308.0, 308.0, 308.0, *bath, 304.0, 304.5, 304.0, 304.0]
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)
    heat = prog.table(302.0)
    assert temperature_rate(heat, 0.05)[1] == pytest.approx(60.0)
    assert temperature_rate(heat, 0.35)[1] == pytest.approx(-6.0 / 0.05 * math.exp(-1.0))
    assert temperature_rate(heat, 0.85)[1] == pytest.approx(-5.0)
    assert temperature_rate(heat, 5.0)[1] == 0.0  # held after the last step
    assert prog.reference == 304.0  # the last temperature


def test_ramp_sign_and_length_follow_the_target() -> None:
    cool = Program((Ramp(300.0, 2.0),)).pieces(308.0)
    assert len(cool) == 1 and cool[0].p == -2.0 and cool[0].t1 == pytest.approx(4.0)
    assert Program((Ramp(300.0, 2.0),)).pieces(300.0) == []  # nothing to ramp


def test_until_steps_are_bounded_and_released_is_a_radius() -> None:
    hold = Program((Hold(308.0, until=Released(0.3)),)).steps[0]
    assert hold.duration == UNTIL_LIMIT
    a0 = 2.2924
    assert Released(0.3).radius(a0) ** 3 == pytest.approx(a0**3 - 0.3 * (a0**3 - 1.0))
    piece = Program((Hold(308.0, 2.0, until=Radius(1.5)),)).pieces(302.0, a0)[0]
    assert piece.until == 1.5 and piece.t1 == 2.0


@pytest.mark.parametrize(("steps", "field"), [
    ((), "steps"),
    ((Hold(308.0),), "steps[0].duration"),
    ((Ramp(308.0, 1.0), Hold(400.0, 1.0)), "steps[1].temperature"),
    ((Ramp(308.0, 0.0),), "steps[0].rate"),
    ((Ramp(308.0, -1.0),), "steps[0].rate"),
    ((Bath(308.0, 0.0, 1.0),), "steps[0].time_constant"),
    ((Hold(308.0, float("nan")),), "steps[0].duration"),
    ((Hold(308.0, until=Released(1.2)),), "steps[0].until.fraction"),
    ((Hold(308.0, until=Radius(0.9)),), "steps[0].until.radius"),
    ((Hold(308.0, until=0.3),), "steps[0].until"),
    ((Trace((0.0, 0.2, 0.1), (302.0, 303.0, 304.0)),), "steps[0].times[2]"),
    ((Trace((0.1, 0.2), (302.0, 303.0)),), "steps[0].times[0]"),
    ((Trace((0.0, 0.2), (302.0, float("nan"))),), "steps[0].temperatures[1]"),
    ((Trace((0.0, 0.2), (302.0, 380.0)),), "steps[0].temperatures[1]"),
    ((Trace((0.0,), (302.0,)),), "steps[0].times"),
    (("hold",), "steps[0]"),
])
def test_bad_steps_name_the_step_and_field(steps: tuple, field: str) -> None:
    with pytest.raises(ParameterError) as err:
        Program(steps)
    assert err.value.field == field


def test_bad_mobility_is_refused() -> None:
    with pytest.raises(ParameterError) as err:
        Program((Hold(308.0, 1.0),), mobility="eta")
    assert err.value.field == "mobility"


def test_mobility_factor_sizes_for_302_to_308() -> None:
    """k_B T alone: 302/308; with water's viscosity (Vogel) also eta(308)/eta(302), about
    0.885 against the tabulated 0.7225/0.8159 mPa s = 0.8855 (CRC)."""
    assert mobility_factor(0, 302.0, 308.0) == 1.0
    assert mobility_factor(1, 302.0, 308.0) == pytest.approx(302.0 / 308.0)
    water = mobility_factor(2, 302.0, 308.0) / (302.0 / 308.0)
    assert water == pytest.approx(0.7225 / 0.8159, rel=5e-3)
    assert mobility_factor(2, 308.0, 308.0) == 1.0


def test_old_protocol_is_a_program_of_holds() -> None:
    prog = Program.from_protocol([(0.1, 308.0), (0.2, 302.0)])
    np.testing.assert_allclose(prog.temperature(300.0, [0.0, 0.05, 0.099, 0.15, 0.3, 1.0]),
                               [308.0, 308.0, 308.0, 302.0, 302.0, 302.0])
