"""Extreme inputs converge or fail with SolverError (never NaN, never a hang); bad input
raises ParameterError naming the field."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from grid_support import every_grid

from solver.errors import BudgetExceeded, ParameterError, SolverError
from solver.full import simulate
from solver.gel import ANB, HHT


def _finite_or_solver_error(**kwargs: object) -> object:
    try:
        res = simulate(**kwargs)
    except SolverError as exc:
        assert isinstance(exc.diagnostics["steps"], (int, np.integer)), exc.diagnostics
        assert exc.diagnostics["grid"] == kwargs.get("grid", "eulerian"), exc.diagnostics
        return None
    for name in ("t", "radius", "phi", "solid_error", "expelled_volume"):
        assert np.all(np.isfinite(getattr(res, name))), name
    return res


@pytest.mark.parametrize(("grid", "settings"), every_grid())
def test_huge_jump_290_to_320(grid: str, settings: dict) -> None:
    """Deep inside the spinodal at 320 K: the paper's model (ell = 0) is flagged, or
    (Eulerian: the centre cell cavitates among the collapsing shells) a SolverError says so;
    the regularized model (the moving grid's) runs to a finite state."""
    try:
        res = simulate(ANB, 290, 320, until=0.3, n=60, grid=grid, rtol=1e-5, **settings)
    except SolverError as exc:
        assert "spinodal" in str(exc) and exc.diagnostics["spinodal_time"] < exc.diagnostics["t"]
        return
    assert np.all(np.isfinite(res.radius)) and np.all(np.isfinite(res.phi))
    assert res.spinodal or settings.get("interfacial_length", 0.0) > 0.0


def test_huge_cooling_320_to_290() -> None:
    res = _finite_or_solver_error(gel=ANB, t_start=320, t_end=290, until=2.0, n=60)
    assert res is not None and res.radius[-1] > 2.5


@pytest.mark.parametrize(("grid", "settings"), every_grid())
@pytest.mark.parametrize(("t0", "t1"), [(302, 308), (308, 302)])
def test_omega_1e4(grid: str, settings: dict, t0: float, t1: float) -> None:
    gel = replace(ANB, omega=1e4)
    _finite_or_solver_error(gel=gel, t_start=t0, t_end=t1, until=0.1, n=60, grid=grid,
                            rtol=1e-5, **settings)


@pytest.mark.parametrize("beta", [1.5, 2.0])
def test_power_law_permeability(beta: float) -> None:
    gel = ANB.with_permeability("power", beta)
    res = _finite_or_solver_error(gel=gel, t_start=302, t_end=308, until=0.05, n=60)
    assert res is not None and np.all(np.diff(res.radius) <= 1e-12)


def test_start_just_past_a_fold() -> None:
    # HHT's swelling fold is ~307.6 K: 0.01 K past it the shrinkage is critically slow
    res = _finite_or_solver_error(gel=HHT, t_start=304, t_end=307.61, until=2.0, n=60)
    assert res is not None


def test_step_budget_raises_with_diagnostics() -> None:
    with pytest.raises(SolverError, match="budget") as err:
        simulate(ANB, 302, 308, until=0.3, n=60, max_steps=50)
    d = err.value.diagnostics
    assert d["steps"] == 50 and d["grid"] == "eulerian" and d["t"] < 0.3


@pytest.mark.parametrize(("kwargs", "field"), [
    ({"t_end": 308}, "protocol"),
    ({"t_end": 308, "until": 0.1, "protocol": [(0.1, 308)]}, "protocol"),
    ({"protocol": [(-1.0, 308)]}, "protocol[0].duration"),
    ({"protocol": [(0.1, 400)]}, "protocol[0].temperature"),
    ({"t_end": 308, "until": 0.1, "grid": "polar"}, "grid"),
    ({"t_end": 308, "until": 0.1, "n": 3}, "n"),
    ({"t_end": 308, "until": 0.1, "integrator": "rk4"}, "integrator"),
    ({"t_end": 308, "until": 0.1, "rtol": 0.0}, "rtol"),
    ({"t_end": 308, "until": 0.1, "dt": 1e-6}, "dt"),
    ({"t_end": 308, "until": 0.1, "every": 1e-9}, "every"),
    ({"t_end": 308, "until": 0.1, "branch": "middle"}, "branch"),
    ({"t_end": 308, "until": 0.1, "initial": (2.0, [0.5, 0.5])}, "initial"),
])
def test_invalid_input_names_the_field(kwargs: dict, field: str) -> None:
    with pytest.raises(ParameterError) as err:
        simulate(ANB, 302, n=kwargs.pop("n", 40), **kwargs)
    assert err.value.field == field


def test_bad_start_temperature() -> None:
    with pytest.raises(ParameterError) as err:
        simulate(ANB, 500, 308, until=0.1, n=40)
    assert err.value.field == "t_start"


def test_wall_clock_budget_stops_a_run_with_a_clear_error() -> None:
    with pytest.raises(BudgetExceeded, match=r"lagrangian grid, N = 60, interfacial length "
                                             r"0\.02\) used its 0 s budget") as err:
        simulate("ANB", 302, 308, until=0.05, grid="lagrangian", n=60,
                 interfacial_length=0.02, max_seconds=0.0)
    assert err.value.diagnostics["grid"] == "lagrangian" and "wall_seconds" in err.value.diagnostics
    res = simulate("ANB", 302, 308, until=0.05, grid="lagrangian", n=60, max_seconds=600.0)
    assert np.all(np.isfinite(res.radius))
    with pytest.raises(ParameterError, match="max_seconds"):
        simulate("ANB", 302, 308, until=0.05, n=60, max_seconds=-1.0)


def test_a_rejected_step_to_a_steps_end_is_retried_shorter_not_for_ever() -> None:
    """Issue 40, R2: a protocol step of 1e-12 tau (an until-step's jump, 'Rest at 290 K
    until radius 130 um') after a hold at 308 K: its one step is rejected, and the
    controller's smaller step snapped back to the step's end (within 1e-12 of it), so the
    compiled loop retried the same step for ever at 100 % CPU.  Now the smaller step is
    taken as it is: the run crosses the jump and stops where the bead, swelling at 290 K,
    reaches 2.6 dry radii."""
    from solver.heating import Hold, Program

    prog = Program((Hold(308.0, 0.0272), Hold(290.0, 1e-12)), "kT", 308.0)
    res = simulate(ANB, 302.0, protocol=prog, stop=2.6, grid="moving", n=400,
                   interfacial_length=8e-5, max_seconds=300)
    assert res.diagnostics["status"] == "stopped"
    assert res.terminal_time == pytest.approx(0.5459, rel=1e-3)
    assert res.radius[-1] == pytest.approx(2.6, rel=1e-6)
