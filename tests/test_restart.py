"""Protocol runs restarted at protocol boundaries (issue 23, dosing.restart).

A protocol run goes step by step, each step from the exact state the last one ended in; a
later protocol sharing its first steps with a stored run starts there, and a schedule's
read-off heating stops at its dose.  Each must give the one-shot run's answer within the
numerical bound: the direct truth's n vs n/2 gap is ~2e-4 of a dose time (docs/speed.md
sec. 3), the integrator's rtol 1e-5.
"""

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

from dosing import Planner, ScheduleRequest
from dosing.protocol import FluidHeatings, windows
from dosing.restart import STATES, Start, boundaries, output_times, run_steps
from dosing.scenario import Scenario, SolverSettings
from solver.full import simulate
from solver.gel import preset

PROTOCOL = ((0.01, 308.0), (0.05, 302.0), (0.02, 308.0))
MOVING = SolverSettings(grid="moving", n=100, interfacial_length=1e-3)
BOUND = 1e-4  # inside the truth's numerical bound (~2e-4), 10x the rtol
TRUTH_BOUND = 2e-4  # the truth's numerical bound at these settings (docs/speed.md sec. 5)


def one_shot(settings: SolverSettings, protocol=PROTOCOL):
    b = boundaries(protocol)
    return simulate("ANB", 302.0, protocol=list(protocol), grid=settings.grid, n=settings.n,
                    rtol=settings.rtol, interfacial_length=settings.interfacial_length,
                    saveat=np.union1d(output_times(b[-1]), b))


def at_boundaries(res, protocol=PROTOCOL) -> np.ndarray:
    return np.array([res.radius_at(t) for t in boundaries(protocol)])


@pytest.mark.parametrize("settings", [SolverSettings(grid="lagrangian", n=100,
                                                     interfacial_length=0.01, method="ladder"),
                                      SolverSettings(grid="eulerian", n=100,
                                                     interfacial_length=0.0)])
def test_steps_one_after_another_are_the_one_shot_run_on_fixed_grids(settings) -> None:
    # every protocol step restarts the integrator, so the chain takes the very same steps
    sc = Scenario(preset("ANB"), 302.0, protocol=PROTOCOL, settings=settings)
    rec, states = run_steps(sc, simulate, 600.0)
    one = one_shot(settings)
    assert rec.diagnostics["steps"] == one.diagnostics["steps"]
    assert rec.t == pytest.approx(one.t, abs=1e-15)
    assert rec.radius == pytest.approx(one.radius, rel=1e-10)
    assert [s["steps"] for s in states] == [1, 2, 3]
    assert [s["t"] for s in states] == boundaries(PROTOCOL)[1:]


def test_steps_one_after_another_on_the_moving_grid_within_the_bound() -> None:
    # the moving grid's mesh history differs after a restart (measured: 777 vs 781 steps,
    # radii within 5e-6)
    sc = Scenario(preset("ANB"), 302.0, protocol=PROTOCOL, settings=MOVING)
    rec, states = run_steps(sc, simulate, 600.0)
    one = one_shot(MOVING)
    assert at_boundaries(rec) == pytest.approx(at_boundaries(one), rel=BOUND)
    assert abs(rec.diagnostics["steps"] / one.diagnostics["steps"] - 1.0) < 0.1
    # a restart from a stored prefix's state continues it
    pre = Scenario(preset("ANB"), 302.0, protocol=PROTOCOL[:2], settings=MOVING)
    prec, pstates = run_steps(pre, simulate, 600.0)
    prec.meta = {STATES: pstates}
    again, _ = run_steps(sc, simulate, 600.0, Start.of(prec, 2))
    assert again.diagnostics["restarted_after_steps"] == 2
    assert at_boundaries(again) == pytest.approx(at_boundaries(one), rel=BOUND)


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
        assert spy.calls == [(PROTOCOL[:1], False), (PROTOCOL[1:2], True)]
        assert planner.restarts == 0
        full = planner.trajectory(Scenario(preset("ANB"), 302.0, protocol=PROTOCOL,
                                           settings=MOVING))
        # the first two steps were not run again: one call, the last step, from their state
        assert spy.calls[2:] == [(PROTOCOL[2:], True)]
        assert planner.restarts == 1
        assert full.diagnostics["restarted_after_steps"] == 2
    with Planner(cache_path=tmp_path / "d.sqlite", executor=ThreadPoolExecutor(1),
                 solver=plain) as fresh:
        one = fresh.trajectory(Scenario(preset("ANB"), 302.0, protocol=PROTOCOL,
                                        settings=MOVING))
        assert fresh.restarts == 0 and STATES not in one.meta
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
    from dosing import drug_dose
    from dosing.drug import DrugModel
    from dosing.drug_dose import DrugDoseRequest, DrugHeatings, first_heating, plan_drug_dose

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
    # each protocol step of a drug run is its own simulate from the last one's exact state,
    # so continuing a kept prefix is the same arithmetic as running it again: bit for bit
    from dosing.drug import DrugModel, DrugRuns
    from dosing.drug_dose import DrugHeatings
    from dosing.drug_schedule import DrugScheduleRequest

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
        runs.close()
    with Planner(cache_path=tmp_path / "d.sqlite", executor=ThreadPoolExecutor(1)) as planner:
        runs = DrugRuns(planner)
        fresh = runs.run(DrugHeatings(req, runs, req.fractions).scenario([0.01, 0.03]))
        assert fresh.diagnostics["mechanics_from_step"] == 0
        runs.close()
    assert np.array_equal(kept.t, fresh.t)
    assert np.array_equal(kept.released_fraction, fresh.released_fraction)
    assert np.array_equal(kept.radius, fresh.radius)


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
        assert spy.calls == [(PROTOCOL[2:], True)] and second.restarts == 1


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
        assert spy.calls[calls:] == [(((0.05, 302.0),), True), (((0.003, 308.0),), True)]
    # the same heating run to that time from t = 0: the same delivery within the bound
    with Planner(cache_path=tmp_path / "d.sqlite", executor=ThreadPoolExecutor(1)) as fresh:
        again = fresh.trajectory(Scenario(req.gel, req.t_start, protocol=((d, 308.0),),
                                          settings=req.settings))
        # the moving grid's front band times its mesh checks by the run's own steps, so a
        # run stopped at an event and one ending at d take different steps: 1.0e-4 apart
        # (measured), inside the truth's numerical bound
        assert h.delivered(again, [d])[0] == pytest.approx(0.2, rel=TRUTH_BOUND)
