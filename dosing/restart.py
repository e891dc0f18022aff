"""Protocol runs step by step, each step from the exact state where the last one ended.

Every step of a (duration, temperature) protocol restarts the full solver's integrator
(``solver.full.integrate``: a new temperature takes a small first step and stops the moving
grid's nodes), so running the steps one after another, each from the last one's final
state (its radius and cell porosities and, on the moving grid, its nodes: exact up to
round-off) and output at the one-shot run's times, takes the same steps as one run of the
whole protocol.  The state at every protocol boundary is kept in the run's metadata
(``STATES``), so a later protocol that shares its first j steps with a stored run starts
there (:class:`Start`): a schedule's shooting simulates only the heating it varies (and
the rest before it), not the heatings and rests fixed before them.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from solver.errors import BudgetExceeded
from solver.full.result import RECORD_ARRAYS, FullResult, uniform_output_times

STATES = "boundary_states"  # meta: the state after each protocol step
_COUNTERS = ("steps", "rejected", "jacobians", "rhs_calls", "merges", "mesh_checks", "remaps",
             "wall_time")


@dataclass(frozen=True)
class Start:
    """A protocol run's start after its first ``steps`` steps: a stored run's ``record`` up
    to there (a(t) and the per-step record, no profiles) and its ``states`` after each of
    those steps (the last one is where the run continues)."""

    steps: int
    record: FullResult
    states: list[dict[str, Any]]

    @classmethod
    def of(cls, stored: FullResult, steps: int) -> Start | None:
        """The start after ``steps`` steps of a stored run (None if it kept no state)."""
        states = [st for st in stored.meta.get(STATES) or [] if not st.get("stopped")][:steps]
        if len(states) != steps or states[-1].get("steps") != steps:
            return None
        rec = truncate(stored, float(states[-1]["t"]))
        rec.diagnostics = {**rec.diagnostics, **states[-1].get("counters", {})}
        return cls(steps, rec, states)


def restartable(solver: Any) -> bool:
    """True for solvers that continue from a given state exactly (``solver.full.simulate``,
    or a stand-in saying so with ``restartable = True``; others are not asked to, and
    asking loads no kernels)."""
    if getattr(solver, "restartable", False):
        return True
    if getattr(solver, "__module__", None) != "solver.full.run":
        return False
    from solver.full import simulate

    return solver is simulate


def boundaries(steps: tuple[tuple[float, float], ...]) -> list[float]:
    """The time at the start of each step and at the end (summed as the solver sums)."""
    out, t = [0.0], 0.0
    for d, _ in steps:
        t += d
        out.append(t)
    return out


def output_times(total: float) -> np.ndarray:
    """The one-shot run's default outputs (the solver's own rule)."""
    return uniform_output_times(total)


def state_of(res: FullResult, steps: int, t: float) -> dict[str, Any]:
    """The last output of a fresh run (with profiles) as plain data: after ``steps`` protocol
    steps, at time ``t`` of the protocol."""
    return {"steps": int(steps), "t": float(t), "radius": float(res.radius[-1]),
            "phi": np.asarray(res.phi[-1], dtype=float).tolist(),
            "nodes": np.asarray(res.nodes[-1], dtype=float).tolist() if res.nodes.size
            else None}


def restart_options(state: dict[str, Any]) -> dict[str, Any]:
    """``simulate`` keywords continuing from ``state``: the profile, and on the moving grid
    its nodes as the first mesh (not a new mesh adapted to it)."""
    kw: dict[str, Any] = {"initial": (state["radius"], np.asarray(state["phi"], dtype=float)),
                          "branch": None}
    if state.get("nodes") is not None:
        from solver.full.moving import MeshOptions

        kw["mesh"] = MeshOptions(nodes=tuple(state["nodes"]))
    return kw


def step_budget(grid: str, left: float) -> dict[str, Any]:
    """``simulate``'s wall-clock budget for one protocol step: ``left`` seconds, but not on
    the moving grid, where the budget's progress ticks (200 a run) would stop a short step's
    integration every duration / 200 and shift the mesh checks (a 0.01 tau heating took
    1.5x the steps); there the step budget (500,000 implicit steps) bounds a step and the
    wall clock is checked between steps."""
    return {} if grid == "moving" else {"max_seconds": max(left, 1.0)}


def truncate(rec: FullResult, t: float) -> FullResult:
    """A stored run's record up to time ``t`` (a protocol boundary: an output and a step)."""
    end = t * (1.0 + 1e-12)
    keep, steps = rec.t <= end, rec.step_t <= end
    arrays = {k: np.asarray(getattr(rec, k))[keep] for k in ("t", "radius", "front",
                                                              "expelled_volume",
                                                              "temperature")}
    arrays.update({k: np.asarray(getattr(rec, k))[steps] for k in ("step_t", "step_radius",
                                                                    "step_rate", "step_edge")})
    return replace(rec, **arrays, meta={})


