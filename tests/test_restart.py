"""Protocol runs continued from a protocol boundary (issue 23; solver.full.state,
dosing.runs.restart).

The full solver keeps a protocol run's state after every step and continues a protocol from
one exactly (``simulate(..., initial=state)``, joined by ``FullResult.after``); the planner
starts a protocol from its longest stored prefix, and a schedule's read-off heating stops at
its dose.  Each must give the one-shot run's answer within the numerical bound: the direct
truth's n vs n/2 gap is ~2e-4 of a dose time (docs/speed.md sec. 3), the integrator's rtol
1e-5.
"""

from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace

import numpy as np
import pytest
from grid_support import every_grid

from dosing import Planner, ScheduleRequest
from dosing.question.shooting import FluidHeatings, windows
from dosing.runs.restart import Start, run_protocol
from dosing.runs.scenario import Scenario, SolverSettings
from solver.errors import ParameterError
from solver.full import FullResult, simulate
from solver.full.state import BoundaryState
from solver.full.state import protocol_boundaries as boundaries
from solver.gel import preset

PROTOCOL = ((0.01, 308.0), (0.05, 302.0), (0.02, 308.0))
MOVING = SolverSettings(grid="moving", n=100, interfacial_length=1e-3)
BOUND = 1e-4  # inside the truth's numerical bound (~2e-4), 10x the rtol
N = 60


def at_boundaries(res, protocol=PROTOCOL) -> np.ndarray:
    return np.array([res.radius_at(t) for t in boundaries(protocol)])


def _run(grid: str, settings: dict, protocol=PROTOCOL, n: int = N, **kw) -> FullResult:
    return simulate("ANB", 302.0, protocol=list(protocol), grid=grid, n=n, rtol=1e-6,
                    **settings, **kw)


