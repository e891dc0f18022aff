"""A batch under a heating protocol outside the reduced model's region
(dosing/population/curves.py): the nodes outside it run on the planner's full solver (the fake's
closed-form a(t) here, as a staircase of holds: it takes no program), the others keep the
reduced model; no planner, no full runs: refused as before.  Over HTTP such a batch is a job
(202), answered by its result."""

from __future__ import annotations

import asyncio
import json
import time
from concurrent.futures import ThreadPoolExecutor

import pytest
from dosing_fakes import FakeSolver

import dosing.planner
from api.cli import main
from dosing import DoseRequest, PhysicalConstants, Planner
from dosing.heating.response import mode_for
from dosing.population.curves import (
    BatchCurves,
    FullNodeCurve,
    OutsideRegion,
    Runs,
    batch_protocol_answer,
    converge,
)
from dosing.question import Batch, Dose, Heating, Request, plan

RAMP = ["Heat to 308 K at 5 K/min"]
# the paper's constants (tau = 2205 s at 50 um): a batch split across the region's edge
CASE = {"gel": "ANB", "t_start": 302.0, "protocol": RAMP, "dose_fraction": 0.8,
        "constants": PhysicalConstants.paper()}
OUT_UM = 50.0  # a CV 0.2 batch's beads under 50 um are outside the region (their own ell)


@pytest.fixture
def planner(fake_planner):
    return fake_planner


def _req(radius: float = OUT_UM, cv: float = 0.2) -> DoseRequest:
    return DoseRequest(**CASE, dry_radius_um=radius, size_distribution={"cv": cv})


def test_out_of_region_batch_answers_on_full_solver_nodes(planner) -> None:
    req = _req()
    with pytest.raises(OutsideRegion) as exc:  # the fast path: no planner, no runs
        batch_protocol_answer(req)
    assert exc.value.field == "size_distribution"
    b = batch_protocol_answer(req, planner=planner)
    assert b.model == "front-slow-sharp+full" and planner.fake.calls
    nodes = b.uncertainty["nodes"]
    assert nodes.full_um and max(nodes.full_um) < OUT_UM <= min(
        r for r in nodes.reduced_um if r > max(nodes.full_um))
    assert 0.0 < nodes.full_fluid_fraction < 1.0
    assert "n vs n/2 check" in b.uncertainty["numerical"].text
    assert b.uncertainty["numerical"].relative > 0.0
    assert "split at" in b.quadrature.rule and b.quadrature.nodes <= 64


def test_the_batch_time_lies_between_its_nodes_own_times(planner) -> None:
    req = _req()
    runs = Runs(planner, True, False, mode_for(planner, req))
    bc = BatchCurves(req, "kT", False, runs)
    t, _ = converge(bc)
    _, v, curves = bc.last
    own = [c.own_seconds for c in curves]
    assert min(own) < t < max(own)
    full = [c for c in curves if isinstance(c, FullNodeCurve)]
    assert full and all(c.covered >= max(own) for c in full)  # run past the largest own time
    # V(T) = f, and each full node has released exactly the dose at its own time
    assert sum(w * c.released(t) for w, c in zip(v, curves, strict=True)) == pytest.approx(
        req.fraction, abs=1e-10)
    assert all(c.released(c.own_seconds) == pytest.approx(req.fraction, abs=1e-12)
               for c in full)


def test_cv_zero_is_the_single_beads_protocol_dose(planner) -> None:
    """A 20 um bead is outside the region (its interfacial length): its batch of one size is
    the single bead's protocol dose on the same runs, exactly; a narrow batch tends to it."""
    one = planner.dose(DoseRequest(**CASE, dry_radius_um=20.0))
    b = batch_protocol_answer(_req(20.0, 0.0), planner=planner)
    assert b.model == one.model == "full"
    assert b.seconds == one.seconds and b.quadrature.nodes == 1 and b.delay == 0.0
    narrow = batch_protocol_answer(_req(20.0, 0.01), planner=planner)
    assert narrow.seconds == pytest.approx(one.seconds, rel=2e-3)


def test_from_the_cache_only(planner, tmp_path) -> None:
    req = _req()
    assert batch_protocol_answer(req, planner=planner, wait=False) is None
    assert not planner.fake.calls  # nothing run
    b = batch_protocol_answer(req, planner=planner)
    n = len(planner.fake.calls)
    again = batch_protocol_answer(req, planner=planner, wait=False)
    assert again.seconds == b.seconds and len(planner.fake.calls) == n


def test_cli_batch_outside_the_region_runs_the_full_solver(monkeypatch, capsys,
                                                           tmp_path) -> None:
    fake, real = FakeSolver(), dosing.planner.one_shot
    monkeypatch.setattr(dosing.planner, "one_shot",
                        lambda path, ex, **kw: real(path, ex, solver=fake, **kw))
    assert main(["dose", "--t-start", "302", "--protocol", RAMP[0], "--fraction", "0.8",
                 "--dry-radius-um", str(OUT_UM), "--size-cv", "0.2", "--paper-constants",
                 "--json",
                 "--cache", str(tmp_path / "c.sqlite")]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["model"] == "front-slow-sharp+full" and fake.calls
    assert got["seconds"] == got["batch"]["seconds"]



@pytest.mark.anyio
async def test_http_batch_outside_the_region_is_a_job(planner) -> None:
    from api_support import asgi

    from api.http import create_app

    body = {**CASE, "constants": {"paper": True}, "dry_radius_um": OUT_UM,
            "size_distribution": {"cv": 0.2}}
    async with asgi(create_app(planner=planner, warm=False)) as (_, raw):
        r = await raw.post("/v1/dose-time", json=body)
        assert r.status_code == 202, r.text
        url = r.json()["validation_url"]
        deadline = time.monotonic() + 60.0
        while True:
            job = (await raw.get(url)).json()
            if job["status"] in ("done", "failed") or time.monotonic() > deadline:
                break
            await asyncio.sleep(0.05)
        assert job["status"] == "done", job
        again = await raw.post("/v1/dose-time", json=body)  # now from the cache
    py = plan(Request("ANB", 302.0, Heating(RAMP), Dose(0.8), population=Batch({"cv": 0.2}),
                      dry_radius_um=OUT_UM, constants=CASE["constants"]), planner=planner)
    assert job["result"]["seconds"] == py.seconds == py.batch.seconds
    assert job["result"]["model"] == py.model == "front-slow-sharp+full"
    assert again.status_code == 200, again.text
    assert again.json()["seconds"] == py.seconds


@pytest.mark.slow
def test_real_solver_50um_batch(tmp_path) -> None:
    """ANB 302 K, 5 K/min to 308 K, 80 %, 50 um CV 0.2 on the real solver (measured: 269.5 s
    against the 226.6 s mean bead, 4 of 32 nodes and 2 percentile beads full, about 11 s
    with compiled kernels)."""
    with Planner(cache_path=tmp_path / "c.sqlite", executor=ThreadPoolExecutor(2)) as p:
        b = batch_protocol_answer(_req(), planner=p)
    assert b.model == "front-slow-sharp+full" and b.quadrature.converged
    assert b.seconds == pytest.approx(269.5, rel=2e-3)
    assert b.mean_bead_seconds == pytest.approx(226.6, rel=1e-3)
    assert b.uncertainty["numerical"].relative < 1e-3
