"""Solid conservation and relaxation to equilibrium on every grid and both integrators."""

from __future__ import annotations

import numpy as np
import pytest
from grid_support import every_grid

from solver.equilibrium import equilibrium
from solver.full import simulate
from solver.gel import ANB, HHT


@pytest.mark.parametrize(("grid", "settings"), every_grid())
def test_solid_conserved_through_a_heat_cool_heat_protocol(grid: str, settings: dict) -> None:
    res = simulate(ANB, 302, protocol=[(0.03, 308), (0.05, 302), (0.3, 308)], grid=grid, n=60,
                   every=0.002, **settings)
    assert np.max(res.solid_error) < 1e-10
    np.testing.assert_array_equal(res.temperature[(res.t > 0) & (res.t <= 0.03)], 308.0)
    assert np.all(res.temperature[(res.t > 0.03) & (res.t <= 0.08)] == 302.0)
    # the final step runs the front to the centre (the Eulerian core merge included)
    eq = equilibrium(ANB, 308, "shrunken")
    assert res.radius[-1] == pytest.approx(eq.stretch, rel=1e-6)


def test_solid_conserved_by_forward_euler() -> None:
    res = simulate(HHT, 308, 304, until=0.002, n=40, integrator="explicit", every=0.0005)
    assert np.max(res.solid_error) < 1e-10


@pytest.mark.parametrize(("grid", "settings"), every_grid())
@pytest.mark.parametrize(("gel", "t0", "t1"), [(ANB, 308, 302), (HHT, 304, 308)])
def test_final_state_is_the_equilibrium_at_t_end(grid: str, settings: dict, gel: object,
                                                 t0: float, t1: float) -> None:
    res = simulate(gel, t0, t1, until=30.0, grid=grid, n=60, every=1.0, **settings)
    branch = "swollen" if t1 < t0 else "shrunken"
    eq = equilibrium(gel, t1, branch)
    assert res.radius[-1] == pytest.approx(eq.stretch, rel=1e-6)
    np.testing.assert_allclose(res.phi[-1], eq.porosity, atol=1e-6)
    assert res.expelled_volume[-1] == pytest.approx(
        4 * np.pi / 3 * (res.radius[0] ** 3 - eq.stretch**3), rel=1e-5)


def test_branch_selects_the_start_state() -> None:
    # ANB has two stable equilibria at 305 K; starting on either branch and holding 305 K
    # keeps the gel there
    for branch in ("swollen", "shrunken"):
        res = simulate(ANB, 305, 305, until=0.1, n=40, branch=branch, every=0.05)
        assert res.diagnostics["branch"] == branch
        assert res.radius[-1] == pytest.approx(equilibrium(ANB, 305, branch).stretch, rel=1e-9)
