"""Design-map routes and the page's routes through httpx's ASGI transport (issue 17).

The sweep job returns the same table as ``dosing.studies.sweep.run_sweep`` (JSON with units, CSV),
reports failing points as rows, queues validations on the planner (fake full solver);
``/v1/front-curve`` is the planner's own front trajectory; the page and its assets are
served from the package.
"""

from __future__ import annotations

import asyncio
import csv
import io
import time

import httpx
import pytest
from api_support import asgi, fake_full_solver, fake_planner, fake_server

from api.http import create_app
from dosing.model_choice import front_run
from dosing.request import resolve_jump
from dosing.studies.sweep import SweepGrid, run_sweep
from solver.gel import preset

pytestmark = pytest.mark.anyio

SWEEP = {"t_start": 302.0, "t_ends": [305.0, 308.0, 310.0], "dry_radii_um": [20.0, 50.0],
         "doses": [0.3, 0.8]}



@pytest.fixture
async def raw(tmp_path):
    with fake_full_solver(delay=0.01) as fake, fake_planner(tmp_path / "c.sqlite", fake) as planner:
        app = create_app(planner=planner, warm=False)
        async with asgi(app) as (_, client):
            yield client
        sweeps = getattr(app.state, "sweeps", None)
        if sweeps is not None:  # drain the sweep thread while the fake solver is in place
            sweeps.runner.executor.shutdown(wait=True)


async def _done(raw, url: str, timeout: float = 30.0) -> dict:
    deadline = time.monotonic() + timeout
    while True:
        out = (await raw.get(url)).json()
        if out["status"] in ("done", "failed") and not out.get("validations_unfinished"):
            return out
        assert time.monotonic() < deadline, out
        await asyncio.sleep(0.05)


async def test_sweep_job_returns_the_table(raw) -> None:
    r = await raw.post("/v1/sweep", json=SWEEP)
    assert r.status_code == 202 and r.headers["location"] == r.json()["sweep_url"]
    assert r.json()["points"] == 12
    out = await _done(raw, r.headers["location"])
    assert out["status"] == "done" and out["points_done"] == 12
    want = run_sweep(SweepGrid(t_ends=SWEEP["t_ends"], dry_radii_um=SWEEP["dry_radii_um"],
                               doses=SWEEP["doses"]))
    table = out["result"]
    assert table["rows"] == want.rows and table["counts"] == want.counts
    assert {c["name"]: c["unit"] for c in table["columns"]}["seconds"] == "s"
    # 80 % at 305 K is more than the gel can expel there: a row with its message
    bad = [x for x in table["rows"] if x["status"] == "error"]
    assert [(x["t_end"], x["dose_fraction"], x["field"]) for x in bad] == [
        (305.0, 0.8, "dose_fraction")] * 2
    again = await raw.post("/v1/sweep", json=SWEEP)  # the same sweep: the same job
    assert again.json()["sweep_id"] == r.json()["sweep_id"]
    text = (await raw.get(r.headers["location"], params={"format": "csv"})).text
    rows = list(csv.DictReader(io.StringIO(text)))
    assert [float(x["seconds [s]"]) if x["seconds [s]"] else None for x in rows] == \
        [x["seconds"] for x in want.rows]
    svg = await raw.get(f"{r.headers['location']}/plot.svg")
    assert svg.headers["content-type"] == "image/svg+xml" and b"<svg" in svg.content[:400]


async def test_sweep_queues_validations_for_the_subset(raw) -> None:
    body = {**SWEEP, "t_ends": [305.0, 308.0], "doses": [0.3], "validate": "needs-full"}
    r = await raw.post("/v1/sweep", json=body)
    out = await _done(raw, r.json()["sweep_url"])
    rows = out["result"]["rows"]
    full = [x for x in rows if x["t_end"] == 305.0]
    assert all(x["validation_id"] and x["validation_status"] == "done"
               and x["time"] is not None for x in full)
    assert all(x["validation_id"] is None for x in rows if x["t_end"] == 308.0)
    v = (await raw.get(f"/v1/validations/{full[0]['validation_id']}")).json()
    assert v["status"] == "done" and v["result"]["time"] == full[0]["truth_time"]


