"""Jobs on a pluggable executor, deduplicated by key; the same planner on Dask distributed."""

import os
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from dosing import DoseRequest, JobRunner, Planner, QueueFullError, ValidationCache
from dosing.runs.jobs import BACKGROUND_NICENESS, Job, default_executor, stop_executor
from dosing.units import radius_after_dose
from solver.gel import HHT


def test_same_key_runs_once_while_unfinished() -> None:
    gate, calls = threading.Event(), []

    def work(x: int) -> int:
        calls.append(x)
        assert gate.wait(10)
        return 2 * x

    with ThreadPoolExecutor(4) as ex:
        runner = JobRunner(ex, max_pending=2)
        f1 = runner.submit("a", work, 1)
        f2 = runner.submit("a", work, 99)  # deduplicated: same future, not run
        assert f1 is f2
        runner.submit("b", work, 2)
        with pytest.raises(QueueFullError):
            runner.submit("c", work, 3)
        assert runner.state("a") in ("pending", "running") and runner.pending() == 2
        gate.set()
        assert f1.result(10) == 2
        time.sleep(0.05)
        assert runner.state("a") == "done" and runner.state("zzz") is None
        f3 = runner.submit("a", work, 5)  # finished keys run again when asked
        assert f3 is not f1 and f3.result(10) == 10
    assert sorted(calls) == [1, 2, 5]


def test_on_done_runs_before_the_future_completes_and_failures_propagate() -> None:
    stored = []
    with ThreadPoolExecutor(2) as ex:
        runner = JobRunner(ex)
        fut = runner.submit("k", lambda: 7, on_done=lambda f: stored.append(f.result()))
        assert fut.result(10) == 7 and stored == [7]
        bad = runner.submit("bad", lambda: 1 / 0)
        with pytest.raises(ZeroDivisionError):
            bad.result(10)
        assert runner.state("bad") == "failed"


def test_default_executor_is_a_spawned_process_pool() -> None:
    ex = default_executor(1)
    try:
        assert ex._mp_context.get_start_method() == "spawn"
    finally:
        ex.shutdown()


@pytest.mark.skipif(not hasattr(os, "nice"), reason="os.nice is POSIX")
def test_a_runners_own_pool_works_at_a_lower_priority() -> None:
    """The validations' pool yields the CPU to the server that owns it (docs/speed.md sec.
    6.1): its workers run BACKGROUND_NICENESS below the parent; a pool made for other
    work (``default_executor()``, the sweep's) runs at the parent's priority."""
    own = os.nice(0)
    runner = JobRunner()
    try:
        worker = runner.submit("nice", os.nice, 0).result(60)
    finally:
        runner.shutdown()
    assert BACKGROUND_NICENESS > 0 and worker == min(19, own + BACKGROUND_NICENESS)
    ex = default_executor(1)
    try:
        assert ex.submit(os.nice, 0).result(60) == own
    finally:
        stop_executor(ex)


@pytest.mark.slow  # the first full-solver call of a session may pay numba compilation
def test_planner_on_dask_distributed(tmp_path: Path) -> None:
    """Real full-solver validations on a Dask LocalCluster through Client.get_executor()."""
    distributed = pytest.importorskip("distributed")
    from dosing import SolverSettings
    from solver.full import simulate

    # a smooth jump on a coarse grid, the paper's model (two grids): under a second per run
    req = DoseRequest("HHT", 304, 307.6, dose_fraction=0.5,
                      settings=SolverSettings(n=50, interfacial_length=0.0))
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        planner = Planner(cache_path=tmp_path / "dask.sqlite", executor=client.get_executor())
        st = planner.wait_validation(planner.submit_validation(req), 120.0, 0.05)
        vid = st.id
        assert st.status == "done", st.error
        planner.close()
    target = radius_after_dose(req.start_radius, 0.5)
    direct = simulate("HHT", 304, 307.6, until=2.0, n=50).time_to_radius(target)
    assert st.result["time"] == pytest.approx(direct, rel=1e-6)
    assert st.result["grid_spread"] < 1e-3  # smooth: the grids agree
    again = Planner(cache_path=tmp_path / "dask.sqlite", executor=ThreadPoolExecutor(1))
    assert again.validation(vid).result == st.result  # persisted by the client-side callback
    again.close()
    again.jobs.executor.shutdown()


