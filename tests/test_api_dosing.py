"""Dose-time, schedule and validation routes through httpx's ASGI transport (issue 6).

The planner is the real ``dosing.Planner`` on a fresh SQLite cache; its full-solver jobs
run the dosing tests' closed-form fake solver (milliseconds) so that the queueing,
deduplication, persistence and 429 paths are exercised without minutes of PDE solves.
The front-model numbers are the planner's own (the service adds no physics).
"""

from __future__ import annotations

import asyncio
import time

import pytest
from api_support import asgi, fake_full_solver, fake_planner

from api.client import ApiError
from api.http import create_app
from dosing import DoseRequest, Planner
from dosing.runs.scenario import LADDER
from dosing.units import radius_after_dose

pytestmark = pytest.mark.anyio

FRONT = {"gel": "ANB", "t_start": 302.0, "t_end": 308.0, "dose_fraction": 0.8,
         "dry_radius_um": 50.0}
SMOOTH = {"gel": "ANB", "t_start": 300.0, "t_end": 303.0, "dose_fraction": 0.2}
LFRONT = {**FRONT, "validation_method": "ladder"}  # issue 8's truth (the ladder's defaults)
LSMOOTH = {**SMOOTH, "validation_method": "ladder"}



@pytest.fixture
def fake():
    with fake_full_solver(delay=0.05) as f:
        yield f


@pytest.fixture
def planner(tmp_path, fake):
    with fake_planner(tmp_path / "cache.sqlite", fake, max_pending=8) as p:
        yield p


@pytest.fixture
async def clients(planner):
    async with asgi(create_app(planner=planner, warm=False)) as pair:
        yield pair


async def _wait_done(api, vid: str, timeout: float = 30.0):
    deadline = time.monotonic() + timeout
    while True:
        v = await api.validation(vid)
        if v.status in ("done", "failed") or time.monotonic() > deadline:
            return v
        await asyncio.sleep(0.05)


async def test_front_dose_answers_at_once(clients, planner) -> None:
    api, raw = clients
    r = await raw.post("/v1/dose-time", json=LFRONT)
    assert r.status_code == 200
    ans = await api.dose_time(LFRONT)
    want = planner.dose(DoseRequest(**FRONT, settings=LADDER))
    assert ans.status == "answered" and ans.model == "front-sharp" and ans.behaviour == "front"
    assert ans.time == want.time and ans.seconds == want.seconds
    assert ans.interfacial_length == 0.005 and ans.truth == want.truth
    paper = await api.dose_time({**LFRONT, "interfacial_length": 0.0})
    assert paper.model == "front" and paper.time > ans.time  # the paper's model: slower
    # issue 5: 80 % of ANB's stored fluid leaves a^3 = 0.2 a0^3 + 0.8: radius 2.29 -> 1.47
    assert ans.start_radius == pytest.approx(2.2924, abs=5e-4)
    assert ans.final_radius == pytest.approx(1.475, abs=5e-3)
    assert ans.seconds == pytest.approx(ans.time * ans.timescale_seconds, rel=1e-12)
    assert ans.final_radius_um == pytest.approx(50.0 * ans.final_radius, rel=1e-12)
    assert "tau =" in ans.timescale_formula and ans.validation is None


async def test_validate_queues_and_reports_front_errors(clients) -> None:
    api, _ = clients
    ans = await api.dose_time(LFRONT, validate=True)
    assert ans.status == "answered" and ans.validation_id
    assert ans.validation_url == f"/v1/validations/{ans.validation_id}"
    v = await _wait_done(api, ans.validation_id)
    assert v.status == "done", v.error
    res = v.result
    assert [e["interfacial_length"] for e in res["runs"]] == [0.005, 0.0025, 0.00125]
    assert res["limit"]["order"] == pytest.approx(1.5, abs=0.01)  # the fake's t(ell)
    # the front model's error is measured against the (fake) full trajectory's time
    assert res["front_time_error"] == pytest.approx(
        (ans.time - res["time"]) / res["time"], rel=1e-9)
    assert res["front_volume_error"] is not None
    again = await api.dose_time(LFRONT)  # the verdict is now served with the answer
    assert again.validation is not None and again.validation.time == res["time"]


