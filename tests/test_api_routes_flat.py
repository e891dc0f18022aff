"""The app's routes are registered one by one (``api.http.add_routes``, issue 23: FastAPI's
``include_router`` matches every included router's routes twice per request): the same
OpenAPI description, the same answers, the body limit and dependency overrides kept.
Speed itself is measured in benchmarks/speed.py (``load``)."""

from __future__ import annotations

import json
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
from api_support import asgi
from dosing_fakes import FakeSolver
from fastapi.routing import APIRoute

import api.http as http
from api.deps import get_planner
from api.errors import ServiceUnavailable
from dosing import Planner


def _app(tmp_path: Path, flat: bool, monkeypatch: pytest.MonkeyPatch):
    planner = Planner(cache_path=tmp_path / f"{flat}.sqlite", executor=ThreadPoolExecutor(1),
                      solver=FakeSolver())
    with monkeypatch.context() as m:
        if not flat:
            m.setattr(http, "add_routes", lambda app, router: app.include_router(router))
        app = http.create_app(planner, warm=False)
    return app, planner


def test_the_description_is_the_same_as_including_the_routers(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    flat, p1 = _app(tmp_path, True, monkeypatch)
    nested, p2 = _app(tmp_path, False, monkeypatch)
    try:
        assert json.dumps(flat.openapi()) == json.dumps(nested.openapi())  # order too
        own = [r for r in flat.router.routes if isinstance(r, APIRoute)]
        other = {getattr(r, "path", None) for r in flat.router.routes
                 if not isinstance(r, APIRoute)}
        assert other <= {"/openapi.json", "/docs-assets", "/docs", "/redoc",
                         "/docs/oauth2-redirect"}, other  # all but the spec and the manual
        assert len(own) > 20
    finally:
        p1.close()
        p2.close()


@pytest.mark.anyio
async def test_answers_limit_and_overrides_are_kept(tmp_path: Path,
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    bodies = {"/v1/dose-time": {"gel": "ANB", "t_start": 302.0, "t_end": 308.0,
                                "dose_fraction": 0.5, "dry_radius_um": 50.0},
              "/v1/classify": {"gel": "ANB", "t_start": 302.0, "t_end": 308.0}}
    got = []
    for flat in (True, False):
        app, planner = _app(tmp_path, flat, monkeypatch)
        try:
            async with asgi(app) as (_, raw):
                got.append([(await raw.post(path, json=body)).json()
                            for path, body in bodies.items()])
                big = b'{"gel": "ANB", "t_start": 302, "doses": [' + b"0.1, " * 300_000 \
                    + b"0.1]}"
                r = await raw.post("/v1/schedule", content=big,
                                   headers={"content-type": "application/json"})
                assert r.status_code == 413 and r.json()["detail"][0]["type"] == \
                    "body_too_large"

                def starting() -> None:
                    raise ServiceUnavailable("overridden")

                app.dependency_overrides[get_planner] = starting
                r = await raw.post("/v1/dose-time", json=bodies["/v1/dose-time"])
                assert r.status_code == 503 and "overridden" in r.text
                app.dependency_overrides.clear()
                assert (await raw.get("/nowhere")).status_code == 404
        finally:
            planner.close()
    assert got[0] == got[1]


def test_a_router_with_other_routes_is_refused() -> None:
    from fastapi import APIRouter, FastAPI

    router = APIRouter()
    router.add_websocket_route("/ws", lambda ws: None)
    with pytest.raises(TypeError):
        http.add_routes(FastAPI(), router)