@pytest.mark.slow
def test_default_process_pool_runs_validations(tmp_path: Path) -> None:
    """The default executor: spawned worker processes; results stored by the parent."""
    from dosing import SolverSettings

    req = DoseRequest("HHT", 304, 307.6, dose_fraction=0.5,
                      settings=SolverSettings(n=50, interfacial_length=0.0))
    with Planner(cache_path=tmp_path / "pool.sqlite") as planner:
        st = planner.wait_validation(planner.submit_validation(req), 300.0)
        assert st.status == "done", st.error
        assert len(planner.cache) == 2


def test_a_run_past_its_wall_budget_fails_clearly() -> None:
    """No validation run can hang: past its budget the run stops with a SolverError that
    names the settings (the solver reports progress at least every 4096 steps)."""
    from dosing import Scenario, SolverSettings
    from dosing.runs.scenario import run_scenario
    from solver.errors import BudgetExceeded, SolverError

    sc = Scenario(HHT, 304.0, 307.6, settings=SolverSettings(n=50, interfacial_length=0.0))
    with pytest.raises(SolverError, match=r"used its 0 s budget .* too stiff") as err:
        run_scenario(sc.to_dict(), budget=0.0)
    diag = err.value.diagnostics
    assert isinstance(err.value, BudgetExceeded)
    assert diag["wall_seconds"] > 0.0 and 0.0 <= diag["fraction"] < 1.0  # stopped mid-run
    meta, _ = run_scenario(sc.to_dict(), horizon=0.5)  # the default budget: 600 s
    assert meta["runs"] == 1


# ----------------------------------------------------------------------------- issue 15

def test_a_group_is_admitted_whole_or_not_at_all() -> None:
    """D4: max_pending counts groups (validations); a group that does not fit is refused
    with nothing of it queued, and the message says what is full."""
    gate = threading.Event()
    with ThreadPoolExecutor(4) as ex:
        runner = JobRunner(ex, max_pending=1, what="validations")
        jobs = [Job(k, gate.wait, (10,)) for k in ("r1", "r2", "r3")]
        futs = runner.submit_group("v1", jobs)
        assert len(futs) == 3 and runner.pending() == 1
        with pytest.raises(QueueFullError, match=r"validations queue is full: 1 validations"):
            runner.submit_group("v2", [Job("r4", gate.wait, (10,)), Job("r5", gate.wait, (10,))])
        assert runner.state("r4") is None and runner.state("r5") is None
        again = runner.submit_group("v3", [Job("r1", gate.wait, (10,))])  # all deduplicated
        assert again[0] is futs[0]
        gate.set()
        assert all(f.result(10) for f in futs)


def _leased(path: Path, lease: float) -> tuple[ValidationCache, JobRunner, ThreadPoolExecutor]:
    cache = ValidationCache(path)
    pool = ThreadPoolExecutor(2)
    return cache, JobRunner(pool, leases=cache, lease_seconds=lease), pool


def test_a_live_holder_keeps_its_lease_and_the_other_takes_its_result(tmp_path: Path) -> None:
    """D5: two runners (two servers) on one cache: the second waits for the first's
    result (renewed lease, run 4x longer than the lease), computing nothing itself."""
    calls: list[str] = []
    store: dict[str, int] = {}

    def work(who: str) -> int:
        calls.append(who)
        time.sleep(1.2)
        return 42

    cache_a, a, pool_a = _leased(tmp_path / "c.sqlite", 0.3)
    cache_b, b, pool_b = _leased(tmp_path / "c.sqlite", 0.3)
    fetch = lambda: store.get("k")  # noqa: E731 - where the holder stores its result
    fa = a.submit("k", work, "a", on_done=lambda f: store.update(k=f.result()), fetch=fetch)
    time.sleep(0.1)
    fb = b.submit("k", work, "b", fetch=fetch)
    assert b.state("k") == "running"
    assert fa.result(10) == 42 and fb.result(10) == 42
    assert calls == ["a"]
    assert cache_a.lease("k") is None  # released once stored
    for r, p, c in ((a, pool_a, cache_a), (b, pool_b, cache_b)):
        r.shutdown()
        p.shutdown()
        c.close()


