"""Design maps (dosing.studies.sweep): every point answered as the planner answers it alone, failing
points reported with their message, validations queued for a subset, the same table on any
executor (inline, a thread pool, a Dask LocalCluster of worker processes)."""

from __future__ import annotations

import csv
import io
import json
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
from dosing_fakes import FakeSolver

from dosing import DoseRequest, Planner
from dosing.studies.sweep import (
    COLUMNS,
    SweepGrid,
    chunks,
    fill_validations,
    run_sweep,
    vary_gel,
)
from solver.errors import ParameterError

# ANB from 302 K: 305 K is a smooth jump (full solver only), 308-310 K front jumps
GRID = {"t_ends": [305.0, 308.0, 310.0], "dry_radii_um": [20.0, 50.0],
        "doses": [0.3, 0.4, 1.2]}  # 1.2: more than the stored fluid


@pytest.fixture(scope="module")
def result():
    return run_sweep(SweepGrid(**GRID))


def test_every_point_is_the_planners_own_answer(result, tmp_path: Path) -> None:
    """A front-model row carries exactly Planner.dose's time, seconds and error estimate
    for that request (one code path, so equality is exact)."""
    answered = [r for r in result.rows if r["status"] == "answered"]
    assert len(answered) == 2 * 2 * 2  # two front T_end x two sizes x the two valid doses
    with Planner(cache_path=tmp_path / "c.sqlite", executor=ThreadPoolExecutor(1)) as p:
        for r in answered:
            ans = p.dose(DoseRequest("ANB", 302.0, r["t_end"], dose_fraction=r["dose_fraction"],
                                     dry_radius_um=r["dry_radius_um"]))
            assert (r["model"], r["time"], r["seconds"], r["error_estimate"]) == (
                ans.model, ans.time, ans.seconds, ans.error_estimate)
            assert r["final_radius_um"] == ans.final_radius_um
        p.jobs.executor.shutdown()


def test_a_failing_point_is_a_row_with_its_message(result) -> None:
    """The 1.2 doses fail with the request's own message naming dose_fraction; the smooth
    jump's points say they need the full solver; the rest of the sweep completed."""
    assert [r["index"] for r in result.rows] == list(range(18))
    bad = [r for r in result.rows if r["dose_fraction"] == 1.2]
    assert len(bad) == 6 and all(r["status"] == "error" for r in bad)
    assert all(r["field"] == "dose_fraction" and "stored fluid" in r["message"]
               and r["time"] is None for r in bad)
    full = [r for r in result.rows if r["t_end"] == 305.0 and r["dose_fraction"] < 1]
    assert full and all(r["status"] == "needs-full" and r["model"] == "full"
                        and r["behaviour"] == "smooth" for r in full)
    assert result.counts == {"needs-full": 4, "answered": 8, "error": 6}


def test_out_of_range_temperature_fails_alone() -> None:
    res = run_sweep(SweepGrid(t_ends=[400.0, 308.0], dry_radii_um=[50.0], doses=[0.8]))
    assert [r["status"] for r in res.rows] == ["error", "answered"]
    assert res.rows[0]["field"] == "t_end" and "373.15" in res.rows[0]["message"]


def test_grid_axes_are_checked() -> None:
    with pytest.raises(ParameterError) as err:
        SweepGrid(t_ends=[], dry_radii_um=[50.0], doses=[0.8])
    assert err.value.field == "t_ends"
    with pytest.raises(ParameterError) as err:
        SweepGrid(t_ends=[308.0], dry_radii_um=[50.0, float("nan")], doses=[0.8])
    assert err.value.field == "dry_radii_um[1]"
    with pytest.raises(ParameterError) as err:
        SweepGrid(t_ends=[308.0], dry_radii_um=[50.0], doses=[0.8], gels=["XYZ"])
    assert err.value.field == "gels[0]"


def test_chunks_share_a_jump() -> None:
    g = SweepGrid(t_ends=[308.0, 309.0], dry_radii_um=[10.0, 20.0, 30.0], doses=[0.2, 0.4],
                  gels=["ANB", "HHT"])
    parts = chunks(g.points(), size=4)
    assert sorted(p["index"] for c in parts for p in c) == list(range(24))
    assert all(len({(p["gel_index"], p["t_end"]) for p in c}) == 1 for c in parts)
    assert [len(c) for c in parts] == [4, 2] * 4


def test_csv_and_json_carry_units(result) -> None:
    rows = list(csv.reader(io.StringIO(result.to_csv())))
    assert rows[0][:7] == ["index [1]", "gel_index [1]", "gel", "t_start [K]", "t_end [K]",
                           "dry_radius_um [um]", "dose_fraction [1]"]
    assert "seconds [s]" in rows[0] and len(rows) == 19
    seconds = rows[0].index("seconds [s]")
    by_index = {int(r[0]): r for r in rows[1:]}
    for r in result.rows:
        cell = by_index[r["index"]][seconds]
        assert (cell == "") if r["seconds"] is None else float(cell) == r["seconds"]
    data = json.loads(result.to_json())
    assert {c["name"]: c["unit"] for c in data["columns"]} == {
        n: u for n, (u, _) in COLUMNS.items()}
    assert data["rows"] == result.rows and data["grid"]["shape"] == [1, 3, 2, 3]


