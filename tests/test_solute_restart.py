"""A solute run continued from a stored run's state at a protocol boundary (issue 23):
the march's whole state (cell masses, step size, advected mass) is kept at every step
boundary, so a protocol sharing the first steps marches only the rest."""

import numpy as np
import pytest

from solver.errors import ParameterError
from solver.full import simulate
from solver.solute import Hindrance, Solute, release
from solver.solute.transport import SoluteStart

A = [(0.01, 308.0), (0.02, 304.0), (0.03, 308.0)]
B = [(0.01, 308.0), (0.02, 304.0), (0.015, 310.0)]  # A's first two steps, another third
EVERY = 1e-4
SOLUTE = Solute(diffusivity=0.05)


def _mechanics(protocol):
    return simulate("ANB", 302.0, protocol=protocol, grid="lagrangian", n=60, rtol=1e-6,
                    every=EVERY)


@pytest.fixture(scope="module")
def runs():
    mech_a, mech_b = _mechanics(A), _mechanics(B)
    return mech_a, release(mech_a, SOLUTE), mech_b


def test_every_step_boundary_keeps_the_marchs_state(runs) -> None:
    mech, rec, _ = runs
    at = [mech.t[int(k)] for k in rec.state_index]
    assert at == pytest.approx([0.01, 0.03, 0.06], abs=1e-12)
    assert rec.states.shape == (3, 60 + 3)
    k = int(rec.state_index[1])
    state = rec.states[1]
    assert state[:61].sum() == pytest.approx(1.0, abs=1e-10)  # the mass, gel and medium
    assert state[60] == rec.released_fraction[k] and state[61] > 0.0  # medium; step size
    assert state[62] == rec.advected_fraction[k]


def test_a_continued_run_is_the_one_run_bit_for_bit(runs) -> None:
    mech, rec, _ = runs
    start = SoluteStart.at(rec, 0.03)
    assert start is not None and mech.t[start.index] == pytest.approx(0.03, abs=1e-12)
    cont = release(mech, SOLUTE, start=start)
    assert cont.diagnostics["from_sample"] == start.index
    assert cont.diagnostics["steps"] < 0.7 * rec.diagnostics["steps"]  # only the rest
    for name in ("released_fraction", "advected_fraction", "in_gel_fraction",
                 "squeezed_fraction", "state_index", "states"):
        assert np.array_equal(getattr(cont, name), getattr(rec, name)), name
    common, i, j = np.intersect1d(rec.profile_t, cont.profile_t, return_indices=True)
    assert common.size >= 25 and np.array_equal(rec.profiles[i], cont.profiles[j])
    assert cont.profile_t.size == rec.profile_t.size == 51


def test_another_protocol_continues_from_the_shared_boundary(runs) -> None:
    # B shares A's first two steps: B's solute continued from A's state at t = 0.03 is B's
    # own run (the mechanics agree to round-off before the boundary on this grid)
    _, rec, mech_b = runs
    fresh = release(mech_b, SOLUTE)
    cont = release(mech_b, SOLUTE, start=SoluteStart.at(rec, 0.03))
    assert cont.diagnostics["from_sample"] > 0
    assert np.max(np.abs(cont.released_fraction - fresh.released_fraction)) < 1e-12
    assert np.max(np.abs(cont.in_gel_fraction + cont.released_fraction - 1.0)) < 1e-12
    assert np.array_equal(cont.state_index, fresh.state_index)


def test_a_start_is_refused_where_it_cannot_continue(runs) -> None:
    mech, rec, _ = runs
    start = SoluteStart.at(rec, 0.03)
    assert SoluteStart.at(rec, 0.02) is None  # no step boundary there
    sieved = Solute(diffusivity=0.05, hindrance=Hindrance(mesh=0.3))  # its twin is run
    with pytest.raises(ParameterError, match="start"):
        release(mech, sieved, start=start)
    other = simulate("ANB", 302.0, protocol=A, grid="lagrangian", n=60, rtol=1e-6,
                     every=2 * EVERY)  # other samples before the boundary
    with pytest.raises(ParameterError, match="start"):
        release(other, SOLUTE, start=start)
