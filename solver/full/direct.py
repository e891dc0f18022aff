"""Direct dose times of the regularized model at one interfacial length, on the moving grid,
with their numerical uncertainty; and the delayed-transition bound of the ell = 0 lattice.

The pieces a planner needs for "one truth" (issue 12, docs/moving_mesh.md): the dose time at
the bead's own ell = xi / a_d run directly (no ladder, no extrapolation), its numerical part
of the uncertainty from a second run with half the cells (the scheme converges at second
order, so |t(n) - t(n/2)| bounds the finer run's error about three times over), and the
model-form alternative: the ell = 0 Lagrangian lattice, whose dose times converge,
N-independent, to the delayed (hysteretic) transition (docs/interfacial.md; 0.116 ANB and
0.221 HHT at 80%).
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from ..equilibrium import equilibrium
from ..errors import ParameterError
from ..gel import Gel, preset
from ..phase import nucleation_level
from .result import FullResult
from .run import simulate

FIRST_UNTIL = 0.1
MAX_UNTIL = 100.0


@dataclass(frozen=True)
class DirectTimes:
    """Times at which the radius first reaches each of ``radii`` in one direct run, in the
    check run with half the cells, their relative gap (the numerical error bound), the time
    the front nucleated at the edge (None without one), and the settings."""

    radii: tuple[float, ...]
    times: tuple[float, ...]
    check_times: tuple[float, ...]
    numerical: tuple[float, ...]
    nucleation_time: float | None
    interfacial_length: float
    n: int
    wall_seconds: float

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form (NaN -> None)."""
        d = asdict(self)
        return {k: ([None if isinstance(x, float) and math.isnan(x) else x for x in v]
                    if isinstance(v, tuple) else v) for k, v in d.items()}


def _gel(gel: Gel | str) -> Gel:
    g = preset(gel) if isinstance(gel, str) else gel
    if not isinstance(g, Gel):
        raise ParameterError("gel", gel, "a Gel or a preset name")
    return g


def _run_to(gel: Gel, t_start: float, t_end: float, radius: float, grid: str, n: int,
            ell: float, rtol: float, max_seconds: float | None) -> FullResult:
    """A run long enough for a(t) to reach ``radius`` (the horizon doubled as needed)."""
    until = FIRST_UNTIL
    while True:
        res = simulate(gel, t_start, t_end, until=until, grid=grid, n=n, interfacial_length=ell,
                       rtol=rtol, every=until / 50, max_seconds=max_seconds)
        if res.step_radius.size and (np.min(res.step_radius) <= radius
                                     <= np.max(res.step_radius)) or until >= MAX_UNTIL:
            return res
        until *= 4.0


def _times(res: FullResult, radii: Sequence[float]) -> tuple[float, ...]:
    out = []
    for a in radii:
        try:
            out.append(float(res.time_to_radius(a)))
        except ValueError:
            out.append(math.nan)
    return tuple(out)


def direct_dose_times(gel: Gel | str, t_start: float, t_end: float, radii: Sequence[float],
                      interfacial_length: float, n: int = 400, rtol: float = 1e-5,
                      max_seconds: float | None = None) -> DirectTimes:
    """Times at which a(t) first reaches each of ``radii`` after T_start -> T_end, on the
    moving grid with n cells at ``interfacial_length`` (> 0), checked against n / 2 cells."""
    g = _gel(gel)
    if not (isinstance(interfacial_length, (int, float)) and interfacial_length > 0.0):
        raise ParameterError("interfacial_length", interfacial_length,
                             "> 0 (the regularized model; use delayed_transition_times for 0)")
    if not radii:
        raise ParameterError("radii", radii, "at least one target radius")
    started = time.perf_counter()
    target = min(radii) if t_end >= t_start else max(radii)
    res = _run_to(g, t_start, t_end, target, "moving", n, interfacial_length, rtol, max_seconds)
    chk = _run_to(g, t_start, t_end, target, "moving", max(n // 2, 10), interfacial_length,
                  rtol, max_seconds)
    times, check = _times(res, radii), _times(chk, radii)
    numerical = tuple(abs(a - b) / a if a > 0.0 else math.nan for a, b in zip(times, check,
                                                                              strict=True))
    nuc = None
    try:
        nuc = res.nucleation_time(nucleation_level(g, t_start, t_end))
    except (ValueError, ParameterError):
        nuc = None
    return DirectTimes(tuple(float(a) for a in radii), times, check, numerical, nuc,
                       float(interfacial_length), int(n), time.perf_counter() - started)


def delayed_transition_times(gel: Gel | str, t_start: float, t_end: float,
                             radii: Sequence[float], ns: Sequence[int] = (200, 400, 800),
                             rtol: float = 1e-5) -> dict[str, Any]:
    """The ell = 0 Lagrangian lattice's times for ``radii`` at each N (uniform grid): the
    delayed-transition front law, and its N-spread (relative, per radius)."""
    g = _gel(gel)
    target = min(radii) if t_end >= t_start else max(radii)
    rows = [_times(_run_to(g, t_start, t_end, target, "lagrangian", int(k), 0.0, rtol, None),
                   radii) for k in ns]
    arr = np.array(rows)
    spread = (np.nanmax(arr, axis=0) - np.nanmin(arr, axis=0)) / arr[-1]
    return {"ns": [int(k) for k in ns], "times": arr.tolist(), "time": arr[-1].tolist(),
            "spread": spread.tolist(), "start_radius": equilibrium(g, t_start).stretch}