def join(first: FullResult, parts: list[tuple[float, FullResult]],
         protocol: list[list[float]], restarted: int) -> FullResult:
    """One record of a protocol from ``first`` (from t = 0) and later ``parts`` (each from
    its own t = 0, which is ``offset`` in the protocol; its first output and step record
    repeat the boundary and are dropped), as one run of the whole protocol records it."""
    cat: dict[str, list[np.ndarray]] = {k: [np.asarray(getattr(first, k), dtype=float)]
                                        for k in RECORD_ARRAYS}
    diag = dict(first.diagnostics)
    spinodal = bool(first.spinodal)
    for offset, part in parts:
        keep, steps = part.t > 0.0, part.step_t > 0.0
        for k in ("t", "radius", "front", "temperature"):
            cat[k].append(np.asarray(getattr(part, k), dtype=float)[keep]
                          + (offset if k == "t" else 0.0))
        for k in ("step_t", "step_radius", "step_rate", "step_edge"):
            cat[k].append(np.asarray(getattr(part, k), dtype=float)[steps]
                          + (offset if k == "step_t" else 0.0))
        pd = part.diagnostics
        for name in _COUNTERS:
            if name in pd:
                diag[name] = diag.get(name, 0) + pd[name]
        if pd.get("message", "ok") != "ok":
            diag["message"] = pd["message"]
        spinodal = spinodal or bool(part.spinodal)
    arrays = {k: np.concatenate(v) for k, v in cat.items() if k != "expelled_volume"}
    a = arrays["radius"]
    arrays["expelled_volume"] = 4.0 * np.pi / 3.0 * (a[0] ** 3 - a**3)
    diag.update(protocol=protocol, status="finished", t_events=[],
                restarted_after_steps=restarted)
    return replace(first, **arrays, spinodal=spinodal, diagnostics=diag, meta={})


def run_steps(sc: Any, solver: Any, budget: float, start: Start | None = None
              ) -> tuple[FullResult, list[dict[str, Any]]]:
    """``sc``'s protocol run (a :class:`dosing.scenario.Scenario` with ``protocol``), step by
    step from ``start`` (or t = 0) with the one-shot run's outputs and the protocol
    boundaries; returns the record (no profiles) and the state after every step."""
    import time

    steps = tuple(sc.protocol)
    s = sc.settings
    bounds = boundaries(steps)
    grid = output_times(bounds[-1])
    started = time.perf_counter()
    j0 = 0 if start is None else start.steps
    states = [] if start is None else [dict(st) for st in start.states]
    state = states[-1] if states else None
    first = None if start is None else start.record
    done = {} if first is None else {k: first.diagnostics.get(k, 0) for k in _COUNTERS}
    parts: list[tuple[float, FullResult]] = []
    stopped, t_e = False, 0.0
    for j in range(j0, len(steps)):
        t0, t1 = bounds[j], bounds[j + 1]
        d, temp = steps[j]
        inner = grid[(grid > t0) & (grid < t1)] - t0
        saveat = np.concatenate([[0.0], inner, [d]])
        kw = {"branch": sc.branch} if state is None else restart_options(state)
        spent = time.perf_counter() - started
        if spent > budget:
            raise BudgetExceeded(
                f"the full-solver run of the protocol used its {budget:.0f} s budget after "
                f"{j} of its {len(steps)} steps", {"wall_seconds": spent, "steps_done": j})
        kw.update(step_budget(s.grid, budget - spent))
        last = j == len(steps) - 1
        if last and sc.stop_expelled is not None and s.integrator == "implicit":
            kw["stop"] = _stop_radius(sc, state)
        res = solver(sc.gel, sc.t_start, protocol=[(d, temp)], saveat=saveat, grid=s.grid,
                     n=s.n, integrator=s.integrator, rtol=s.rtol,
                     interfacial_length=s.interfacial_length, **kw)
        stopped = res.diagnostics.get("status") == "stopped"
        t_e = t0 + float(res.t[-1])
        for k in _COUNTERS:
            done[k] = done.get(k, 0) + res.diagnostics.get(k, 0)
        state = {**state_of(res, j + 1, t1), "counters": dict(done)}
        if stopped:  # not the protocol's boundary: the end of a shorter last step
            state.update(stopped=True, t=t_e)
        states.append(state)
        rec = res.without_profiles()
        if first is None:
            first = rec
        else:
            parts.append((t0, rec))
    assert first is not None
    out = join(first, parts, [list(x) for x in steps], j0)
    if stopped:
        out.diagnostics.update(status="stopped", t_events=[t_e])
    return out, states


def _stop_radius(sc: Any, state: dict[str, Any] | None) -> float:
    """The radius at which the last step has expelled ``sc.stop_expelled`` (from the state
    it starts in, or the start equilibrium)."""
    if state is None:
        from solver.equilibrium import equilibrium

        a0 = float(equilibrium(sc.gel, sc.t_start, sc.branch).stretch)
    else:
        a0 = float(state["radius"])
    a3 = a0**3 - float(sc.stop_expelled)
    return float(np.cbrt(a3)) if a3 > 1.0 else 1.0 + 1e-9  # beyond reach: never stops


def stopped_as_run(sc: Any, rec: FullResult) -> tuple[Any, FullResult] | None:
    """A protocol run that stopped at its dose (``sc.stop_expelled``) is also the run of
    the protocol whose last step ends there: that scenario (the last step's duration the
    stop's time less the step's start, as a reading of the run computes it) and the record
    (finished, its state at the stop the state after the last step); None if it did not
    stop."""
    states = list(rec.meta.get(STATES) or [])
    if sc.stop_expelled is None or rec.terminal_time is None or not states or not (
            states[-1].get("stopped")):
        return None
    steps = tuple(sc.protocol)
    start = boundaries(steps)[-2]
    last = (float(rec.terminal_time) - start, steps[-1][1])
    alias = replace(sc, protocol=(*steps[:-1], last), stop_expelled=None)
    end = {k: v for k, v in states[-1].items() if k != "stopped"}
    meta = {**rec.meta, "key": alias.key(), "scenario": alias.key_dict(),
            STATES: [*states[:-1], {**end, "t": boundaries(alias.protocol)[-1]}],
            "stopped_run": sc.key()}
    diag = {**rec.diagnostics, "status": "finished", "t_events": [],
            "protocol": [list(x) for x in alias.protocol]}
    return alias, replace(rec, diagnostics=diag, meta=meta)
