"""Issue 23's answer path: memoised validation scenarios, one batched cache lookup, runs
that stop at their dose.  Speed itself is measured in benchmarks/speed.py; these check that
the shortcuts give the same answers and do what they claim."""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest
from dosing_fakes import FakeSolver

from dosing import DoseRequest, Planner
from dosing.planner import request_scenarios
from dosing.scenario import STOP_MARGIN, Scenario, SolverSettings, run_scenario
from solver import ANB
from solver.full.result import FullResult

FRONT = {"gel": "ANB", "t_start": 302.0, "t_end": 308.0}


class StoppingFake(FakeSolver):
    """The fake solver honouring ``stop``: the run ends where the radius reaches it."""

    def __init__(self) -> None:
        super().__init__()
        self.stops: list[float | None] = []

    def __call__(self, gel, t_start, t_end=None, *, stop=None, **kw) -> FullResult:
        self.stops.append(stop)
        res = super().__call__(gel, t_start, t_end, **kw)
        if stop is None or res.radius.min() > stop:
            return res
        k = int(np.argmax(res.radius <= stop))
        a3 = np.interp(stop**3, [res.radius[k] ** 3, res.radius[k - 1] ** 3],
                       [res.t[k], res.t[k - 1]])
        t = np.append(res.t[:k], a3)
        r = np.append(res.radius[:k], stop)
        a0 = res.radius[0]
        return FullResult(t=t, radius=r, front=np.full(r.size, np.nan),
                          expelled_volume=4 * math.pi / 3 * (a0**3 - r**3),
                          temperature=np.append(res.temperature[:k], res.temperature[k]),
                          diagnostics={"steps": int(t.size), "status": "stopped",
                                       "t_events": [float(t[-1])]})


def test_scenarios_are_memoised_and_equal_to_fresh_ones() -> None:
    req = DoseRequest(**FRONT, dose_fraction=0.8, dry_radius_um=50.0)
    first, again = request_scenarios(req), request_scenarios(
        DoseRequest(**FRONT, dose_fraction=0.3, dry_radius_um=50.0))
    assert first is again  # the same jump and settings: built once
    fresh = [Scenario(sc.gel, sc.t_start, sc.t_end, branch=sc.branch, settings=sc.settings)
             for sc in first]
    assert [sc.key() for sc in first] == [sc.key() for sc in fresh]
    other = request_scenarios(DoseRequest(**FRONT, dose_fraction=0.8, dry_radius_um=20.0))
    assert other is not first and other[0].key() != first[0].key()  # the bead's own ell


def test_one_batched_lookup_per_answer(tmp_path: Path) -> None:
    planner = Planner(cache_path=tmp_path / "c.sqlite", executor=ThreadPoolExecutor(1),
                      solver=FakeSolver())
    calls: list[int] = []
    get_many = planner.cache.get_many
    planner.cache.get_many = lambda keys: calls.append(len(keys)) or get_many(keys)
    try:
        req = DoseRequest(**FRONT, dose_fraction=0.5, dry_radius_um=50.0)
        planner.dose(req)
        planner.dose(req)
        assert calls == [len(request_scenarios(req))] * 2  # one query for all the runs
    finally:
        planner.close()


def test_get_many_returns_stored_rows_only(tmp_path: Path) -> None:
    from dosing.cache import ValidationCache

    with ValidationCache(tmp_path / "c.sqlite") as cache:
        cache.put("a", {"horizon": 1.0}, b"blob-a")
        cache.put("b", {"horizon": 2.0}, b"blob-b")
        got = cache.get_many(["a", "missing", "b", "a"])
        assert got == {"a": ({"horizon": 1.0}, b"blob-a"), "b": ({"horizon": 2.0}, b"blob-b")}
        assert cache.get_many([]) == {}