def test_an_expired_lease_is_taken_over(tmp_path: Path) -> None:
    """D5: a holder that stopped renewing (another host's crashed server) loses its lease
    when it expires; the waiting runner then computes the job itself."""
    cache, runner, pool = _leased(tmp_path / "c.sqlite", 5.0)
    assert cache.claim("k", "elsewhere:1:dead", 0.8)
    assert not cache.claim("k", runner.owner, 5.0)
    t0 = time.monotonic()
    fut = runner.submit("k", lambda: "mine", fetch=lambda: None)
    assert runner.state("k") == "running"  # someone else's, as far as we know
    assert fut.result(10) == "mine"
    assert 0.5 <= time.monotonic() - t0 < 5.0
    runner.shutdown()
    pool.shutdown()
    cache.close()


def test_a_dead_local_holder_is_taken_over_at_once(tmp_path: Path) -> None:
    """A lease whose owner is a process of this host that has ended is free at once (a
    restart after kill -9 does not wait for the expiry)."""
    import socket
    import subprocess
    import sys

    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True).stdout.strip()
    cache = ValidationCache(tmp_path / "c.sqlite")
    assert cache.claim("k", f"{socket.gethostname()}:{dead}:x", 3600.0)
    assert cache.claim("k", "me:1:y", 60.0)
    assert cache.lease("k")[0] == "me:1:y"
    cache.close()


def test_stop_executor_ends_the_pool_workers() -> None:
    """D3: the planner's own pool is stopped, its workers terminated, on close."""
    import psutil

    runner = JobRunner(max_pending=4)
    fut = runner.submit("k", time.sleep, 30.0)
    deadline = time.monotonic() + 60
    while not (procs := list(runner.executor._processes.values())) and \
            time.monotonic() < deadline:
        time.sleep(0.05)
    pids = [p.pid for p in procs]
    assert pids and all(psutil.pid_exists(p) for p in pids)
    runner.shutdown(wait=False)
    assert fut.exception(10) is not None
    assert not any(psutil.pid_exists(p) and psutil.Process(p).status() != "zombie"
                   for p in pids)


def test_default_executor_does_not_rerun_an_unguarded_script(tmp_path: Path) -> None:
    """A script with no ``if __name__ == "__main__"`` guard (as the README's code is pasted)
    runs once: the pool's spawned workers do not import it again, and it finishes."""
    import subprocess
    import sys

    script = tmp_path / "pasted.py"
    script.write_text("from dosing.runs.jobs import default_executor, stop_executor\n"
                      "print('script body ran', flush=True)\n"
                      "ex = default_executor(1)\n"
                      "print('result', ex.submit(abs, -3).result(timeout=60), flush=True)\n"
                      "stop_executor(ex)\n")
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          timeout=120, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.count("script body ran") == 1
    assert "result 3" in done.stdout


# ----------------------------------------------------------------------------- issue 40, R1/R2

def test_errors_from_a_pool_worker_come_back_and_the_pool_survives() -> None:
    """A solver error (ParameterError: picklable now) and an error that does not pickle
    (a WorkerError naming it) come back as errors; the pool is never broken by them."""
    import pool_jobs

    from dosing.runs.jobs import WorkerError
    from solver.errors import ParameterError

    runner = JobRunner(max_pending=8)
    try:
        with pytest.raises(ParameterError) as err:
            runner.submit("p", pool_jobs.bad_parameter).result(60)
        assert err.value.field == "steps[0].duration" and err.value.value == 4e7
        with pytest.raises(WorkerError, match="Unpicklable: 1/2"):
            runner.submit("l", pool_jobs.bad_local).result(60)
        assert runner.submit("ok", pool_jobs.slow, 5, 0.0).result(60) == 5
        assert runner.pool_status()["restarts"] == 0
    finally:
        runner.shutdown(wait=False)


def test_a_dead_worker_fails_its_job_only_and_the_pool_is_replaced() -> None:
    """A worker killed while it runs a job: that job fails (WorkerDied, not retried), the
    jobs queued behind it run on the replacement pool, /health's pool status counts it."""
    import pool_jobs

    from dosing.runs.jobs import WorkerDied

    runner = JobRunner(max_pending=8)
    try:
        dead = runner.submit("die", pool_jobs.die)
        queued = [runner.submit(f"q{i}", pool_jobs.slow, i) for i in range(3)]
        with pytest.raises(WorkerDied, match="died while it ran"):
            dead.result(60)
        assert [f.result(60) for f in queued] == [0, 1, 2]
        status = runner.pool_status()
        assert status["status"] == "ok" and status["restarts"] == 1
        assert runner.state("die") == "failed"
    finally:
        runner.shutdown(wait=False)


