"""Jobs on a pluggable executor, deduplicated by key; the same planner on Dask distributed."""

import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from dosing import DoseRequest, JobRunner, Planner, QueueFullError
from dosing.jobs import default_executor
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
    from dosing.scenario import run_scenario
    from solver.errors import BudgetExceeded, SolverError

    sc = Scenario(HHT, 304.0, 307.6, settings=SolverSettings(n=50, interfacial_length=0.0))
    with pytest.raises(SolverError, match=r"used its 0 s budget .* too stiff") as err:
        run_scenario(sc.to_dict(), budget=0.0)
    diag = err.value.diagnostics
    assert isinstance(err.value, BudgetExceeded)
    assert diag["wall_seconds"] > 0.0 and 0.0 <= diag["fraction"] < 1.0  # stopped mid-run
    meta, _ = run_scenario(sc.to_dict(), horizon=0.5)  # the default budget: 600 s
    assert meta["runs"] == 1
