"""Property-based run over the OpenAPI spec (schemathesis): no input gives a server error.

Every operation gets generated valid and invalid inputs (bounded: ``MAX_EXAMPLES`` per
operation and ``TIME_BUDGET_S`` per test, no per-example deadline); each answer must be a
non-5xx status the spec documents, with a body matching the documented schema.  A second
pass sends the same cases as non-strict JSON: one number of each body replaced by NaN,
Infinity, -Infinity or 1e309 (issue 15, D1), which must be a 422 naming that field,
answered in strict JSON.  Full-solver jobs run on the fake solver.
"""

from __future__ import annotations

import json
import time
import zlib
from collections.abc import Iterator
from typing import Any

import pytest
import schemathesis
from api_support import fake_full_solver, fake_planner
from hypothesis import HealthCheck, settings
from schemathesis.checks import (
    content_type_conformance,
    not_a_server_error,
    response_schema_conformance,
    status_code_conformance,
)

from api.errors import MAX_ERRORS
from api.http import create_app

MAX_EXAMPLES = 30
TIME_BUDGET_S = 120.0  # per test function: later examples are skipped past it
NON_FINITE = ("NaN", "Infinity", "-Infinity", "1e309")
MARK = "__NON_FINITE__"


class _LatePlanner:
    """Stands in for the planner until the module fixture provides the real one."""

    target = None

    def __getattr__(self, name: str) -> object:
        return getattr(self.target, name)


_late = _LatePlanner()
app = create_app(planner=_late, warm=False)
schema = schemathesis.openapi.from_asgi("/openapi.json", app)
_started: dict[str, float] = {}


def _over_budget(test: str) -> bool:
    return time.monotonic() - _started.setdefault(test, time.monotonic()) > TIME_BUDGET_S


@pytest.fixture(scope="module", autouse=True)
def _fake_planner(tmp_path_factory):
    """The real planner on a fresh cache, its full-solver jobs on the fake solver; schedule
    jobs are drained before the planner closes."""
    with fake_full_solver() as fake, fake_planner(tmp_path_factory.mktemp("st") / "cache.sqlite",
                                                  fake, max_pending=16) as planner:
        _late.target = planner
        yield
        app.state.service.stop(wait=True)
        _late.target = None


@schema.parametrize()
@settings(max_examples=MAX_EXAMPLES, deadline=None, derandomize=True,
          suppress_health_check=list(HealthCheck))
def test_no_server_error(case) -> None:
    if _over_budget("strict"):
        return
    case.call_and_validate(checks=[not_a_server_error, status_code_conformance,
                                   content_type_conformance, response_schema_conformance])


def _numbers(obj: Any, path: tuple = ()) -> Iterator[tuple]:
    """Paths to every number (not bool) in a JSON value."""
    if isinstance(obj, bool):
        return
    if isinstance(obj, (int, float)):
        yield path
    elif isinstance(obj, dict):
        for k, v in obj.items():
            yield from _numbers(v, (*path, k))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from _numbers(v, (*path, i))


def _strict(text: str) -> Any:
    def refuse(token: str) -> None:
        raise ValueError(f"non-strict JSON in an answer: {token}")

    return json.loads(text, parse_constant=refuse)


@schema.parametrize()
@settings(max_examples=MAX_EXAMPLES, deadline=None, derandomize=True,
          suppress_health_check=list(HealthCheck))
def test_non_strict_json_is_a_422_naming_the_field(case) -> None:
    """The generated body with one number made non-finite (chosen by the body's hash)."""
    if _over_budget("non-strict") or case.method.upper() != "POST":
        return
    body = case.body
    paths = list(_numbers(body)) if isinstance(body, dict) else []
    if not paths:
        return
    pick = zlib.crc32(json.dumps(body, sort_keys=True, default=str).encode())
    path, token = paths[pick % len(paths)], NON_FINITE[pick % len(NON_FINITE)]
    node = body = json.loads(json.dumps(body))
    for part in path[:-1]:
        node = node[part]
    node[path[-1]] = MARK
    raw = json.dumps(body).replace(f'"{MARK}"', token)
    resp = case.call(headers={"content-type": "application/json"}, data=raw.encode())
    assert resp.status_code == 422, (raw[:300], resp.status_code, resp.text[:300])
    detail = _strict(resp.text)["detail"]
    tags = ("custom", "preset", "float", "int", "str", "bool")  # union members' tags
    locs = [[p for p in d["loc"] if p not in tags and not (isinstance(p, str) and "[" in p)]
            for d in detail]
    if any(d["type"] == "truncated" for d in detail):  # over MAX_ERRORS: the rest counted
        assert len(detail) == MAX_ERRORS + 1, len(detail)
        return
    # the field itself, or the unknown field it sits in (an extra key is refused whole)
    assert any(len(loc) > 1 and list(path[:len(loc) - 1]) == loc[1:] for loc in locs), (
        raw[:300], locs)
