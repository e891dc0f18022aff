"""The client has a method per route and every JSON answer carries its provenance
(issue 37).

* ``api.client.ROUTES`` (the table the client's methods are written from) is compared with
  ``/openapi.json``: a route the service gains or loses fails here until the table follows.
* Every route is called through the client (on the ASGI app, the fake full solver): each
  JSON answer comes back as its documented model and carries ``request`` (the resolved
  request, with units) and ``version``; CSV and SVG come back as text and bytes.
* Against a live ``thermogel serve`` capped at one connection per client, a call answered
  429 with ``Retry-After`` waits that long and then is answered; a bounded wait raises.
"""

from __future__ import annotations

import asyncio
import socket
import threading
import time
from pathlib import Path

import httpx
import pytest
from api_support import asgi, fake_full_solver, fake_planner, serve_process
from pydantic import BaseModel

from api import client as api_client
from api.client import ROUTES, ApiError, Client
from api.http import create_app

SENSITIVITY = {"vary": [{"name": "dry_radius_um", "low": 40.0, "high": 60.0}],
               "method": "morris", "samples": 4}



def _spec() -> dict:
    app = create_app(cache_path=None, warm=False)
    return app.openapi()


def test_the_client_has_a_method_per_route_of_the_spec() -> None:
    spec = _spec()
    served = {(m.upper(), p) for p, ops in spec["paths"].items() for m in ops}
    table = {(r.method, r.path) for r in ROUTES}
    assert table == served, (served - table, table - served)
    assert len(ROUTES) == len(served) == len({r.name for r in ROUTES})
    for route in ROUTES:
        method = getattr(Client, route.name)
        assert f"{route.method} {route.path}" in method.__doc__
        op = spec["paths"][route.path][route.method.lower()]
        assert ("requestBody" in op) == (route.body is not None), route.name
        ok = op["responses"].get("200") or op["responses"].get("202")
        media = set(ok.get("content", {}))
        assert (route.media is None) == ("application/json" in media), route.name
        for ref in (*route.answers, *(r for r in [route.accepted] if r)):
            model = api_client._model(ref)  # a model, or a union of models (jobs)
            assert isinstance(model, type) and issubclass(model, BaseModel) or \
                all(issubclass(m, BaseModel) for m in _members(model)), ref


def _members(union: object) -> list[type]:
    out = []
    for arg in getattr(union, "__args__", ()):
        out += _members(arg) if getattr(arg, "__args__", None) else [arg]
    meta = getattr(union, "__origin__", None)
    if meta is not None and not out:
        out += _members(meta)
    return [m for m in out if isinstance(m, type)]


def _examples(spec: dict) -> dict[str, dict]:
    bodies = {}
    for path, ops in spec["paths"].items():
        body = ops.get("post", {}).get("requestBody")
        if body:
            ref = body["content"]["application/json"]["schema"]["$ref"].rsplit("/", 1)[-1]
            examples = spec["components"]["schemas"][ref].get("examples")
            bodies[path] = examples[0] if examples else None
    bodies["/v1/sensitivity"] = SENSITIVITY
    return bodies


def _stamped(answer: BaseModel, route: str) -> None:
    extra = answer.model_dump()
    assert isinstance(extra.get("request"), dict) and "units" in extra["request"], route
    version = extra.get("version")
    assert version, route
    if route != "health":  # /health's own version field is the package version (a string)
        assert {"package", "code", "solver"} <= set(version), route


@pytest.mark.anyio
async def test_every_route_answers_its_model_with_request_and_version(tmp_path: Path) -> None:
    spec = _spec()
    bodies = _examples(spec)
    called: set[str] = set()
    with fake_full_solver() as fake, fake_planner(tmp_path / "c.sqlite", fake) as planner:
        async with asgi(create_app(planner=planner, warm=False)) as (api, _):
            async def call(name: str, *args, **kw):
                called.add(name)
                return await getattr(api, name)(*args, **kw)

            for name in ("health", "gels"):
                _stamped(await call(name), name)
            answers = {}
            for route in ROUTES:
                if route.body and route.path in bodies and route.name not in (
                        "schedule", "fit_release", "sweep"):
                    ans = answers[route.name] = await call(route.name, bodies[route.path])
                    _stamped(ans, route.name)
            if "design_heating" in answers:  # a design job's poll (issue 39)
                _stamped(await call("design_job", answers["design_heating"].id), "design_job")
            dose = await call("dose_time", bodies["/v1/dose-time"])
            assert dose.request["units"]["t_start"] == "K"
            assert dose.request["units"]["heating.t_end"] == "K"
            hold = await call("schedule", {**bodies["/v1/schedule"], "check_protocol": False,
                                           "correct": False})
            _stamped(hold, "schedule")
            job = await call("schedule", bodies["/v1/schedule"])
            assert job.validation_id.startswith("schedule-")
            _stamped(job, "schedule (202)")
            release = await call("fit_release", {**bodies["/v1/fit/release"], "solver_n": 40})
            _stamped(release, "fit_release")
            _stamped(await call("fit_job", release.id), "fit_job")
            fits = await call("fit_swelling", bodies["/v1/fit/swelling"])
            sweep = await call("sweep", bodies["/v1/sweep"])
            _stamped(sweep, "sweep")
            deadline = time.monotonic() + 120
            while time.monotonic() < deadline:
                status = await call("sweep_status", sweep.sweep_id)
                if status.status in ("done", "failed"):
                    break
                await asyncio.sleep(0.2)
            _stamped(status, "sweep_status")
            assert (await call("sweep_table_csv", sweep.sweep_id)).startswith(("#", "index"))
            assert b"<svg" in await call("sweep_plot_svg", sweep.sweep_id, gel=0)
            assert b"<svg" in await call("phase_map_svg", base="ANB", t_start=302, t_end=308)
            for jid in (job.validation_id, fits.id, sweep.sweep_id):
                _stamped(await call("job", jid), f"job {jid}")
            v = await call("validation", job.validation_id)
            _stamped(v, "validation")
    assert called == {r.name for r in ROUTES}


def test_a_429_is_asked_again_after_its_retry_after(tmp_path: Path) -> None:
    with serve_process(tmp_path / "c.sqlite", "--max-connections-per-client", "1",
                       "--no-warmup") as (url, _):
        port = int(url.rsplit(":", 1)[1])
        hold = socket.create_connection(("127.0.0.1", port))  # the client's one connection
        try:
            time.sleep(0.3)
            with httpx.Client(base_url=url) as raw:
                first = raw.get("/health")
            assert first.status_code == 429 and int(first.headers["retry-after"]) >= 1
            with Client(url, retries=0) as c, pytest.raises(ApiError) as e:
                c.gels()
            assert e.value.status == 429 and e.value.retry_after >= 1
            threading.Timer(0.5, hold.close).start()  # freed before the Retry-After is up
            t0 = time.monotonic()
            with Client(url) as c:
                gels = c.gels()
            waited = time.monotonic() - t0
        finally:
            hold.close()
    assert gels.gels and "version" in gels.model_dump()
    assert waited >= float(first.headers["retry-after"]) - 0.1