async def test_full_scenario_is_202_then_answered_from_cache(clients, fake) -> None:
    api, raw = clients
    r1 = await raw.post("/v1/dose-time", json=LSMOOTH)
    r2 = await raw.post("/v1/dose-time", json=LSMOOTH)
    assert (r1.status_code, r2.status_code) == (202, 202)
    vid = r1.json()["validation_id"]
    assert r2.json()["validation_id"] == vid  # deduplicated by scenario
    assert r1.headers["location"] == f"/v1/validations/{vid}"
    v = await _wait_done(api, vid)
    assert v.status == "done" and v.result["time"] > 0
    assert sorted(c["n"] for c in fake.calls) == [800, 1600, 3200]  # one run per rung
    ans = await api.dose_time(LSMOOTH)
    assert ans.status == "answered" and ans.model == "full"
    req = DoseRequest(**SMOOTH, settings=LADDER)
    assert ans.final_radius == pytest.approx(radius_after_dose(req.start_radius, 0.2), rel=1e-12)
    assert ans.time == pytest.approx(v.result["time"], rel=1e-12)


@pytest.mark.parametrize(("body", "field"), [
    ({**FRONT, "dose_fraction": 1.5}, "dose_fraction"),                     # above the fluid
    ({**FRONT, "dose_fraction": 0.99}, "dose_fraction"),                    # above what leaves
    ({**FRONT, "dose_fraction": None, "dose_volume_ul": 1.0}, "dose_volume_ul"),
    ({**FRONT, "dose_fraction": None, "drug_mass_ug": 1.0}, "concentration_ug_per_ul"),
    ({**FRONT, "t_start": 308.0, "t_end": 302.0}, "t_end"),                 # swelling jump
    ({**FRONT, "t_end": 380.0}, "t_end"),
    ({**FRONT, "dose_fraction": None}, "dose_fraction"),
    ({**FRONT, "dry_radius_um": -5.0}, "dry_radius_um"),
    ({**FRONT, "dry_radius_um": "big"}, "dry_radius_um"),
    ({**FRONT, "constants": {"viscosity_pa_s": "honey"}}, "constants.viscosity_pa_s"),
    ({**FRONT, "swollen_radius_um": 100.0}, "swollen_radius_um"),           # two sizes
    ({**FRONT, "interfacial_length": 0.001, "validation_method": "ladder"},
     "interfacial_length"),                                                 # ladder too fine
    ({**FRONT, "interfacial_length": 0.5}, "interfacial_length"),
])
async def test_bad_dose_is_422_naming_the_field(clients, body, field) -> None:
    api, raw = clients
    r = await raw.post("/v1/dose-time", json={k: v for k, v in body.items() if v is not None})
    assert r.status_code == 422, r.text
    with pytest.raises(ApiError) as err:
        await api.dose_time(body)
    assert any(f == field or f.startswith(field + ".") for f in err.value.fields), err.value


async def test_unknown_validation_is_404(clients) -> None:
    _, raw = clients
    for vid in ("nope", "schedule-nope"):
        r = await raw.get(f"/v1/validations/{vid}")
        assert r.status_code == 404 and r.json()["detail"][0]["loc"] == ["path", "validation_id"]


async def test_full_queue_is_429_with_retry_after(tmp_path) -> None:
    """max_pending counts validations (issue 15, D4: it counted solver runs, so a
    three-run validation could be admitted in part): one validation, all three of its
    runs, fills a queue of one; the next is refused whole, naming what is full."""
    with fake_full_solver(delay=1.0) as fake, \
            fake_planner(tmp_path / "c.sqlite", fake, max_pending=1) as planner:
        async with asgi(create_app(planner=planner, warm=False)) as (_, raw):
            r1 = await raw.post("/v1/dose-time", json=SMOOTH)  # three rungs: the queue is full
            r2 = await raw.post("/v1/dose-time", json={**SMOOTH, "t_start": 300.5})
            assert r1.status_code == 202
            assert r2.status_code == 429 and int(r2.headers["retry-after"]) >= 1
            assert "validations queue is full" in r2.json()["detail"]
            assert "(at most 1)" in r2.json()["detail"]
            r3 = await raw.post("/v1/dose-time", json=SMOOTH)  # the same scenario: deduplicated
            assert r3.status_code == 202
            assert planner.jobs.pending() == 1
            v = await raw.get(r1.json()["validation_url"])
            assert v.status_code == 200
            # the refused validation left nothing queued behind
            assert all(planner.jobs.state(sc.key()) is None for sc in planner.scenarios(
                DoseRequest(**{**SMOOTH, "t_start": 300.5})))