def test_the_table_does_not_depend_on_the_executor(result) -> None:
    with ThreadPoolExecutor(2) as pool:
        assert run_sweep(SweepGrid(**GRID), executor=pool, chunk_size=2).rows == result.rows


def test_dask_local_cluster_returns_the_identical_table(tmp_path: Path) -> None:
    """10 x 10 x 5 through a LocalCluster of worker processes (rows pickled both ways)
    is the same table as the inline sweep, to the last bit."""
    distributed = pytest.importorskip("distributed")
    import numpy as np

    grid = SweepGrid(t_ends=np.linspace(307.5, 311.5, 10), dry_radii_um=np.geomspace(10, 200, 10),
                     doses=[0.1, 0.3, 0.5, 0.7, 0.9])
    inline = run_sweep(grid)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        planner = Planner(executor=client.get_executor(), cache_path=tmp_path / "c.sqlite")
        try:
            on_dask = run_sweep(grid, executor=planner.jobs.executor, planner=planner)
        finally:
            planner.close()
        ran = client.run(lambda: "dosing.studies.sweep" in sys.modules)  # in the worker process
        assert list(ran.values()) == [True]
    assert len(on_dask.rows) == 500 and on_dask.counts == inline.counts
    assert on_dask.rows == inline.rows


def test_validations_are_queued_for_the_chosen_points(tmp_path: Path) -> None:
    """'needs-full' queues a validation per smooth point (on the fake full solver); the ids
    are the planner's, so /v1/validations/{id} polls them."""
    pool = ThreadPoolExecutor(1)
    with Planner(cache_path=tmp_path / "c.sqlite", executor=pool, solver=FakeSolver()) as p:
        res = run_sweep(SweepGrid(t_ends=[305.0, 308.0], dry_radii_um=[50.0], doses=[0.2, 0.4]),
                        executor=p.jobs.executor, planner=p,
                        validate="needs-full")
        ids = [r["validation_id"] for r in res.rows]
        assert ids[:2] != [None, None] and ids[2:] == [None, None]
        for vid in ids[:2]:
            assert p.wait_validation(vid, 30.0, 0.02).status == "done"
        assert fill_validations(res, p) == 0
        req = DoseRequest("ANB", 302.0, 305.0, dose_fraction=0.2, dry_radius_um=50.0)
        ans = p.dose(req)  # now answered from the cache: the same time as the filled row
        row = res.rows[0]
        assert (row["validation_status"], row["time"], row["seconds"], row["error_estimate"]) \
            == ("done", ans.time, ans.seconds, ans.error_estimate)
        with pytest.raises(ParameterError):
            run_sweep(SweepGrid(t_ends=[308.0], dry_radii_um=[50.0], doses=[0.3]), planner=p,
                      validate=[5])
    pool.shutdown()
    with pytest.raises(ParameterError) as err:
        run_sweep(SweepGrid(t_ends=[308.0], dry_radii_um=[50.0], doses=[0.3]), validate="all")
    assert err.value.field == "validate"


def test_a_failing_executor_chunk_is_reported_not_raised() -> None:
    """A chunk the executor loses (here: a worker raising) becomes error rows naming the
    executor's failure; the other chunks' rows are complete."""
    from concurrent.futures import Future

    class Flaky(ThreadPoolExecutor):
        def submit(self, fn, part, *a):
            if part[0]["t_end"] == 309.0:
                fut: Future = Future()
                fut.set_exception(OSError("worker lost"))
                return fut
            return super().submit(fn, part, *a)

    with Flaky(1) as pool:
        res = run_sweep(SweepGrid(t_ends=[308.0, 309.0], dry_radii_um=[50.0], doses=[0.3, 0.5]),
                        executor=pool)
    assert [r["status"] for r in res.rows] == ["answered", "answered", "error", "error"]
    msg = res.rows[2]["message"]
    assert "worker lost" in msg and "OSError" not in msg  # plain words (issue 40, R9)


def test_gel_parameters_are_an_axis() -> None:
    """vary_gel: the product of parameter axes, each gel named by its values; a sweep over
    them answers each gel as the planner answers that gel alone."""
    from dosing.model_choice import front_time
    from dosing.units import radius_after_dose
    from solver.gel import ANB

    gels = vary_gel("ANB", omega=[50.0, 200.0], b1=[-0.0569, -0.057])
    assert [g.name for g in gels] == ["ANB omega=50 b1=-0.0569", "ANB omega=50 b1=-0.057",
                                      "ANB omega=200 b1=-0.0569", "ANB omega=200 b1=-0.057"]
    assert (gels[3].omega, gels[3].b1, gels[3].a0) == (200.0, -0.057, ANB.a0)
    res = run_sweep(SweepGrid(t_ends=[308.0], dry_radii_um=[50.0], doses=[0.5], gels=gels))
    assert [r["gel_index"] for r in res.rows] == [0, 1, 2, 3]
    for gel, row in zip(gels, res.rows, strict=True):
        req = DoseRequest(gel, 302.0, 308.0, dose_fraction=0.5)
        assert row["time"] == front_time(req, radius_after_dose(req.start_radius, 0.5))
    with pytest.raises(ParameterError) as err:
        vary_gel("ANB", chi=[1.0])
    assert err.value.field == "vary"
    with pytest.raises(ParameterError) as err:
        vary_gel("ANB", omega=[-1.0])
    assert err.value.field == "vary.omega"
