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
from dosing.runs.scenario import STOP_MARGIN, Scenario, SolverSettings, run_scenario
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


def test_one_batched_lookup_per_answer_and_none_without_a_stored_truth(
        tmp_path: Path) -> None:
    planner = Planner(cache_path=tmp_path / "c.sqlite", executor=ThreadPoolExecutor(1),
                      solver=FakeSolver())
    calls: list[int] = []
    get_many = planner.cache.get_many
    planner.cache.get_many = lambda keys, found=None: calls.append(len(keys)) or get_many(
        keys, found)
    try:
        req = DoseRequest(**FRONT, dose_fraction=0.5, dry_radius_um=50.0)
        plain = planner.dose(req)
        assert calls == []  # no run of this truth stored: no keys, no lookup
        assert plain.scenario_key == request_scenarios(req)[0].key()
        validated = planner.dose(req, validate=True)
        planner.runs._mem.clear()
        calls.clear()
        again = planner.dose(req)
        assert again.validation is not None
        assert calls == [len(request_scenarios(req))]  # one query for all the runs
        assert planner.dose(req).validation is not None and len(calls) == 1  # then held
        assert again.time == validated.time == plain.time
        other = DoseRequest(**FRONT, dose_fraction=0.5, dry_radius_um=20.0)
        calls.clear()
        assert planner.dose(other).validation is None and calls == []  # another bead
    finally:
        planner.close()


def test_a_stored_run_short_of_the_dose_is_not_read_again(tmp_path: Path) -> None:
    """A run that stopped at a smaller dose is decoded once; a larger dose asks only for
    the row's checksum until a longer run replaces it."""
    planner = Planner(cache_path=tmp_path / "c.sqlite", executor=ThreadPoolExecutor(2),
                      solver=StoppingFake())
    try:
        small = DoseRequest(**FRONT, dose_fraction=0.3, dry_radius_um=50.0)
        planner.dose(small, validate=True)
        decoded: list[str] = []
        from_npz = FullResult.from_npz

        def counting(blob, meta=None):
            decoded.append(meta["key"])
            return from_npz(blob, meta)

        FullResult.from_npz = staticmethod(counting)  # type: ignore[method-assign]
        try:
            planner.runs._mem.clear()
            large = DoseRequest(**FRONT, dose_fraction=0.8, dry_radius_um=50.0)
            first = planner.dose(large)
            n = len(decoded)
            assert n > 0 and first.validation is None  # short of 80 %: unvalidated
            for _ in range(3):
                assert planner.dose(large).validation is None
            assert len(decoded) == n  # not decoded again
            planner.dose(large, validate=True)  # longer runs replace the short ones
            assert planner.dose(large).validation is not None
        finally:
            FullResult.from_npz = from_npz  # type: ignore[method-assign]
    finally:
        planner.close()


def test_get_many_returns_stored_rows_only(tmp_path: Path) -> None:
    from dosing.runs.cache import ValidationCache

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

    from dosing.runs.cache import ValidationCache

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


def test_plain_is_asdict() -> None:
    """An answer's ``to_dict`` (``dosing.answers.plain``) is ``dataclasses.asdict``'s
    result, a copy: nested records, containers of every kind, numpy leaves."""
    from collections import namedtuple
    from dataclasses import asdict, dataclass, field

    from dosing.answers import plain

    Pair = namedtuple("Pair", "lo hi")

    @dataclass
    class Inner:
        x: float
        arr: np.ndarray = field(default_factory=lambda: np.arange(3.0))

    @dataclass
    class Outer:
        a: int
        inner: Inner
        rows: list
        t: tuple
        d: dict
        pair: Pair
        none: None = None

    o = Outer(1, Inner(np.float64(2.5)), [{"k": [1, 2.0, "s", None, True]}], (Inner(1.0),),
              {"u": {"v": (1, 2)}}, Pair(1.0, 2.0))
    got, want = plain(o), asdict(o)
    assert repr(got) == repr(want)
    assert type(got["pair"]) is Pair and type(got["t"]) is tuple
    got["rows"][0]["k"].append(9)
    got["inner"]["arr"][0] = 7.0
    assert o.rows[0]["k"] == [1, 2.0, "s", None, True] and o.inner.arr[0] == 0.0  # a copy


