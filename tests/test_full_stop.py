"""Terminal events and output selection of simulate (issue 21): ``stop`` ends a run when
the radius reaches a value, located inside the accepted step; ``saveat`` picks outputs."""

from __future__ import annotations

import numpy as np
import pytest
from grid_support import every_grid

from solver.errors import ParameterError
from solver.full import simulate

RUN = {"n": 40, "rtol": 1e-8, "atol": 1e-11}


@pytest.mark.parametrize(("grid", "extra"), every_grid())
def test_stop_ends_at_the_crossing_of_the_uninterrupted_run(grid: str, extra: dict) -> None:
    """The terminal time is the whole run's dense crossing time (same steps up to it, so
    equal to rounding), the last output is the target radius, and the record says so."""
    whole = simulate("ANB", 302, 308, until=0.2, grid=grid, **RUN, **extra)
    target = 0.5 * (whole.radius[0] + whole.radius[-1])
    t_cross = whole.time_to_radius(target)
    res = simulate("ANB", 302, 308, until=0.2, grid=grid, stop=target, **RUN, **extra)
    assert res.status == "stopped"
    assert res.terminal_time == pytest.approx(t_cross, rel=1e-9)
    assert res.t_events.tolist() == [res.terminal_time]
    assert res.t[-1] == res.terminal_time
    assert res.radius[-1] == pytest.approx(target, rel=1e-7)  # dense state at the event
    assert res.step_t[-1] == res.terminal_time  # the per-step record ends there
    assert res.time_to_radius(target) == pytest.approx(t_cross, rel=1e-9)
    assert np.all(np.diff(res.t) > 0)
    assert res.horizon < 0.2


def test_stop_on_a_rising_radius() -> None:
    """Cooling swells the bead: a target above the start radius is reached from below."""
    whole = simulate("HHT", 308, 304, until=0.05, grid="lagrangian", **RUN)
    target = whole.radius[0] + 0.3 * (whole.radius[-1] - whole.radius[0])
    res = simulate("HHT", 308, 304, until=0.05, grid="lagrangian", stop=target, **RUN)
    assert res.radius[-1] > res.radius[0]
    assert res.terminal_time == pytest.approx(whole.time_to_radius(target), rel=1e-9)


def test_stop_not_reached_finishes_at_the_horizon() -> None:
    res = simulate("ANB", 302, 308, until=0.01, grid="lagrangian", stop=1.05, **RUN)
    assert res.status == "finished"
    assert res.t_events.size == 0 and res.terminal_time is None
    assert res.horizon == 0.01


def test_saveat_selects_outputs_and_adds_the_terminal_time() -> None:
    times = [0.0, 0.003, 0.01, 0.02, 0.15]
    res = simulate("ANB", 302, 308, until=0.2, grid="lagrangian", saveat=times, **RUN)
    assert res.t.tolist() == times and res.status == "finished"
    stopped = simulate("ANB", 302, 308, until=0.2, grid="lagrangian", saveat=times,
                       stop=2.0, **RUN)
    t_e = stopped.terminal_time
    assert t_e is not None and 0.02 < t_e < 0.15
    assert stopped.t.tolist() == [0.0, 0.003, 0.01, 0.02, t_e]


@pytest.mark.parametrize(("kwargs", "field"), [
    ({"stop": 0.5}, "stop"),
    ({"stop": float("nan")}, "stop"),
    ({"stop": 2.0, "integrator": "explicit"}, "integrator"),
    ({"saveat": [0.0, 0.5]}, "saveat"),
    ({"saveat": [0.002, 0.001]}, "saveat"),
    ({"saveat": [0.001], "every": 0.001}, "saveat"),
])
def test_bad_events_and_outputs_are_refused(kwargs: dict, field: str) -> None:
    with pytest.raises(ParameterError) as err:
        simulate("ANB", 302, 308, until=0.01, n=20, **kwargs)
    assert err.value.field == field


def test_stop_takes_a_released_fraction_of_the_start_radius() -> None:
    from solver.heating import Released

    res = simulate("ANB", 302, 308, until=0.3, grid="lagrangian", stop=Released(0.5), **RUN)
    a0 = res.radius[0]
    assert res.status == "stopped"
    assert res.radius[-1] ** 3 == pytest.approx(a0**3 - 0.5 * (a0**3 - 1.0), rel=1e-7)
    with pytest.raises(ParameterError) as err:
        simulate("ANB", 302, 308, until=0.3, n=20, stop=Released(1.5))
    assert err.value.field == "stop.fraction"


def test_a_stopped_runs_last_slope_is_its_steps_own() -> None:
    """The stopped state's da/dt is the accepted step's cubic at the event (a dense state's
    rhs was garbage on the Lagrangian grid, and a later time_to_radius over that last long
    step read a crossing 12 % early: HHT 304 -> 307.6 K, smooth, long steps)."""
    kw = dict(grid="lagrangian", n=800, interfacial_length=0.005, rtol=1e-5)
    free = simulate("HHT", 304.0, 307.6, until=2.0, **kw)
    target = float(np.interp(1.0, free.t, free.radius))
    run = simulate("HHT", 304.0, 307.6, until=2.0, stop=target * (1 - 1e-6), **kw)
    t, a, rate = run._dense()
    assert rate[-1] == pytest.approx(np.interp(1.0, free.t, np.gradient(free.radius, free.t)),
                                     rel=0.05)
    assert run.time_to_radius(target) == pytest.approx(1.0, rel=1e-3)
