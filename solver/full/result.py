"""FullResult: the one record of a full PDE run (arrays plus diagnostics), fresh or stored.

The solver returns it with every output's profiles; the planner's cache keeps it without
them (:meth:`FullResult.without_profiles`: a(t), R_f(t), the expelled volume, T(t) and the
per-step record) as an ``.npz`` blob (:meth:`to_npz` / :meth:`from_npz`, the one codec:
:meth:`save` / :meth:`load` write and read the same bytes as a file).  Missing values: a
time that does not exist (no nucleation) is None, never NaN; a radius never reached raises
ValueError; array entries without a value (no front at an output) are NaN, which the JSON
form turns into null.
"""

from __future__ import annotations

import io
import json
import math
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..crossing import first_fall, hermite_root, linear_cube_root
from ..json_safe import json_safe
from ..presenters import html_or_none, presenter
from .state import (
    COUNTERS,
    BoundaryState,
    states_from_arrays,
    states_from_data,
    states_to_arrays,
)

_ARRAYS = ("t", "radius", "front", "jump", "phi", "coords", "temperature", "expelled_volume",
           "solid_error", "step_t", "step_radius", "step_rate", "step_edge", "nodes")
# what a stored run keeps (the planner's cache; also the arrays of its older blobs)
RECORD_ARRAYS = ("t", "radius", "front", "expelled_volume", "temperature", "step_t",
                 "step_radius", "step_rate", "step_edge")
DEFAULT_OUTPUTS = 200  # a run's outputs over its length unless told (simulate's ``every``)
STATES = "boundary_states"  # older stored runs' meta key of the states
_PER_OUTPUT = ("t", "radius", "front", "jump", "phi", "temperature", "solid_error", "nodes")
_PER_STEP = ("step_t", "step_radius", "step_rate", "step_edge")


# radii this close (relative) are one radius: the last bits of the start radius differ
# between the equilibrium's root and the sum of the run's cell volumes (1e-16 seen)
SAME_RADIUS = 1e-12


def uniform_output_times(total: float, every: float | None = None) -> np.ndarray:
    """A run's outputs every ``every`` (default total / DEFAULT_OUTPUTS) from 0, and
    ``total``."""
    every = total / DEFAULT_OUTPUTS if every is None else every
    k = int(math.floor(total / every + 1e-9))
    times = np.unique(np.concatenate([np.arange(k + 1) * every, [total]]))
    return times[times <= total]


def _empty() -> np.ndarray:
    return np.zeros(0)


def _empty2() -> np.ndarray:
    return np.zeros((0, 0))