async def test_sweep_input_errors_name_the_field(raw) -> None:
    r = await raw.post("/v1/sweep", json={**SWEEP, "t_ends": [305.0, 400.0]})
    assert r.status_code == 422 and r.json()["detail"][0]["loc"] == ["body", "t_ends", 1]
    big = {**SWEEP, "t_ends": [308.0] * 200, "dry_radii_um": [50.0] * 200}
    r = await raw.post("/v1/sweep", json=big)
    assert r.status_code == 422 and "at most 20000 points" in r.json()["detail"][0]["msg"]
    assert (await raw.get("/v1/sweeps/sweep-nope")).status_code == 404


async def test_front_curve_is_the_planners_trajectory(raw) -> None:
    r = await raw.post("/v1/front-curve", json={"gel": "ANB", "t_start": 302, "t_end": 308})
    assert r.status_code == 200
    out = r.json()
    fr = front_run(preset("ANB"), 302.0, 308.0, "swollen", True)
    assert out["model"] == "front-sharp" and out["t"] == fr.t.tolist()
    assert out["radius"] == fr.radius.tolist() and out["front"] == fr.front.tolist()
    jump = resolve_jump(preset("ANB"), 302.0, 308.0, None)
    assert (out["start_radius"], out["final_radius"]) == (jump.start_radius, jump.final_radius)
    paper = (await raw.post("/v1/front-curve", json={"gel": "ANB", "t_start": 302,
                                                     "t_end": 308, "interfacial_length": 0,
                                                     "n": 11})).json()
    assert paper["model"] == "front" and len(paper["t"]) == 11
    smooth = await raw.post("/v1/front-curve", json={"gel": "ANB", "t_start": 302,
                                                     "t_end": 305})
    assert smooth.status_code == 422
    assert smooth.json()["detail"][0]["loc"] == ["body", "t_end"]
    assert "smooth" in smooth.json()["detail"][0]["msg"]


async def test_page_and_assets_are_served(raw) -> None:
    page = await raw.get("/")
    assert page.status_code == 200 and "text/html" in page.headers["content-type"]
    assert '<script src="/static/app.js">' in page.text
    js = await raw.get("/static/app.js")
    assert js.status_code == 200 and "openapi.json" in js.text
    assert (await raw.get("/static/app.css")).headers["content-type"].startswith("text/css")
    assert (await raw.get("/static/../http.py")).status_code == 404
    assert (await raw.get("/static/index.py")).status_code == 404
    svg = await raw.get("/v1/phase-map.svg", params={"base": "HHT", "t_start": 304,
                                                     "t_end": 308})
    assert svg.status_code == 200 and svg.headers["content-type"] == "image/svg+xml"
    custom = await raw.get("/v1/phase-map.svg", params={"base": "ANB", "omega": 120})
    assert custom.status_code == 200 and custom.content != (await raw.get(
        "/v1/phase-map.svg", params={"base": "ANB"})).content
    bad = await raw.get("/v1/phase-map.svg", params={"t_end": 400})
    assert bad.status_code == 422 and bad.json()["detail"][0]["loc"] == ["query", "t_end"]
    bad = await raw.get("/v1/phase-map.svg", params={"omega": -1})
    assert bad.status_code == 422 and bad.json()["detail"][0]["loc"] == ["query", "omega"]


def _poll(c: httpx.Client, url: str, timeout: float = 120.0) -> dict:
    deadline = time.monotonic() + timeout
    while True:
        out = c.get(url).json()
        if out["status"] in ("done", "failed") and not out.get("validations_unfinished"):
            return out
        assert time.monotonic() < deadline, out
        time.sleep(0.1)


