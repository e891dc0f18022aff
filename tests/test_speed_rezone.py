"""The moving grid's mesh check in one compiled call (issue 23): the same arithmetic as
the step-by-step Python check it replaced (``Rezoner.check_python``), so the same run."""

from __future__ import annotations

import numpy as np
import pytest

from solver.full import simulate
from solver.full.moving import Rezoner

RUN = {"grid": "moving", "n": 60, "interfacial_length": 2e-3, "rtol": 1e-5}


def test_compiled_check_reproduces_the_python_check(monkeypatch) -> None:
    fast = simulate("ANB", 302, 308, until=0.06, **RUN)
    monkeypatch.setattr(Rezoner, "__call__", Rezoner.check_python)
    ref = simulate("ANB", 302, 308, until=0.06, **RUN)
    assert fast.diagnostics["remaps"] == ref.diagnostics["remaps"] > 0
    assert fast.diagnostics["steps"] == ref.diagnostics["steps"]
    np.testing.assert_allclose(fast.radius, ref.radius, rtol=1e-12)
    a = 0.5 * (fast.radius[0] + fast.radius[-1])
    assert fast.time_to_radius(a) == pytest.approx(ref.time_to_radius(a), rel=1e-12)