@pytest.mark.parametrize(("grid", "settings"), every_grid())
def test_a_protocol_continued_from_a_boundary_state_is_the_one_shot_run(grid, settings) -> None:
    """A run of the first two steps, continued from its state after them through the third
    (one simulate call, in protocol time) and joined: the one-shot run of the protocol.
    Every step restarts the integrator (a small first step; the moving nodes stop), so on
    the fixed grids the continuation takes the very same steps (radii equal to round-off
    of the state's profile); the moving grid's mesh-motion history is what a continuation
    forgets (the state keeps its nodes, not the history of their targets), a change of the
    discretisation's error far below its N vs N/2 change (asserted: a tenth of it; here
    the same steps, at N = 100, ell = 1e-3 4 % more steps after the boundary and radii
    3e-7 apart, measured).  The prefix outputs as the one-shot run does (the moving grid
    lands a step on every output)."""
    one = _run(grid, settings)
    t2 = boundaries(PROTOCOL)[2]
    pre = _run(grid, settings, PROTOCOL[:2], saveat=one.t[one.t <= t2])
    assert [(s.steps, s.t) for s in one.boundary_states] == list(
        zip([1, 2, 3], boundaries(PROTOCOL)[1:], strict=True))
    state = pre.boundary_state(2)
    cont = _run(grid, settings, initial=state)
    assert cont.t[0] == pytest.approx(boundaries(PROTOCOL)[2], abs=0.0)  # protocol time
    assert cont.diagnostics["start"] == {"t": state.t, "steps": 2}
    joined = cont.after(pre)
    assert joined.diagnostics["restarted_after_steps"] == 2
    assert [s.steps for s in joined.boundary_states] == [1, 2, 3]
    assert np.all(np.diff(joined.t) > 0.0) and np.all(np.diff(joined.step_t) > 0.0)
    gap = np.abs(at_boundaries(joined) / at_boundaries(one) - 1.0).max()
    half = _run(grid, settings, n=N // 2)
    refine = np.abs(at_boundaries(half) / at_boundaries(one) - 1.0).max()
    assert gap <= 0.1 * refine
    if grid != "moving":
        assert gap < 1e-10
        assert joined.diagnostics["steps"] == one.diagnostics["steps"]
        last = one.boundary_states[-1]
        assert joined.boundary_states[-1].phi == pytest.approx(last.phi, rel=1e-9)
    else:
        assert joined.boundary_states[-1].nodes.shape == (N + 1,)
        assert abs(joined.diagnostics["steps"] / one.diagnostics["steps"] - 1.0) < 0.1


def test_a_boundary_state_round_trips_and_is_checked() -> None:
    """A state as plain data and in a run's npz; older stored runs kept them in meta (the
    same keys); a state that is not a boundary of the protocol is refused."""
    res = _run("lagrangian", {}, PROTOCOL[:2])
    st = res.boundary_state(1)
    again = BoundaryState.from_data(st.to_data())
    assert (again.t, again.steps, again.radius, again.nodes) == (st.t, 1, st.radius, None)
    assert np.array_equal(again.phi, st.phi) and again.counters == st.counters
    rec = res.without_profiles()
    back = FullResult.from_npz(rec.to_npz())
    assert [s.to_data() for s in back.boundary_states] == [
        s.to_data() for s in res.boundary_states]
    old = FullResult.from_npz(FullResult(t=rec.t, radius=rec.radius, front=rec.front).to_npz(),
                              {"boundary_states": [s.to_data() for s in res.boundary_states]})
    assert old.boundary_state(1).radius == st.radius and old.boundary_state(2) is not None
    assert "boundary_states" not in old.meta
    with pytest.raises(ParameterError, match="initial.t"):
        _run("lagrangian", {}, ((0.02, 308.0), *PROTOCOL[1:]), initial=st)
    with pytest.raises(ParameterError, match="initial.steps"):
        _run("lagrangian", {}, PROTOCOL[:1], initial=st)
    with pytest.raises(ParameterError, match="initial.nodes"):
        _run("moving", {"interfacial_length": 0.02}, initial=st)


def test_a_wall_clock_budget_changes_no_step_on_the_moving_grid() -> None:
    """``max_seconds`` is checked where the stepping loop stops anyway: the run takes the
    same steps as without it (its progress ticks used to stop the integration 200 times a
    run and shift the moving grid's mesh checks wherever the outputs are not at those
    ticks: here, before, 737 steps instead of 378 and radii 2e-5 apart)."""
    kw = {"interfacial_length": 1e-3, "saveat": np.linspace(0.0, 0.01, 38)}
    free = _run("moving", kw, PROTOCOL[:1], n=100)
    timed = _run("moving", kw, PROTOCOL[:1], n=100, max_seconds=1e6)
    assert timed.diagnostics["steps"] == free.diagnostics["steps"]
    assert timed.diagnostics["mesh_checks"] == free.diagnostics["mesh_checks"]
    assert np.array_equal(timed.radius, free.radius)


def test_a_protocol_run_stores_its_states_and_continues_a_stored_prefix() -> None:
    """dosing's run of a protocol: one simulate call, from a stored prefix's state."""
    sc = Scenario(preset("ANB"), 302.0, protocol=PROTOCOL, settings=MOVING)
    one = run_protocol(sc, simulate, 600.0)
    assert [s.steps for s in one.boundary_states] == [1, 2, 3]
    assert not one.phi.size and one.diagnostics["restarted_after_steps"] == 0
    pre = run_protocol(Scenario(preset("ANB"), 302.0, protocol=PROTOCOL[:2], settings=MOVING),
                       simulate, 600.0)
    again = run_protocol(sc, simulate, 600.0, Start.of(pre, 2))
    assert again.diagnostics["restarted_after_steps"] == 2
    assert at_boundaries(again) == pytest.approx(at_boundaries(one), rel=BOUND)
    assert Start.of(pre, 3) is None


class Counting:
    """simulate, counted by the protocol it is asked for; restartable as simulate is."""

    restartable = True

    def __init__(self) -> None:
        self.calls: list[tuple[tuple, bool]] = []

    def __call__(self, *args, **kw):
        self.calls.append((tuple(map(tuple, kw["protocol"])), kw.get("initial") is not None))
        return simulate(*args, **kw)


def plain(*args, **kw):
    """simulate behind a name the planner does not know restarts exactly: one-shot runs."""
    return simulate(*args, **kw)


def test_a_stored_prefix_is_not_run_again(tmp_path) -> None:
    spy = Counting()
    with Planner(cache_path=tmp_path / "c.sqlite", executor=ThreadPoolExecutor(1),
                 solver=spy) as planner:
        planner.trajectory(Scenario(preset("ANB"), 302.0, protocol=PROTOCOL[:2],
                                    settings=MOVING))
        assert spy.calls == [(PROTOCOL[:2], False)]
        assert planner.restarts == 0
        full = planner.trajectory(Scenario(preset("ANB"), 302.0, protocol=PROTOCOL,
                                           settings=MOVING))
        # the first two steps were not run again: one call from their state
        assert spy.calls[1:] == [(PROTOCOL, True)]
        assert planner.restarts == 1
        assert full.diagnostics["restarted_after_steps"] == 2
    with Planner(cache_path=tmp_path / "d.sqlite", executor=ThreadPoolExecutor(1),
                 solver=plain) as fresh:
        one = fresh.trajectory(Scenario(preset("ANB"), 302.0, protocol=PROTOCOL,
                                        settings=MOVING))
        assert fresh.restarts == 0 and one.diagnostics["steps"] > 0
    assert at_boundaries(full) == pytest.approx(at_boundaries(one), rel=BOUND)


def test_a_read_off_heating_stops_at_its_dose(tmp_path) -> None:
    req = ScheduleRequest("ANB", 302.0, 308.0, doses=[0.2, 0.2], rests=[0.05],
                          settings=MOVING)
    with Planner(cache_path=tmp_path / "c.sqlite", executor=ThreadPoolExecutor(1)) as planner:

        def run(steps, stop_expelled=None):
            return planner.trajectory(Scenario(req.gel, req.t_start, protocol=steps,
                                               settings=req.settings,
                                               stop_expelled=stop_expelled))

        h = FluidHeatings(run, req)
        trial = [0.003, 0.05]
        stopped = h.run_until(trial, 1)
        whole = h.run(trial)
        start = windows(trial, req.rests)[1][0]
        assert stopped.status == "stopped" and stopped.horizon < start + 0.01
        assert whole.status == "finished" and whole.horizon == pytest.approx(0.103)
        assert h.reach(stopped, trial, 1).duration == pytest.approx(
            h.reach(whole, trial, 1).duration, rel=BOUND)
        # both started from the stored state after the first heating and the rest
        assert planner.restarts == 1
    # a protocol without the event keeps its key
    assert "stop_expelled" not in Scenario(req.gel, 302.0, protocol=PROTOCOL).key_dict()


def test_a_restarted_schedule_equals_the_one_shot_schedule(tmp_path) -> None:
    req = ScheduleRequest("ANB", 302.0, 308.0, doses=[0.2, 0.2, 0.2], rests=[0.05, 0.05],
                          settings=MOVING, check_protocol=True)
    answers = []
    for name, solver in (("restart", None), ("plain", plain)):
        with Planner(cache_path=tmp_path / f"{name}.sqlite", executor=ThreadPoolExecutor(1),
                     solver=solver) as planner:
            answers.append(planner.schedule(req))
            assert (planner.restarts > 0) == (solver is None)
    new, old = answers
    assert new.corrected["met"] and old.corrected["met"]
    assert new.corrected["actuation_times"] == pytest.approx(
        old.corrected["actuation_times"], rel=BOUND)
    assert new.protocol_check["delivered_fractions"] == pytest.approx(
        old.protocol_check["delivered_fractions"], rel=BOUND)


def test_a_drug_dose_run_stops_soon_after_its_dose(tmp_path, monkeypatch) -> None:
    # the full solver's drug run is read off a heating of twice the reduced drug model's
    # time (it ran to FIRST_HEATING = 0.5 tau, 66x this dose): the same dose within the
    # answer's numerical bound (the drug run on n / 2 cells)
    from dosing.payload import release as drug_dose
    from dosing.payload.drug import DrugModel
    from dosing.payload.release import (
        DrugDoseRequest,
        DrugHeatings,
        first_heating,
        plan_drug_dose,
    )

    req = DrugDoseRequest("ANB", 302, 308, DrugModel(diffusivity_cm2_s=1e-7, hindrance="none"),
                          dose_fraction=0.5, dry_radius_um=50,
                          settings=SolverSettings(interfacial_length=0.01, n=100))
    guess, floor = first_heating(req)
    assert floor == 0.0
    with Planner(cache_path=tmp_path / "c.sqlite", executor=ThreadPoolExecutor(1)) as planner:
        ans = plan_drug_dose(planner, req, validate=True)
        heat = DrugHeatings(req, None, [0.5])  # type: ignore[arg-type]
        assert ans.scenario_key == heat.scenario([2.0 * guess]).key()
        assert 2.0 * guess < 4.0 * ans.time
    monkeypatch.setattr(drug_dose, "first_heating",
                        lambda r: (drug_dose.FIRST_HEATING / 2.0, drug_dose.READ_OFF_FLOOR))
    with Planner(cache_path=tmp_path / "d.sqlite", executor=ThreadPoolExecutor(1)) as planner:
        long = plan_drug_dose(planner, req, validate=True)
        assert long.scenario_key == heat.scenario([drug_dose.FIRST_HEATING]).key()
    bound = ans.uncertainty.numerical.relative
    assert 0.0 < bound < 0.05
    assert ans.time == pytest.approx(long.time, rel=bound)


def test_a_drug_run_continues_the_kept_mechanics_of_its_prefix(tmp_path) -> None:
    # a drug run continues the kept mechanics of its protocol's prefix from their state
    # after it (one simulate call): the outputs of a fresh run, and its mechanics up to the
    # moving grid's mesh history (see the first test)
    from dosing.payload.cycles import DrugScheduleRequest
    from dosing.payload.drug import DrugModel
    from dosing.payload.release import DrugHeatings
    from dosing.runs.solute import DrugRuns

    req = DrugScheduleRequest("ANB", 302, 308, DrugModel(diffusivity_cm2_s=1e-8, load_ug=1.0,
                                                         hindrance="none"),
                              doses=[0.2, 0.2], rests=[0.05], dry_radius_um=50,
                              settings=SolverSettings(interfacial_length=0.01, n=100))
    with Planner(cache_path=tmp_path / "c.sqlite", executor=ThreadPoolExecutor(1)) as planner:
        runs = DrugRuns(planner)
        heat = DrugHeatings(req, runs, req.fractions)
        runs.run(heat.scenario([0.01, 0.02]))
        assert runs.restarts == 0
        kept = runs.run(heat.scenario([0.01, 0.03]))
        assert runs.restarts == 1 and kept.diagnostics["mechanics_from_step"] == 2
        # and its solute from the kept run's state at that boundary (its own samples after)
        assert kept.diagnostics["solute_from_sample"] > 0
        runs.close()
    with Planner(cache_path=tmp_path / "d.sqlite", executor=ThreadPoolExecutor(1)) as planner:
        runs = DrugRuns(planner)
        fresh = runs.run(DrugHeatings(req, runs, req.fractions).scenario([0.01, 0.03]))
        assert fresh.diagnostics["mechanics_from_step"] == 0
        assert fresh.diagnostics["solute_from_sample"] == 0
        runs.close()
    assert np.array_equal(kept.t, fresh.t)
    # measured: radii 1.5e-9 relative, released fractions 9e-10 apart
    assert kept.radius == pytest.approx(fresh.radius, rel=1e-7)
    assert kept.released_fraction == pytest.approx(fresh.released_fraction, abs=1e-7)


def test_another_processs_stored_prefix_serves_too(tmp_path) -> None:
    # the run store keeps each protocol run's states: a planner that never saw the prefix
    # run (another process, sharing the cache file) starts from it
    with Planner(cache_path=tmp_path / "c.sqlite", executor=ThreadPoolExecutor(1),
                 solver=Counting()) as first:
        first.trajectory(Scenario(preset("ANB"), 302.0, protocol=PROTOCOL[:2],
                                  settings=MOVING))
    spy = Counting()
    with Planner(cache_path=tmp_path / "c.sqlite", executor=ThreadPoolExecutor(1),
                 solver=spy) as second:
        second.trajectory(Scenario(preset("ANB"), 302.0, protocol=PROTOCOL, settings=MOVING))
        assert spy.calls == [(PROTOCOL, True)] and second.restarts == 1


def test_a_stopped_read_off_is_the_run_of_its_heating(tmp_path) -> None:
    # the heating read off a stopped run lasts until the stop (the dose and STOP_MARGIN),
    # and that run is also the run of the protocol ending there: the secant's first check
    # of it, and the next heating's prefix, run nothing more
    spy = Counting()
    req = ScheduleRequest("ANB", 302.0, 308.0, doses=[0.2, 0.2], rests=[0.05],
                          settings=MOVING)
    with Planner(cache_path=tmp_path / "c.sqlite", executor=ThreadPoolExecutor(1),
                 solver=spy) as planner:

        def run(steps, stop_expelled=None):
            return planner.trajectory(Scenario(req.gel, req.t_start, protocol=steps,
                                               settings=req.settings,
                                               stop_expelled=stop_expelled))

        h = FluidHeatings(run, req)
        stopped = h.run_until([0.05], 0)
        d = h.reach(stopped, [0.05], 0).duration
        assert stopped.status == "stopped" and d == pytest.approx(stopped.terminal_time)
        calls = len(spy.calls)
        exact = h.run([d])
        assert len(spy.calls) == calls and exact.status == "finished"  # no new run
        assert h.delivered(exact, [d])[0] == pytest.approx(0.2 * (1 + 1e-6), rel=1e-9)
        h.run([d, 0.003])
        assert spy.calls[calls:] == [(((d, 308.0), (0.05, 302.0), (0.003, 308.0)), True)]
    # the same heating run to that time from t = 0: the same delivery within the bound
    with Planner(cache_path=tmp_path / "d.sqlite", executor=ThreadPoolExecutor(1)) as fresh:
        again, half = (fresh.trajectory(Scenario(
            req.gel, req.t_start, protocol=((d, 308.0),),
            settings=replace(req.settings, n=n))) for n in (MOVING.n, MOVING.n // 2))
        # the moving grid's front band times its mesh checks by the run's own steps, so a
        # run stopped at an event and one ending at d take different steps: 1.0e-4 and
        # 2.0e-4 apart (measured on two machines: the steps follow the last bits of the
        # arithmetic), inside these settings' numerical bound, the n vs n / 2 gap (2.9e-3)
        delivered, coarse = (h.delivered(r, [d])[0] for r in (again, half))
        assert abs(delivered - 0.2) <= 0.5 * abs(coarse - delivered)


def test_a_restarted_planner_starts_where_the_first_would_have(tmp_path) -> None:
    """Issue 40, R11: which stored run a protocol starts from was kept in the planner's
    memory only, so a job resumed after a restart could start from another stored state
    (the prefix's own run, or an earlier one) than the uninterrupted job did: equal to
    round-off and the moving grid's mesh history (3e-7), which a schedule's shooting can
    carry to ~5e-6.  The cache keeps it too: a planner started afresh starts from the same
    run's state."""
    other = (*PROTOCOL[:2], (0.03, 306.0))
    with Planner(cache_path=tmp_path / "c.sqlite", executor=ThreadPoolExecutor(1),
                 solver=Counting()) as first:
        run = Scenario(preset("ANB"), 302.0, protocol=PROTOCOL, settings=MOVING)
        first.trajectory(run)
        want = first.runs._start(Scenario(preset("ANB"), 302.0, protocol=other, settings=MOVING))
    assert want is not None and want.steps == 2 and want.record.meta["key"] == run.key()
    with Planner(cache_path=tmp_path / "c.sqlite", executor=ThreadPoolExecutor(1),
                 solver=Counting()) as second:
        got = second.runs._start(Scenario(preset("ANB"), 302.0, protocol=other, settings=MOVING))
    assert got is not None and got.steps == 2 and got.record.meta["key"] == run.key()
    same = got.record.boundary_state(2), want.record.boundary_state(2)
    assert same[0].phi.tobytes() == same[1].phi.tobytes() and same[0].t == same[1].t