def test_jump_runs_stop_at_their_dose_and_protocols_do_not() -> None:
    fake = StoppingFake()
    sc = Scenario(ANB, 302.0, 308.0, settings=SolverSettings(grid="lagrangian", n=40,
                                                             interfacial_length=0.0))
    a0 = 2.2918
    need = 0.5 * (a0 + 1.47)
    meta, blob = run_scenario(sc.to_dict(), horizon=1.0, need_radius=need, solver=fake)
    traj = FullResult.from_npz(blob, meta)
    assert fake.stops == [pytest.approx(need * (1.0 - STOP_MARGIN), rel=1e-12)]
    assert traj.status == "stopped" and traj.radius.min() <= need
    assert traj.time_to_radius(need) < traj.horizon  # the dose is inside the stored run
    whole = fake.__class__.__mro__[1]()(ANB, 302.0, protocol=[(1.0, 308.0)],
                                        grid="lagrangian", n=40)
    assert traj.time_to_radius(need) == pytest.approx(whole.time_to_radius(need), rel=1e-4)
    prot = Scenario(ANB, 302.0, protocol=((0.1, 308.0), (0.1, 302.0)),
                    settings=SolverSettings(grid="lagrangian", n=40, interfacial_length=0.0))
    run_scenario(prot.to_dict(), need_radius=need, solver=fake)
    assert fake.stops[-1] is None  # a protocol runs whole


def test_a_run_stopped_before_the_front_time_is_run_on_to_it() -> None:
    """The truth's radius at the front model's time is part of the report: a run whose dose
    comes first is run again, without the event, to that time."""
    fake = StoppingFake()
    sc = Scenario(ANB, 302.0, 308.0, settings=SolverSettings(grid="lagrangian", n=40,
                                                             interfacial_length=0.0))
    need = 2.0
    meta, blob = run_scenario(sc.to_dict(), horizon=0.5, need_radius=need, need_time=0.4,
                              solver=fake)
    traj = FullResult.from_npz(blob, meta)
    assert fake.stops[0] is not None and fake.stops[-1] is None and meta["runs"] == 2
    assert traj.horizon >= 0.4 and traj.status == "finished"


def test_validated_answer_is_the_same_with_stopping_runs(tmp_path: Path) -> None:
    """A validation on the stopping fake answers as on the fake that runs whole (the dose
    time within the linear a^3 interpolation the fake's outputs allow)."""
    answers = []
    for k, solver in enumerate((FakeSolver(), StoppingFake())):
        p = Planner(cache_path=tmp_path / f"{k}.sqlite", executor=ThreadPoolExecutor(2),
                    solver=solver)
        try:
            answers.append(p.dose(DoseRequest("HHT", 304.0, 307.6, dose_fraction=0.5,
                                              dry_radius_um=50.0)))
        finally:
            p.close()
            p.jobs.executor.shutdown(wait=True)
    whole, stopped = answers
    assert stopped.model == whole.model == "full"
    assert stopped.time == pytest.approx(whole.time, rel=1e-4)
    assert stopped.error_estimate == pytest.approx(whole.error_estimate, rel=0.05, abs=1e-5)


def test_get_many_sees_every_write_after_remembering_absent_keys(tmp_path: Path) -> None:
    """Absent keys are remembered only while the file is unchanged: a write by this
    connection, by another thread's, or by another cache object (another process) shows."""
    import threading

    from dosing.cache import ValidationCache

    path = tmp_path / "c.sqlite"
    with ValidationCache(path) as cache, ValidationCache(path) as other:
        keys = ["mine", "thread", "process"]
        assert cache.get_many(keys) == {}
        assert cache.get_many(keys) == {}  # remembered, still right
        cache.put("mine", {"h": 1}, b"1")
        assert set(cache.get_many(keys)) == {"mine"}
        th = threading.Thread(target=cache.put, args=("thread", {"h": 2}, b"2"))
        th.start()
        th.join()
        assert set(cache.get_many(keys)) == {"mine", "thread"}
        other.put("process", {"h": 3}, b"3")
        assert set(cache.get_many(keys)) == {"mine", "thread", "process"}
