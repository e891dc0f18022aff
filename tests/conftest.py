"""Session-wide test settings."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import pytest

from dosing import Planner


@pytest.fixture(autouse=True, scope="session")
def _private_gel_store(tmp_path_factory: pytest.TempPathFactory):
    """Fitted gels saved by any test (e.g. generated HTTP bodies with ``save``) go to a
    temporary store, never to the user's ~/.cache/thermogel/gels."""
    mp = pytest.MonkeyPatch()
    mp.setenv("THERMOGEL_GELS", str(tmp_path_factory.mktemp("gels")))
    yield
    mp.undo()


@pytest.fixture(scope="session")
def anyio_backend() -> str:
    """The async tests' event loop (pytest-anyio): asyncio only (session-wide, so module
    fixtures may be async too)."""
    return "asyncio"


@pytest.fixture
def planner(tmp_path):
    """A real planner on a temporary cache with a one-thread executor (closed after the
    test); a test module may define its own."""
    p = Planner(cache_path=tmp_path / "cache.sqlite", executor=ThreadPoolExecutor(1))
    yield p
    p.close()
    p.jobs.executor.shutdown(wait=True)


@pytest.fixture
def fake_planner(tmp_path):
    """A planner on the fake full solver (``dosing_fakes.FakeSolver``, as ``.fake``: its
    closed-form a(t) in milliseconds), a two-thread executor, a temporary cache."""
    from dosing_fakes import FakeSolver

    fake = FakeSolver()
    p = Planner(cache_path=tmp_path / "fake.sqlite", executor=ThreadPoolExecutor(2),
                solver=fake)
    p.fake = fake
    yield p
    p.close()
    p.jobs.executor.shutdown(wait=True)
