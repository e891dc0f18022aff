"""The planner's bookkeeping for protocol runs that continue a stored prefix.

Which stored run a protocol starts from (:class:`Start`), the one ``simulate`` call from its
state (:func:`run_protocol`), and a read-off heating's stopped run as the run of the protocol
ending at its stop (:func:`stopped_as_run`).  docs/architecture.md, "The life of a schedule"
and "The run store"."""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from solver.errors import BudgetExceeded
from solver.full.result import FullResult, uniform_output_times
from solver.full.state import protocol_boundaries


@dataclass(frozen=True)
class Start:
    """A protocol run's start after its first ``steps`` steps: a stored ``record`` (of a
    protocol sharing those steps) that kept its state there."""

    steps: int
    record: FullResult

    @classmethod
    def of(cls, stored: FullResult, steps: int) -> Start | None:
        """The start after ``steps`` steps of a stored run (None if it kept no state there)."""
        return cls(steps, stored) if stored.boundary_state(steps) is not None else None


def restartable(solver: Any) -> bool:
    """True for solvers that continue from a given state exactly (``solver.full.simulate``,
    or a stand-in saying so with ``restartable = True``; others are not asked to, and
    asking loads no kernels)."""
    if getattr(solver, "restartable", False):
        return True
    from .full import is_full_solver

    return is_full_solver(solver)


def run_protocol(sc: Any, solver: Any, budget: float, start: Start | None = None
                 ) -> FullResult:
    """``sc``'s protocol run (a ``Scenario`` with ``protocol``) as stored (no profiles, boundary
    states kept): one ``simulate`` from ``start`` (or t = 0) within ``budget`` wall seconds, output
    at the one-shot run's times and every boundary.  With ``sc.stop_expelled`` the last step stops
    once it expelled that volume (docs/architecture.md, "The run store")."""
    steps = tuple(sc.protocol)
    began = time.perf_counter()
    bounds = protocol_boundaries(steps)
    outputs = np.union1d(uniform_output_times(bounds[-1]), bounds)
    first = 0 if start is None else start.steps
    last = len(steps) - 1
    if sc.stop_expelled is not None and sc.settings.integrator == "implicit":
        if last > 0 and (start is None or start.steps < last):
            start = Start(last, _call(sc, solver, steps[:last], start, budget, began,
                                      outputs[outputs <= bounds[last]]))
        a0 = None if last == 0 else start.record.boundary_state(last).radius  # type: ignore
        rec = _call(sc, solver, steps, start, budget, began, outputs, _stop_radius(sc, a0))
    else:
        rec = _call(sc, solver, steps, start, budget, began, outputs)
    rec.diagnostics["restarted_after_steps"] = first
    return rec


def _call(sc: Any, solver: Any, steps: tuple, start: Start | None, budget: float,
          began: float, outputs: np.ndarray, stop: float | None = None) -> FullResult:
    """One ``simulate`` of ``steps`` from ``start`` (joined to its record), or t = 0, with
    ``outputs`` (those before the start are not produced)."""
    s = sc.settings
    left = budget - (time.perf_counter() - began)
    if left <= 0.0:
        raise BudgetExceeded(f"the full-solver run of the protocol used its {budget:.0f} s "
                             f"budget", {"wall_seconds": budget - left})
    kw: dict[str, Any] = {"branch": sc.branch} if start is None else {
        "initial": start.record.boundary_state(start.steps)}
    if stop is not None:
        kw["stop"] = stop
    res = solver(sc.gel, sc.t_start, protocol=list(steps), saveat=outputs, grid=s.grid, n=s.n,
                 integrator=s.integrator, rtol=s.rtol, interfacial_length=s.interfacial_length,
                 max_seconds=max(left, 1.0), **kw).without_profiles()
    return res if start is None else res.after(start.record)


def _stop_radius(sc: Any, a0: float | None) -> float:
    """The radius at which the last step has expelled ``sc.stop_expelled`` from radius
    ``a0`` at its start (None: the start equilibrium)."""
    if a0 is None:
        from solver.equilibrium import equilibrium

        a0 = float(equilibrium(sc.gel, sc.t_start, sc.branch).stretch)
    a3 = float(a0) ** 3 - float(sc.stop_expelled)
    return float(np.cbrt(a3)) if a3 > 1.0 else 1.0 + 1e-9  # beyond reach: never stops


def stopped_as_run(sc: Any, rec: FullResult) -> tuple[Any, FullResult] | None:
    """A protocol run that stopped at its dose (``sc.stop_expelled``) is also the run of
    the protocol whose last step ends there: that scenario (the last step's duration the
    stop's time less the step's start, as a reading of the run computes it) and the record
    (finished, its state at the stop the state after the last step); None if it did not
    stop."""
    states = list(rec.boundary_states)
    if sc.stop_expelled is None or rec.terminal_time is None or not states or not (
            states[-1].stopped):
        return None
    steps = tuple(sc.protocol)
    start = protocol_boundaries(steps)[-2]
    last = (float(rec.terminal_time) - start, steps[-1][1])
    alias = replace(sc, protocol=(*steps[:-1], last), stop_expelled=None)
    end = replace(states[-1], stopped=False, t=protocol_boundaries(alias.protocol)[-1])
    meta = {**rec.meta, "key": alias.key(), "scenario": alias.key_dict(),
            "stopped_run": sc.key()}
    diag = {**rec.diagnostics, "status": "finished", "t_events": [],
            "protocol": [list(x) for x in alias.protocol]}
    return alias, replace(rec, diagnostics=diag, meta=meta,
                          boundary_states=[*states[:-1], end])