@dataclass
class FullResult:
    """Outputs of :func:`solver.full.simulate` (dimensionless, as in the paper).

    Per output time t: radius a(t), front R_f(t) (r units, NaN without a sharp front),
    porosity jump at the front (core minus shell, NaN without a front), porosity
    snapshots phi (len(t), n) at ``coords`` (cell centres: R = r/a on the Eulerian grid,
    the dry coordinate rho on the Lagrangian grid), temperature, expelled fluid volume
    (eq. FluidVolExpelled) and the relative solid-volume error.  ``step_*`` hold a,
    da/dt and the edge cell's porosity at every accepted step (dense a(t) for crossing
    times; the time a front nucleates at the edge).  On the moving grid ``nodes`` holds
    every output's dry node radii (len(t), n + 1), the cells ``phi`` refers to, and
    ``coords`` the last output's cell midpoints; on fixed grids it is empty.  A stored run
    (the planner's cache) has no profiles (``phi``, ``coords``, ``jump``, ``solid_error``,
    ``nodes`` empty) and carries ``meta``: its cache key, scenario, horizon, wall time.
    A protocol run's ``boundary_states`` hold its state after every step it completed
    (:class:`~solver.full.state.BoundaryState`; the last one where a ``stop`` ended it,
    marked ``stopped``): what ``simulate(..., initial=state)`` continues from, and
    :meth:`after` joins such a continued run to the record before it.
    """

    t: np.ndarray
    radius: np.ndarray
    front: np.ndarray
    jump: np.ndarray = field(default_factory=_empty)
    phi: np.ndarray = field(default_factory=_empty2)
    coords: np.ndarray = field(default_factory=_empty)
    temperature: np.ndarray = field(default_factory=_empty)
    expelled_volume: np.ndarray = field(default_factory=_empty)
    solid_error: np.ndarray = field(default_factory=_empty)
    spinodal: bool = False
    diagnostics: dict[str, Any] = field(default_factory=dict)
    step_t: np.ndarray = field(default_factory=_empty)
    step_radius: np.ndarray = field(default_factory=_empty)
    step_rate: np.ndarray = field(default_factory=_empty)
    step_edge: np.ndarray = field(default_factory=_empty)
    nodes: np.ndarray = field(default_factory=_empty2)
    meta: dict[str, Any] = field(default_factory=dict)
    boundary_states: list[BoundaryState] = field(default_factory=list)

    @property
    def grid(self) -> str:
        """'eulerian', 'lagrangian' or 'moving'."""
        return str(self.diagnostics.get("grid", "eulerian"))

    @property
    def horizon(self) -> float:
        """The last simulated time."""
        return float(self.t[-1])

    @property
    def status(self) -> str:
        """'stopped' (the ``stop`` event ended the run) or 'finished' (the horizon did)."""
        return str(self.diagnostics.get("status", "finished"))

    @property
    def t_events(self) -> np.ndarray:
        """Times of the terminal event (scipy's ``solve_ivp``): one time, or none."""
        return np.asarray(self.diagnostics.get("t_events") or [], dtype=float)

    @property
    def terminal_time(self) -> float | None:
        """The time the ``stop`` event ended the run (its last output), or None."""
        ev = self.t_events
        return float(ev[0]) if ev.size else None

    def _dense(self) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """(t, a, da/dt) at every accepted step, or (t, a, None) at the outputs."""
        if self.step_t.size >= 2:
            return self.step_t, self.step_radius, self.step_rate
        return self.t, self.radius, None

    def radius_at(self, time: float) -> float:
        """a(t), interpolated linearly between accepted steps (or outputs)."""
        t, a, _ = self._dense()
        return float(np.interp(time, t, a))

    def nucleation_time(self, level: float) -> float | None:
        """First time the edge cell's porosity falls to ``level`` (None if it never does, or
        the run has no per-step record): with a level between the swollen and shrunken
        porosities, when the front forms."""
        if self.step_edge.size != self.step_t.size or self.step_t.size < 2:
            return None
        t = first_fall(self.step_t, self.step_edge, level)
        return None if math.isnan(t) else t

    def time_to_radius(self, a_target: float, after: float = 0.0) -> float:
        """First time t >= ``after`` at which a(t) reaches ``a_target``, from the side a is on
        at ``after`` (it falls to a target below, rises to one above).

        Between accepted steps a(t) is the cubic Hermite interpolant of a and da/dt; between
        outputs (a record without steps, or from ``after`` to the next step) a^3 is linear
        in t, as the expelled volume (eq. FluidVolExpelled).  A target that is never
        crossed but lies within ``SAME_RADIUS`` of the radius at ``after`` is reached there
        (the start radius as the equilibrium gives it and as the run's cells sum it may
        differ in the last bits, on the side the bead moves away from; a target on the side
        it moves to is crossed, however close: a dose of 1e-15 has its own time).  Raises
        ValueError if the radius never reaches it.
        """
        target = float(a_target)
        t, a, rate = self._dense()
        start = max(float(after), float(t[0]))
        i0 = int(np.searchsorted(t, start, side="left"))
        a0 = float(a[i0]) if i0 < t.size and t[i0] == start else self.radius_at(start)
        if a0 == target:
            return start
        hit = np.nonzero((a[i0:] - target) * np.sign(a0 - target) <= 0.0)[0]
        if hit.size == 0 and abs(a0 - target) <= SAME_RADIUS * abs(target):
            return start  # the radius at the start, to its last bits, on the side left
        if hit.size == 0:
            rest = a[i0:] if i0 < t.size else a[-1:]
            raise ValueError(f"the radius never reaches {target:.6g} (range {rest.min():.6g} "
                             f"to {rest.max():.6g} over {start:.6g} <= t <= {t[-1]:.6g})")
        j = i0 + int(hit[0])
        if j == i0:  # between ``after`` and the next sample
            return linear_cube_root(start, a0, float(t[j]), float(a[j]), target)
        if rate is not None and t[j] > t[j - 1]:
            return float(hermite_root(t[j - 1], t[j], a[j - 1], a[j], rate[j - 1], rate[j],
                                      target))
        return linear_cube_root(float(t[j - 1]), float(a[j - 1]), float(t[j]), float(a[j]),
                                target)

    def state_at(self, time: float) -> tuple[float, float, np.ndarray]:
        """(a, R_f, phi profile) at ``time``, interpolated linearly between outputs."""
        x = float(time)
        if not self.phi.size:
            raise ValueError("this record keeps no profiles (a stored run)")
        if not (self.t[0] <= x <= self.t[-1]):
            raise ValueError(f"time {x:g} outside the run [{self.t[0]:g}, {self.t[-1]:g}]")
        k = int(np.searchsorted(self.t, x, side="right") - 1)
        k = min(max(k, 0), self.t.size - 1)
        if k == self.t.size - 1 or self.t[k + 1] == self.t[k]:
            return float(self.radius[k]), float(self.front[k]), self.phi[k].copy()
        w = (x - self.t[k]) / (self.t[k + 1] - self.t[k])
        a = (1 - w) * self.radius[k] + w * self.radius[k + 1]
        fr = (1 - w) * self.front[k] + w * self.front[k + 1]
        return float(a), float(fr), (1 - w) * self.phi[k] + w * self.phi[k + 1]

    def cell_radii(self) -> np.ndarray:
        """Cell-centre radii r at every output, shape (len(t), n)."""
        if self.grid == "eulerian":
            return self.radius[:, None] * self.coords[None, :]
        n = self.coords.size
        if self.nodes.size:
            w = np.diff(self.nodes**3, axis=1)
            r3 = np.cumsum(w / (1.0 - self.phi), axis=1)
        else:
            w = np.diff((np.arange(n + 1) / n) ** 3)
            r3 = np.cumsum(w[None, :] / (1.0 - self.phi), axis=1)
        lo = np.concatenate([np.zeros((r3.shape[0], 1)), r3[:, :-1]], axis=1)
        return np.cbrt(0.5 * (lo + r3))

    def boundary_state(self, steps: int) -> BoundaryState | None:
        """The state after the protocol's first ``steps`` steps (None if not kept)."""
        for st in self.boundary_states:
            if st.steps == steps and not st.stopped:
                return st
        return None

    def truncated(self, time: float) -> FullResult:
        """This run up to ``time`` (outputs and accepted steps at or before it; its states
        up to there; no meta)."""
        end = float(time) * (1.0 + 1e-12)
        keep, steps = self.t <= end, self.step_t <= end
        arrays = {k: np.asarray(getattr(self, k))[keep] for k in (*_PER_OUTPUT,
                                                                  "expelled_volume")
                  if np.shape(getattr(self, k))[:1] == self.t.shape}
        arrays.update({k: np.asarray(getattr(self, k))[steps] for k in _PER_STEP
                       if np.shape(getattr(self, k)) == self.step_t.shape})
        states = [st for st in self.boundary_states if st.t <= end]
        return replace(self, **arrays, boundary_states=states, meta={})

    def after(self, prefix: FullResult) -> FullResult:
        """This run, continued from a protocol boundary (``simulate(..., initial=state)``),
        as one run of the whole protocol records it: ``prefix`` (a run of the same
        protocol's first steps, e.g. a stored one; its state there is where this one
        started) up to the boundary, then this run.  Outputs: the prefix's up to the
        boundary, then this run's after them; per-step record: the prefix's up to the
        boundary, this run's after it (its record at the boundary is the new step's rate,
        the one-shot run keeps the old one's); profiles only where both have them;
        counters summed (``diagnostics['restarted_after_steps']``: the steps before)."""
        start = self.diagnostics.get("start")
        if not start:
            raise ValueError("this run did not continue from a protocol boundary")
        t_s, j = float(start["t"]), int(start["steps"])
        pre = prefix.truncated(t_s)
        state = pre.boundary_state(j)
        last = float(pre.t[-1]) if pre.t.size else -math.inf
        mine, steps = self.t > last, self.step_t > t_s * (1.0 + 1e-12)
        arrays: dict[str, np.ndarray] = {}
        for name in _PER_OUTPUT:
            a, b = np.asarray(getattr(pre, name)), np.asarray(getattr(self, name))
            if (a.shape[:1] == pre.t.shape and b.shape[:1] == self.t.shape and a.size
                    and b.size and a.shape[1:] == b.shape[1:]):
                arrays[name] = np.concatenate([a, b[mine]])
            else:
                arrays[name] = _empty2() if a.ndim == 2 or b.ndim == 2 else _empty()
        for name in _PER_STEP:
            arrays[name] = np.concatenate([np.asarray(getattr(pre, name), dtype=float),
                                           np.asarray(getattr(self, name), dtype=float)[steps]])
        a = arrays["radius"]
        arrays["expelled_volume"] = 4.0 * np.pi / 3.0 * (a[0] ** 3 - a**3)
        diag = dict(self.diagnostics)
        base = state.counters if state is not None else {}
        for name in COUNTERS:
            if name in base or name in diag:
                diag[name] = base.get(name, 0) + diag.get(name, 0)
        diag["restarted_after_steps"] = j
        states = [st for st in pre.boundary_states if st.steps <= j and not st.stopped]
        return replace(self, **arrays, spinodal=bool(pre.spinodal or self.spinodal),
                       diagnostics=diag, boundary_states=states + list(self.boundary_states),
                       meta={})

    def to_json_dict(self, profiles: bool = True) -> dict[str, Any]:
        """JSON-ready dict (NaN -> None); ``profiles=False`` drops the phi snapshots."""
        out: dict[str, Any] = {}
        for name in _ARRAYS:
            if name in ("phi", "nodes") and not profiles:
                continue
            if name == "nodes" and not self.nodes.size:
                continue
            out[name] = getattr(self, name)
        out["spinodal"] = bool(self.spinodal)
        out["diagnostics"] = self.diagnostics
        return json_safe(out)

    def without_profiles(self) -> FullResult:
        """This run as the planner stores it: a(t), R_f(t), the expelled volume, T(t) and
        the per-step record (``RECORD_ARRAYS``), diagnostics and meta; no profiles."""
        return replace(self, jump=_empty(), phi=_empty2(), coords=_empty(),
                       solid_error=_empty(), nodes=_empty2(),
                       **{k: np.asarray(getattr(self, k), dtype=float) for k in RECORD_ARRAYS})

    def to_npz(self) -> bytes:
        """The run as ``.npz`` bytes: every array, ``spinodal``, the diagnostics as JSON and
        the boundary states (:func:`~solver.full.state.states_to_arrays`; ``meta`` is not
        in it: the cache keeps it beside the blob)."""
        buf = io.BytesIO()
        np.savez_compressed(buf, spinodal=np.array(bool(self.spinodal)),
                            diagnostics=np.array(json.dumps(json_safe(self.diagnostics))),
                            **states_to_arrays(self.boundary_states),
                            **{name: np.asarray(getattr(self, name)) for name in _ARRAYS})
        return buf.getvalue()

    @classmethod
    def from_npz(cls, blob: bytes, meta: dict[str, Any] | None = None) -> FullResult:
        """Inverse of :meth:`to_npz`; also reads the planner's older blobs (the arrays of
        ``RECORD_ARRAYS`` alone: diagnostics and ``spinodal`` then come from
        ``meta['diagnostics']``; boundary states from ``meta['boundary_states']``, where
        the planner kept them before the solver did)."""
        meta = dict(meta or {})
        with np.load(io.BytesIO(blob), allow_pickle=False) as data:
            kwargs: dict[str, Any] = {f.name: np.array(data[f.name]) for f in fields(cls)
                                      if f.name in _ARRAYS and f.name in data}
            diag = (json.loads(str(data["diagnostics"])) if "diagnostics" in data
                    else dict(meta.get("diagnostics") or {}))
            spinodal = (bool(data["spinodal"]) if "spinodal" in data
                        else bool(diag.get("spinodal", False)))
            states = states_from_arrays(data)
        older = meta.pop(STATES, None)
        return cls(**kwargs, spinodal=spinodal, diagnostics=diag, meta=meta,
                   boundary_states=states or states_from_data(older))

    def save(self, path: str | Path) -> Path:
        """Write :meth:`to_npz`'s bytes to an .npz file (the suffix is added if missing)."""
        p = Path(path)
        if p.suffix != ".npz":
            p = p.with_name(p.name + ".npz")
        p.write_bytes(self.to_npz())
        return p

    @classmethod
    def load(cls, path: str | Path) -> FullResult:
        """Read a file written by :meth:`save`."""
        return cls.from_npz(Path(path).read_bytes())

    # -- tables and files (presenters registered by dosing.export / dosing.tables) -------
    def to_xarray(self, dry_radius_um: float | None = None,
                  timescale_seconds: float | None = None, request: Any = None,
                  truth: str | None = None) -> Any:
        """This run as an xarray Dataset with units, long names and provenance
        (:func:`dosing.export.run_dataset`; um and s where the bead size and tau are given)."""
        return presenter("run_dataset")(self, dry_radius_um, timescale_seconds, request, truth)

    def to_netcdf(self, path: str | Path, **kwargs: Any) -> Path:
        """Write :meth:`to_xarray` to a netCDF file (``kwargs`` go to :meth:`to_xarray`)."""
        return presenter("to_netcdf")(self.to_xarray(**kwargs), path)

    def to_dataframe(self, dry_radius_um: float | None = None,
                     timescale_seconds: float | None = None) -> Any:
        """One row per output time (pandas; columns ``name [unit]``)."""
        return presenter("run_frame")(self, dry_radius_um, timescale_seconds)

    def _repr_html_(self) -> str | None:
        return html_or_none("run_html", self)