async def test_blocking_work_never_blocks_the_event_loop(tmp_path, fake) -> None:
    class SlowPlanner(Planner):
        def answer(self, req, validate=False):  # the service's one planner call per dose
            time.sleep(1.5)
            return super().answer(req, validate)

    with fake_planner(tmp_path / "c.sqlite", fake, cls=SlowPlanner) as planner:
        async with asgi(create_app(planner=planner, warm=False)) as (api, _):
            slow = asyncio.create_task(api.dose_time(FRONT))
            await asyncio.sleep(0.1)
            t0 = time.perf_counter()
            assert (await api.health()).status == "ok"
            assert time.perf_counter() - t0 < 0.7
            assert not slow.done()
            assert (await slow).model == "front-sharp"


async def test_schedule_hold_then_checked_job(clients) -> None:
    api, raw = clients
    body = {"gel": "ANB", "t_start": 302.0, "t_end": 308.0, "doses": [0.3, 0.3, 0.3],
            "rests": [0.5, 0.5], "dry_radius_um": 50.0}
    out = await api.schedule({**body, "check_protocol": False, "correct": False})
    assert out.status == "answered" and len(out.hold) == 3
    cum = [await api.dose_time(gel="ANB", t_start=302.0, t_end=308.0, dose_fraction=f)
           for f in (0.3, 0.6, 0.9)]
    assert [row["end"] for row in out.hold] == pytest.approx([a.time for a in cum], rel=1e-12)
    # the protocol check and the correction are the default, as in Python and the CLI; the
    # 202 carries the hold reading as the rough reading it is
    r = await raw.post("/v1/schedule", json=body)
    assert r.status_code == 202
    assert [row["end"] for row in r.json()["hold"]] == [row["end"] for row in out.hold]
    assert "rough" in r.json()["note"]
    v = await _wait_done(api, r.json()["validation_id"])
    assert v.status == "done" and v.kind == "schedule", v.error
    got = v.result["corrected"]
    assert got is not None and v.result["protocol_check"] is not None
    bad = await raw.post("/v1/schedule", json={**body, "doses": [0.5, 0.5], "rests": [0.1]})
    assert bad.status_code == 422 and bad.json()["detail"][0]["loc"][:2] == ["body", "doses"]


class PlannerSpy:
    """Wraps the planner and records every public call the service makes on it (the
    planner's own calls on itself do not go through the spy)."""

    def __init__(self, planner: Planner) -> None:
        self._planner = planner
        self.calls: list[str] = []

    def __getattr__(self, name: str) -> object:
        attr = getattr(self._planner, name)
        if name.startswith("_") or not callable(attr):
            return attr

        def call(*args: object, **kwargs: object) -> object:
            self.calls.append(name)
            return attr(*args, **kwargs)
        return call


async def test_the_service_calls_the_planner_once_per_request(planner) -> None:
    """Issue 16: one planner call per POST /v1/dose-time (answered, 202, answered from the
    cache, answered with a validation queued) and per quick POST /v1/schedule."""
    spy = PlannerSpy(planner)
    async with asgi(create_app(planner=spy, warm=False)) as (api, raw):
        calls = []
        for body in (FRONT, LSMOOTH, {**FRONT, "validate_full": True}):
            spy.calls.clear()
            r = await raw.post("/v1/dose-time", json=body)
            # the envelope's delayed-law lattice run (issue 36) is run here once and stored
            calls.append((r.status_code, [c for c in spy.calls if c != "run_here"]))
        assert calls == [(200, ["answer"]), (202, ["answer"]), (200, ["answer"])]
        vid = (await raw.post("/v1/dose-time", json=LSMOOTH)).json()["validation_id"]
        assert (await _wait_done(api, vid)).status == "done"
        spy.calls.clear()
        r = await raw.post("/v1/dose-time", json=LSMOOTH)  # now from the cache
        calls = [c for c in spy.calls if c != "run_here"]  # the envelope's lattice run
        assert (r.status_code, r.json()["model"], calls) == (200, "full", ["answer"])
        spy.calls.clear()
        r = await raw.post("/v1/schedule", json={"gel": "ANB", "t_start": 302.0,
                                                 "t_end": 308.0, "doses": [0.3, 0.3],
                                                 "check_protocol": False, "correct": False})
        calls = [c for c in spy.calls if c != "run_here"]  # the envelope's lattice run
        assert (r.status_code, calls) == (200, ["schedule_now"])
