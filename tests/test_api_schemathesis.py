"""Property-based run over the OpenAPI spec (schemathesis): no input gives a server error.

Every operation gets generated valid and invalid inputs (bounded: ``MAX_EXAMPLES`` per
operation, no deadline); each answer must be a non-5xx status the spec documents, with a
body matching the documented schema.  Full-solver jobs run on the fake solver.
"""

from __future__ import annotations

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

from api.http import create_app

MAX_EXAMPLES = 30


class _LatePlanner:
    """Stands in for the planner until the module fixture provides the real one."""

    target = None

    def __getattr__(self, name: str) -> object:
        return getattr(self.target, name)


_late = _LatePlanner()
app = create_app(planner=_late, warm=False)
schema = schemathesis.openapi.from_asgi("/openapi.json", app)


@pytest.fixture(scope="module", autouse=True)
def _fake_planner(tmp_path_factory):
    """The real planner on a fresh cache, its full-solver jobs on the fake solver (patched
    in only while this module runs); schedule jobs are drained before the patch goes."""
    with fake_full_solver(), fake_planner(tmp_path_factory.mktemp("st") / "cache.sqlite",
                                          max_pending=16) as planner:
        _late.target = planner
        yield
        app.state.service.stop(wait=True)
        _late.target = None


@schema.parametrize()
@settings(max_examples=MAX_EXAMPLES, deadline=None, derandomize=True,
          suppress_health_check=list(HealthCheck))
def test_no_server_error(case) -> None:  # noqa: ANN001
    case.call_and_validate(checks=[not_a_server_error, status_code_conformance,
                                   content_type_conformance, response_schema_conformance])
