"""The delayed-jump estimate's parts (solver/front/heating.py): the coexistence onset of
the start state and the time a program reaches it."""

from __future__ import annotations

import math

import pytest

from solver.equilibrium import equilibrium
from solver.errors import NotApplicableError
from solver.front.heating import onset_temperature, onset_time
from solver.gel import ANB
from solver.heating import Bath, Hold, Program, Ramp
from solver.phase import in_coexistence


def test_onset_is_where_the_start_stretch_enters_coexistence() -> None:
    a0 = equilibrium(ANB, 302.0, "swollen").stretch
    t_c = onset_temperature(ANB, a0, 302.0, 308.0)
    assert t_c is not None and 307.0 < t_c < 307.2  # 307.11 K
    assert in_coexistence(ANB, t_c + 1e-4, a0)
    assert not in_coexistence(ANB, t_c - 1e-4, a0)
    assert onset_temperature(ANB, a0, 302.0, 304.0) is None  # one phase up to 304 K


def test_onset_time_on_ramps_and_baths() -> None:
    ramp = Program((Hold(302.0, 0.1), Ramp(308.0, 60.0)))
    assert onset_time(ramp, 302.0, 305.0) == pytest.approx(0.1 + 3.0 / 60.0)
    bath = Program((Bath(308.0, 0.02, duration=1.0),))
    assert onset_time(bath, 302.0, 307.0) == pytest.approx(0.02 * math.log(6.0))
    with pytest.raises(NotApplicableError):
        onset_time(Program((Ramp(306.0, 1.0),)), 302.0, 307.0)
