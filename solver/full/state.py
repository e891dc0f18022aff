"""BoundaryState: the full solver's exact state at a protocol boundary, to continue from.

A (duration, temperature) protocol run records its state after every step it completes
(``FullResult.boundary_states``); ``simulate(..., initial=state)`` continues the same protocol
from there, in protocol time, as the one run of the whole protocol would (every step
restarts the integrator: a new temperature takes a small first step and stops the moving
grid's nodes).  The state is the profile the grid's state is rebuilt from exactly up to
round-off: the radius, the cell porosities and, on the moving grid, the dry node radii of
its cells (the mesh is kept, not adapted anew).  Plain JSON data for the run store
(:meth:`to_data` / :meth:`from_data`; the keys are those of the planner's earlier stored
runs' ``meta['boundary_states']``, so those read too), or as arrays in a run's npz
(:func:`states_to_arrays`).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

import numpy as np

# the solver's counters a state carries, summed over the run up to it
COUNTERS = ("steps", "rejected", "jacobians", "rhs_calls", "merges", "mesh_checks", "remaps")


@dataclass(frozen=True, eq=False)
class BoundaryState:
    """The state after the first ``steps`` protocol steps, at protocol time ``t``:
    radius a, cell porosities ``phi`` and, on the moving grid, the cells' dry node radii
    ``nodes`` (None on the fixed grids); ``counters`` the solver's work up to there
    (``COUNTERS``).  ``stopped``: not a boundary but where the ``stop`` event ended the run
    inside step ``steps`` (a read-off heating's end, dosing.restart.stopped_as_run)."""

    t: float
    steps: int
    radius: float
    phi: np.ndarray
    nodes: np.ndarray | None = None
    counters: dict[str, float] = field(default_factory=dict)
    stopped: bool = False

    def to_data(self) -> dict[str, Any]:
        """Plain JSON data (lists and floats)."""
        out: dict[str, Any] = {
            "steps": int(self.steps), "t": float(self.t), "radius": float(self.radius),
            "phi": np.asarray(self.phi, dtype=float).tolist(),
            "nodes": None if self.nodes is None else np.asarray(self.nodes,
                                                                 dtype=float).tolist(),
            "counters": {k: v for k, v in self.counters.items()}}
        if self.stopped:
            out["stopped"] = True
        return out

    @classmethod
    def from_data(cls, data: dict[str, Any]) -> BoundaryState:
        """Inverse of :meth:`to_data`."""
        nodes = data.get("nodes")
        return cls(t=float(data["t"]), steps=int(data["steps"]), radius=float(data["radius"]),
                   phi=np.asarray(data["phi"], dtype=float),
                   nodes=None if nodes is None else np.asarray(nodes, dtype=float),
                   counters=dict(data.get("counters") or {}),
                   stopped=bool(data.get("stopped", False)))


def states_from_data(items: Any) -> list[BoundaryState]:
    """A list of states from plain data (None or [] -> [])."""
    return [BoundaryState.from_data(d) for d in items or []]


ARRAY_KEYS = ("state_t", "state_steps", "state_radius", "state_phi", "state_nodes",
              "state_stopped", "state_counters")


def states_to_arrays(states: list[BoundaryState]) -> dict[str, np.ndarray]:
    """States as the arrays of a run's npz (``ARRAY_KEYS``: binary, exact and quicker to
    write than their JSON); the counters as one JSON string."""
    if not states:
        return {}
    nodes = [st.nodes for st in states]
    return {"state_t": np.array([st.t for st in states], dtype=float),
            "state_steps": np.array([st.steps for st in states], dtype=np.int64),
            "state_radius": np.array([st.radius for st in states], dtype=float),
            "state_phi": np.vstack([np.asarray(st.phi, dtype=float) for st in states]),
            "state_nodes": (np.vstack([np.asarray(x, dtype=float) for x in nodes])
                            if all(x is not None for x in nodes) else np.zeros((0, 0))),
            "state_stopped": np.array([st.stopped for st in states], dtype=bool),
            "state_counters": np.array(json.dumps([st.counters for st in states]))}


def states_from_arrays(data: Any) -> list[BoundaryState]:
    """Inverse of :func:`states_to_arrays` (``data``: a mapping holding its arrays; an npz
    file decompresses an array on every access, so each is read once)."""
    if "state_t" not in data:
        return []
    t, k, a, phi, nodes, stopped = (np.asarray(data[name]) for name in ARRAY_KEYS[:-1])
    counters = json.loads(str(data["state_counters"]))
    return [BoundaryState(t=float(t[i]), steps=int(k[i]), radius=float(a[i]),
                          phi=phi[i].copy(), nodes=nodes[i].copy() if nodes.size else None,
                          counters=dict(counters[i]), stopped=bool(stopped[i]))
            for i in range(t.size)]


def protocol_boundaries(steps: Any) -> list[float]:
    """The time at the start of each (duration, temperature) step and at the end, summed
    as the solver sums its segments."""
    out, t = [0.0], 0.0
    for duration, _ in steps:
        t += duration
        out.append(t)
    return out