@pytest.mark.slow
def test_a_finished_sweep_survives_kill_and_restart(tmp_path) -> None:
    """Sweeps are stored jobs: a finished sweep is answered, unchanged and without running
    again, by a server restarted on the same cache after a kill -9 (the schedule jobs'
    test, tests/test_api_hardening.py), on its own route and on GET /v1/jobs/{id}."""
    cache = tmp_path / "c.sqlite"
    body = {**SWEEP, "validate": [0]}
    with fake_server(cache, 0.05) as (url, _), httpx.Client(base_url=url, timeout=60) as c:
        r = c.post("/v1/sweep", json=body)
        assert r.status_code == 202, r.text
        sid = r.json()["sweep_id"]
        table = _poll(c, f"/v1/jobs/{sid}")
        assert table["status"] == "done" and sum(table["result"]["counts"].values()) == 12
    # SIGKILLed on leaving the block
    with fake_server(cache, 0.05) as (url, _), httpx.Client(base_url=url, timeout=60) as c:
        again = c.get(f"/v1/sweeps/{sid}").json()
        assert again["status"] == "done" and again["points_done"] == again["points"] == 12
        assert again["result"]["rows"] == table["result"]["rows"]
        assert c.get(f"/v1/jobs/{sid}").json()["result"]["rows"] == table["result"]["rows"]
        assert c.post("/v1/sweep", json=body).json()["sweep_id"] == sid


async def test_only_the_last_sweeps_are_kept(raw, monkeypatch: pytest.MonkeyPatch) -> None:
    """Rendered tables are bounded in memory (SWEEPS_KEPT); the tables themselves are stored
    jobs, so a sweep whose rendering was dropped is read back from the store, and posting it
    again is the same job with the same table."""
    import api.routers.sweep as routes

    monkeypatch.setattr(routes, "SWEEPS_KEPT", 1)
    one = {**SWEEP, "doses": [0.3]}
    first = (await raw.post("/v1/sweep", json=one)).json()["sweep_url"]
    table = await _done(raw, first)
    assert table["status"] == "done"
    second = (await raw.post("/v1/sweep", json={**one, "doses": [0.4]})).json()["sweep_url"]
    assert (await _done(raw, second))["status"] == "done"
    kept = raw._transport.app.state.sweeps.rendered  # the ASGI transport's app
    assert {k[0] for k in kept} == {second.rsplit("/", 1)[1]}
    assert (await raw.get(first)).json()["result"]["rows"] == table["result"]["rows"]
    again = (await raw.post("/v1/sweep", json=one)).json()["sweep_url"]
    assert again == first and (await _done(raw, first))["result"]["counts"] == {
        "needs-full": 2, "answered": 4}


async def test_one_poll_route_for_every_kind_of_job(raw) -> None:
    """GET /v1/jobs/{id} answers for a sweep with the body of its own route, and a 404
    names the kind of job the id claims and the path parameter."""
    r = await raw.post("/v1/sweep", json=SWEEP)
    sid = r.json()["sweep_id"]
    own = await _done(raw, r.headers["location"])
    via_jobs = (await raw.get(f"/v1/jobs/{sid}")).json()
    assert via_jobs["status"] == "done" and via_jobs["result"]["rows"] == own["result"]["rows"]
    for jid, kind in (("sweep-0000", "sweep"), ("fit-swelling-00", "fit"),
                      ("schedule-00", "schedule"), ("abc123", "validation")):
        miss = await raw.get(f"/v1/jobs/{jid}")
        assert miss.status_code == 404
        detail = miss.json()["detail"][0]
        assert detail["loc"] == ["path", "job_id"] and f"no {kind}" in detail["msg"], detail
    miss = await raw.get("/v1/sweeps/sweep-0000")
    assert miss.json()["detail"][0]["loc"] == ["path", "sweep_id"]
    assert "no sweep job" in miss.json()["detail"][0]["msg"]