def _copy_rows(src: Planner, dst_path: Path) -> None:
    """Every run ``src`` stored, written to ``dst_path`` by a cache object of its own (as
    another process would)."""
    from dosing.runs.cache import ValidationCache

    with ValidationCache(dst_path) as other:
        for key in src.cache.keys():
            meta, blob = src.cache.get_raw(key)
            other.put(key, meta, blob)


def test_a_warm_answer_with_its_truth_stored_reads_no_row(tmp_path: Path) -> None:
    """Issue 35: once a front-model dose's validation runs are stored and its answer made,
    asking again reads no row (one pragma: the cache's generation) and answers the same."""
    pool = ThreadPoolExecutor(2)
    planner = Planner(cache_path=tmp_path / "c.sqlite", executor=pool, solver=FakeSolver())
    try:
        req = DoseRequest(**FRONT, dose_fraction=0.8, dry_radius_um=50.0)
        validated = planner.dose(req, validate=True)
        pool.shutdown(wait=True)  # its runs' last writes (leases let go) done
        first = planner.dose(req)
        assert first.validation is not None and first.to_dict() == validated.to_dict()
        cache = planner.cache
        calls: list[str] = []
        for name in ("get_many", "digests", "stored_runs", "get", "get_raw"):
            real = getattr(cache, name)

            def spy(*a, _name=name, _real=real, **kw):
                calls.append(_name)
                return _real(*a, **kw)

            setattr(cache, name, spy)
        sql: list[str] = []
        cache._con().set_trace_callback(sql.append)
        try:
            again = [planner.dose(req) for _ in range(3)]
            now = planner.answer(req)
        finally:
            cache._con().set_trace_callback(None)
        assert calls == []
        assert sql and all(s.strip().upper() == "PRAGMA DATA_VERSION" for s in sql)
        assert all(a.to_dict() == first.to_dict() for a in [*again, now.answer])
        again[0].validation.runs[0]["time"] = -1.0  # a caller's change stays in its answer
        assert planner.dose(req).to_dict() == first.to_dict()
    finally:
        planner.close()


def test_a_warm_answer_sees_runs_another_cache_stores(tmp_path: Path) -> None:
    """A warm answer notices rows written by another connection to its file (another
    process): a truth stored short of the dose leaves it unvalidated; the longer runs,
    replacing those rows, validate the next answer, which is the one they give."""
    runs = {}
    for name, f in (("short", 0.3), ("long", 0.8)):
        src = Planner(cache_path=tmp_path / f"{name}.sqlite", executor=ThreadPoolExecutor(2),
                      solver=StoppingFake())
        try:
            runs[name] = (src, src.dose(DoseRequest(**FRONT, dose_fraction=f,
                                                    dry_radius_um=50.0), validate=True))
        finally:
            src.close()
    path = tmp_path / "shared.sqlite"
    planner = Planner(cache_path=path, executor=ThreadPoolExecutor(1), solver=StoppingFake())
    try:
        req = DoseRequest(**FRONT, dose_fraction=0.8, dry_radius_um=50.0)
        prior = planner.dose(req)
        assert prior.validation is None and planner.dose(req).to_dict() == prior.to_dict()
        _copy_rows(runs["short"][0], path)  # the truth stored, short of 80 %
        short = planner.dose(req)
        assert short.validation is None and short.to_dict() == prior.to_dict()
        _copy_rows(runs["long"][0], path)  # longer runs replace those rows
        got = planner.dose(req)
        assert got.validation is not None
        assert got.to_dict() == runs["long"][1].to_dict()
        assert planner.dose(req).to_dict() == got.to_dict()
        # a new row for another bead: its first answer sees it too
        other = DoseRequest(**FRONT, dose_fraction=0.8, dry_radius_um=20.0)
        assert planner.dose(other).validation is None
        src = Planner(cache_path=tmp_path / "bead.sqlite", executor=ThreadPoolExecutor(2),
                      solver=StoppingFake())
        try:
            want = src.dose(other, validate=True)
        finally:
            src.close()
        _copy_rows(src, path)  # (its model-form runs, shared by the beads, rewritten too)
        got = planner.dose(other)
        assert got.validation is not None and got.validation.time == want.validation.time
        assert got.error_estimate == want.error_estimate
    finally:
        planner.close()
