"""A fake full solver with a closed-form a(t), to test the planner's logic in milliseconds.

In every protocol step a^3 relaxes exponentially to the stable equilibrium at the step's
temperature, at a rate that depends on the grid (so the two grids "disagree" like the
real solver does in the front regime) and on the interfacial length: times scale as
1 + ELL_C ell^ELL_ORDER, so a ladder's Richardson limit is the ell = 0 time exactly.
"""

from __future__ import annotations

import math
import threading

import numpy as np

from solver.equilibrium import equilibrium, nearest_stable
from solver.full import FullResult

RATES = {"eulerian": 10.0, "lagrangian": 8.0, "moving": 8.0}
MOVING_C = 2.0  # the moving grid's times scale as 1 + MOVING_C / n (a direct check's gap)
ELL_C, ELL_ORDER = 200.0, 1.5  # ell = 0.005: times 7 % later


class FakeSolver:
    """Callable like solver.full.simulate (pass it as ``Planner(solver=...)``); returns a
    real FullResult (outputs only, no per-step record); counts calls; can block or fail on
    demand."""

    def __init__(self, rate_scale: float = 1.0) -> None:
        self.calls: list[dict] = []
        self.lock = threading.Lock()
        self.gate: threading.Event | None = None
        self.fail: str | None = None
        self.rate_scale = rate_scale

    def __call__(self, gel, t_start, t_end=None, *, protocol=None, grid="eulerian", n=400,
                 branch=None, interfacial_length=0.0, **kw) -> FullResult:
        with self.lock:
            self.calls.append({"grid": grid, "protocol": protocol, "n": n,
                               "interfacial_length": interfacial_length})
        if self.gate is not None:
            assert self.gate.wait(30)
        if self.fail:
            from solver.errors import SolverError

            raise SolverError(self.fail, {"fake": True})
        rate = RATES[grid] * self.rate_scale / (1.0 + ELL_C * interfacial_length**ELL_ORDER)
        if grid == "moving":
            rate /= 1.0 + MOVING_C / n
        a = equilibrium(gel, t_start, branch or "swollen").stretch
        a0 = a
        ts, rs, temps = [0.0], [a], [t_start]
        t = 0.0
        for dur, temp in protocol:
            af = nearest_stable(gel, temp, a).stretch
            tt = np.linspace(0.0, dur, 400)[1:]
            a3 = af**3 + (a**3 - af**3) * np.exp(-rate * tt)
            ts += list(t + tt)
            rs += list(np.cbrt(a3))
            temps += [temp] * tt.size
            t += dur
            a = float(np.cbrt(a3[-1]))
        r = np.array(rs)
        return FullResult(t=np.array(ts), radius=r, front=np.full(r.size, np.nan),
                          expelled_volume=4 * math.pi / 3 * (a0**3 - r**3),
                          temperature=np.array(temps), diagnostics={"steps": len(ts)})


def exact_time(a0: float, af: float, a: float, grid: str = "eulerian", scale: float = 1.0) -> float:
    """Closed-form time for one jump: a^3 = af^3 + (a0^3 - af^3) exp(-rate t)."""
    return -math.log((a**3 - af**3) / (a0**3 - af**3)) / (RATES[grid] * scale)