def test_a_job_past_its_hard_limit_is_killed_and_failed() -> None:
    """A job that never returns (a loop that holds the worker) is killed at the runner's
    hard limit; the job after it runs."""
    import pool_jobs

    from dosing.runs.jobs import WorkerDied

    runner = JobRunner(max_pending=8, hard_seconds=2.0)
    try:
        t0 = time.monotonic()
        stuck = runner.submit("spin", pool_jobs.spin)
        after = runner.submit("after", pool_jobs.slow, "after")
        with pytest.raises(WorkerDied, match="hard limit of 2 s"):
            stuck.result(60)
        assert time.monotonic() - t0 < 30
        assert after.result(60) == "after"
    finally:
        runner.shutdown(wait=False)


def test_a_runs_budget_covers_all_its_solver_calls(monkeypatch: pytest.MonkeyPatch) -> None:
    """run_scenario's budget (THERMOGEL_RUN_SECONDS when set) is for the whole run: a jump
    extended x4 while its radius is short of the need stops at the budget with a
    BudgetExceeded naming the settings, not after a budget per call."""
    from dosing_fakes import FakeSolver

    from dosing.runs.scenario import (
        RUN_BUDGET_S,
        Scenario,
        SolverSettings,
        hard_limit,
        run_budget,
        run_scenario,
    )
    from solver.errors import BudgetExceeded
    from solver.gel import preset

    monkeypatch.delenv("THERMOGEL_RUN_SECONDS", raising=False)
    assert run_budget() == RUN_BUDGET_S and hard_limit(RUN_BUDGET_S) == 900.0
    for bad in ("", "x", "-1", "nan", "0"):
        monkeypatch.setenv("THERMOGEL_RUN_SECONDS", bad)
        assert run_budget() == RUN_BUDGET_S
    monkeypatch.setenv("THERMOGEL_RUN_SECONDS", "0.5")
    assert run_budget() == 0.5 and hard_limit(0.5) == 60.5

    class Slow(FakeSolver):
        def __call__(self, *args, **kw):
            time.sleep(0.2)
            return super().__call__(*args, **kw)

    solver = Slow()
    sc = Scenario(preset("ANB"), 300.0, 303.0, settings=SolverSettings(grid="lagrangian",
                                                                       n=40))
    t0 = time.monotonic()
    with pytest.raises(BudgetExceeded, match=r"lagrangian grid, N = 40.*0 s budget") as err:
        run_scenario(sc.to_dict(), horizon=0.01, need_radius=1.0001, solver=solver)
    assert time.monotonic() - t0 < 2.0 and 2 <= len(solver.calls) <= 4
    assert err.value.diagnostics["scenario"]["settings"]["n"] == 40


@pytest.mark.slow
def test_a_run_that_killed_its_worker_is_not_run_again_by_a_poll(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A validation whose runs kill their worker fails (WorkerDied); polled by a planner
    started afresh on the same cache, it is failed at once, nothing run (the deaths are
    kept in the cache); asked again (submitted), it runs again."""
    import pool_jobs

    from dosing import SolverSettings

    calls = tmp_path / "calls"
    monkeypatch.setenv("THERMOGEL_TEST_CALLS", str(calls))
    req = DoseRequest("HHT", 304, 307.6, dose_fraction=0.5,
                      settings=SolverSettings(n=50, interfacial_length=0.0))
    with Planner(cache_path=tmp_path / "c.sqlite", solver=pool_jobs.dying_solver) as planner:
        vid = planner.submit_validation(req)
        st = planner.wait_validation(vid, 120.0)
        assert st.status == "failed" and "died while it ran" in st.error, st.error
        assert planner.jobs.pool_status()["restarts"] >= 1
    ran = calls.read_text().count("\n")
    assert ran == 2  # the truth and its check run, each killed its worker once
    with Planner(cache_path=tmp_path / "c.sqlite", solver=pool_jobs.dying_solver) as planner:
        st = planner.validation(vid)  # a poll after a restart
        assert st.status == "failed" and "died while it ran" in st.error, st.error
        time.sleep(1.0)
        assert calls.read_text().count("\n") == ran  # nothing ran
        assert planner.jobs.pool_status()["restarts"] == 0
        assert planner.submit_validation(req) == vid  # asked again: run again
        assert planner.wait_validation(vid, 120.0).status == "failed"
        assert calls.read_text().count("\n") == 2 * ran
