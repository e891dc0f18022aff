"""Session-wide test settings."""

from __future__ import annotations

import pytest


@pytest.fixture(autouse=True, scope="session")
def _private_gel_store(tmp_path_factory: pytest.TempPathFactory):
    """Fitted gels saved by any test (e.g. generated HTTP bodies with ``save``) go to a
    temporary store, never to the user's ~/.cache/thermogel/gels."""
    mp = pytest.MonkeyPatch()
    mp.setenv("THERMOGEL_GELS", str(tmp_path_factory.mktemp("gels")))
    yield
    mp.undo()
