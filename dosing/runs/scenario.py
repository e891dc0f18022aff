"""The dimensionless scenario (the cache key) and the full-solver run that serves it.

One dimensionless run serves every bead size and dose: the key holds the gel's dimensionless
parameters and permeability law, the start temperature and branch, the protocol, the solver
settings and the code version.  :func:`run_scenario`: plain data in, an ``.npz`` blob out, for
any executor (docs/architecture.md, "The run store")."""

from __future__ import annotations

import functools
import hashlib
import json
import math
import os
import threading
import time
from array import array
from collections.abc import Callable
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any

import numpy as np

from solver.errors import BudgetExceeded, ParameterError, SolverError, require_finite_positive
from solver.full.result import FullResult
from solver.gel import Gel, check_temperature
from solver.json_safe import json_safe
from solver.limits import (
    LADDER_RUNGS,
    TRUTH_DIRECT_ELL_RANGE,
    TRUTH_LADDER_ELL_RANGE,
    TRUTH_LADDER_START_RANGE,
    TRUTH_N_RANGE,
)

SCHEMA = 1
# the names of the solver's grid registry (solver.full.grids.GRIDS, in its order; written
# out so that settings and the CLI's options load no kernels: tests/test_speed_imports.py
# checks that they agree)
GRIDS = ("eulerian", "lagrangian", "moving")
INTEGRATORS = ("implicit", "explicit")
METHODS = ("direct", "ladder")
N_RANGE = TRUTH_N_RANGE  # the ranges are solver.limits' (one definition)
ELL_RANGE = TRUTH_LADDER_ELL_RANGE
DIRECT_ELL_RANGE = TRUTH_DIRECT_ELL_RANGE
LADDER_TOP = TRUTH_LADDER_START_RANGE[1]  # a ladder's coarsest ell (solver.limits)


DEFAULT_INTERFACIAL_LENGTH = 0.005  # coarsest rung of the validation ladder (dry radii)
# ell of the direct truth without a bead size: the ell -> 0 limit, pinned by a direct run at
# 1e-4 (HHT t80 0.074350, -0.34 % from the limit 0.0746; ANB 0.077842, +0.18 % from 0.0777:
# docs/moving_mesh.md sec. 4)
LIMIT_INTERFACIAL_LENGTH = 1e-4
DIRECT_N = 400  # moving-grid cells of a direct run (its check run has DIRECT_N / 2)
CELLS_PER_LENGTH = 4  # Lagrangian cells per ell: t80 converged to 1e-4 (docs/interfacial.md)
RUNGS = LADDER_RUNGS  # ladder ell, ell/2, ell/4: the observed order and the limit


@dataclass(frozen=True)
class SolverSettings:
    """Full-solver settings that define a validation (all part of the scenario key).  ``method``
    'direct' (default, issue 12): the regularized model at ell on the moving grid, checked at n / 2
    (:meth:`rungs`); 'ladder' (issue 8): the ell -> 0 limit from ell, ell/2, ell/4; ell = 0: the
    paper's model.  ``interfacial_length`` None: the bead's own (docs/interfacial.md sec. 9)."""

    grid: str | None = None
    n: int | None = None
    integrator: str = "implicit"
    rtol: float | None = None
    interfacial_length: float | None = None
    method: str = "direct"

    def __post_init__(self) -> None:
        if self.method not in METHODS:
            raise ParameterError("settings.method", self.method, " or ".join(map(repr, METHODS)))
        direct = self.method == "direct"
        object.__setattr__(self, "auto_length", self.interfacial_length is None)
        if self.interfacial_length is None:
            ell = LIMIT_INTERFACIAL_LENGTH if direct else DEFAULT_INTERFACIAL_LENGTH
        else:
            ell = _interfacial_length(self.interfacial_length,
                                      DIRECT_ELL_RANGE if direct else ELL_RANGE)
        object.__setattr__(self, "interfacial_length", ell)
        if self.grid is None:
            object.__setattr__(self, "grid", "eulerian" if ell == 0.0 else
                               "moving" if direct else "lagrangian")
        if self.grid not in GRIDS:
            raise ParameterError("settings.grid", self.grid, " or ".join(map(repr, GRIDS)))
        if self.integrator not in INTEGRATORS:
            raise ParameterError("settings.integrator", self.integrator,
                                 " or ".join(map(repr, INTEGRATORS)))
        if self.grid == "moving" and self.integrator != "implicit":
            raise ParameterError("settings.integrator", self.integrator,
                                 "'implicit' on the moving grid")
        if self.n is None:
            object.__setattr__(self, "n", 400 if ell == 0.0 or direct else
                               math.ceil(CELLS_PER_LENGTH / ell - 1e-9))
        if isinstance(self.n, bool) or not isinstance(self.n, (int, np.integer)) or not (
                N_RANGE[0] <= int(self.n) <= N_RANGE[1]):
            raise ParameterError("settings.n", self.n, f"an integer {N_RANGE[0]}-{N_RANGE[1]}")
        object.__setattr__(self, "n", int(self.n))
        rtol = require_finite_positive("settings.rtol", self.rtol if self.rtol is not None
                                       else (1e-5 if ell > 0.0 else 1e-6))
        if rtol > 1e-2:
            raise ParameterError("settings.rtol", self.rtol, "0 < rtol <= 1e-2")
        object.__setattr__(self, "rtol", rtol)

    @property
    def regularized(self) -> bool:
        """True for the regularized model (ell > 0), False for the paper's."""
        return self.interfacial_length > 0.0

    @property
    def direct(self) -> bool:
        """True for the direct truth (the regularized model at this ell, no extrapolation)."""
        return self.method == "direct" and self.regularized

    def with_length(self, ell: float) -> SolverSettings:
        """These settings at interfacial length ``ell`` (n, grid and rtol kept)."""
        return replace(self, interfacial_length=ell)

    def check(self) -> SolverSettings:
        """The numerical check of these settings: the same run on n / 2 cells (at least
        N_RANGE[0]); its gap to this run is the numerical part of an answer's error."""
        return replace(self, n=max(self.n // 2, N_RANGE[0]))

    def rungs(self) -> list[SolverSettings]:
        """The validation runs: direct, this run and its check with n / 2 cells; a ladder,
        ell / 2^k with n 2^k cells (k < RUNGS); the paper's model, this grid and then the
        other fixed one."""
        if not self.regularized:
            fixed = [g for g in GRIDS if g != "moving"]
            return [replace(self, grid=g)
                    for g in (self.grid, *(g for g in fixed if g != self.grid))]
        if self.direct:
            if self.n // 2 < N_RANGE[0]:
                raise ParameterError("settings.n", self.n, f"an integer {2 * N_RANGE[0]}-"
                                     f"{N_RANGE[1]} (the check run has n / 2 cells)")
            return [self, self.check()]
        scale = 1 << (RUNGS - 1)
        if not ELL_RANGE[0] * scale <= self.interfacial_length <= LADDER_TOP:
            raise ParameterError("settings.interfacial_length", self.interfacial_length,
                                 f"0 or {ELL_RANGE[0] * scale:g}-{LADDER_TOP:g} dry radii "
                                 f"(the ladder goes down to ell / {scale})")
        if self.n * scale > N_RANGE[1]:
            raise ParameterError("settings.n", self.n, f"an integer {N_RANGE[0]}-"
                                 f"{N_RANGE[1] // scale} (the ladder's finest rung has {scale} "
                                 f"times more cells)")
        return [SolverSettings(self.grid, self.n << k, self.integrator, self.rtol,
                               self.interfacial_length / (1 << k), self.method)
                for k in range(RUNGS)]

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form (the resolved values: every field that changes the run; each is
        a str, int or float, so no copy is needed: ``asdict`` cost a third of a key)."""
        return {name: getattr(self, name) for name in _SETTINGS_FIELDS}

    def request_dict(self) -> dict[str, Any]:
        """Plain-data form as asked for: ``interfacial_length`` None when it was not given
        (the bead's own, set per request), so the settings can be sent on unresolved."""
        d = self.to_dict()
        if self.auto_length:
            d["interfacial_length"] = None
        return d


def _interfacial_length(value: Any, bounds: tuple[float, float] = ELL_RANGE) -> float:
    """A validated settings.interfacial_length: 0 or within ``bounds`` (dry radii)."""
    try:
        ell = float(value)
    except (TypeError, ValueError):
        ell = math.nan
    if isinstance(value, bool) or not (ell == 0.0 or bounds[0] <= ell <= bounds[1]):
        raise ParameterError("settings.interfacial_length", value,
                             f"0 (the paper's model) or {bounds[0]:g}-{bounds[1]:g} dry "
                             "radii")
    return ell


_SETTINGS_FIELDS = tuple(f.name for f in fields(SolverSettings))
TRUTH = SolverSettings()  # the validation truth: a direct run (the bead's own ell, or 1e-4)
LADDER = SolverSettings(method="ladder")  # issue 8's truth: the ladder's limit ell -> 0
PAPER = SolverSettings(interfacial_length=0.0)  # the paper's model: Eulerian grid, N = 400


@functools.cache
def code_version() -> str:
    """Digest of the solver sources a full-solver run depends on (not the front model, nor
    the passive solute, which never changes the mechanics: drug runs key on it themselves)."""
    import solver

    root = Path(solver.__file__).parent
    h = hashlib.sha256()
    for p in sorted(root.rglob("*.py")):
        if p.relative_to(root).parts[0] in ("front", "front.py", "fit", "solute"):
            continue  # not the full solver
        h.update(p.relative_to(root).as_posix().encode())
        h.update(p.read_bytes())
    return h.hexdigest()[:16]


Step = tuple[float, float]
# the key's canonical JSON (json.dumps(..., sort_keys=True, separators=(",", ":")), with the
# encoder built once)
_KEY_JSON = json.JSONEncoder(sort_keys=True, separators=(",", ":"))
RUN_BUDGET_S = 600.0  # wall time of one validation run (the default ladder's largest: ~65 s)
RUN_BUDGET_ENV = "THERMOGEL_RUN_SECONDS"  # the service's setting of that budget


def run_budget(default: float = RUN_BUDGET_S) -> float:
    """The wall seconds one full-solver run may take (all its calls of the solver):
    $THERMOGEL_RUN_SECONDS when set to a number > 0, else ``default``.  Read where the run
    starts (a pool worker inherits the service's environment)."""
    raw = os.environ.get(RUN_BUDGET_ENV, "")
    try:
        x = float(raw) if raw.strip() else default
    except ValueError:
        return default
    return x if math.isfinite(x) and x > 0.0 else default


def hard_limit(budget: float) -> float:
    """When a run that has not stopped at its ``budget`` is killed from outside (its
    worker: ``dosing.runs.jobs.JobRunner(hard_seconds=...)``): the budget, plus half of it or
    at least a minute for the record to be written."""
    return float(budget) + max(60.0, 0.5 * float(budget))


@dataclass(frozen=True)
class Scenario:
    """A dimensionless full-solver run: one jump (``t_end``) or a protocol of steps (``protocol``:
    (duration, temperature) steps from the equilibrium at ``t_start`` on ``branch``).  A jump has
    no fixed duration: its run is extended until the radius asked for is reached, and the cache
    keeps one row per scenario."""

    gel: Gel
    t_start: float
    t_end: float | None = None
    protocol: tuple[Step, ...] | None = None
    branch: str = "swollen"
    settings: SolverSettings = field(default_factory=SolverSettings)
    # a continuous temperature program (dosing.heating.program.program_spec) and the
    # radius at which its run stops (a terminal event); in place of t_end / protocol
    program: Any = None
    stop: float | None = None
    # a protocol's last step ends where the fluid it expels, a^3 at its start minus a^3
    # (volumes in 4 pi / 3 dry volumes), reaches this (a terminal event: a read-off heating)
    stop_expelled: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "t_start", check_temperature(self.t_start, "t_start"))
        if self.stop_expelled is not None:
            v = float(self.stop_expelled)
            if self.protocol is None or not (math.isfinite(v) and v > 0.0):
                raise ParameterError("stop_expelled", self.stop_expelled,
                                     "a volume > 0 with a protocol")
            object.__setattr__(self, "stop_expelled", v)
        if self.program is not None:
            if self.t_end is not None or self.protocol is not None:
                raise ParameterError("program", "with t_end/protocol", "one of them")
            object.__setattr__(self, "program", _interned(self.program))
            return
        if (self.t_end is None) == (self.protocol is None):
            raise ParameterError("protocol", self.protocol, "exactly one of t_end or protocol")
        if self.t_end is not None:
            object.__setattr__(self, "t_end", check_temperature(self.t_end, "t_end"))
        else:
            steps = tuple((float(d), check_temperature(t, "protocol.temperature"))
                          for d, t in self.protocol)
            for d, _ in steps:
                if not math.isfinite(d) or d < 0.0:
                    raise ParameterError("protocol.duration", d, "a finite number >= 0")
            object.__setattr__(self, "protocol", steps)

    def key_dict(self) -> dict[str, Any]:
        """Everything that defines the dimensionless answer (JSON-ready, canonical)."""
        what: dict[str, Any] = ({"t_end": self.t_end} if self.t_end is not None
                                else {"program": plain(self.program), "stop": self.stop}
                                if self.program is not None
                                else {"protocol": [list(s) for s in self.protocol]})
        if self.stop_expelled is not None:
            what["stop_expelled"] = self.stop_expelled
        return {"schema": SCHEMA, "gel": list(self.gel.key()), "t_start": self.t_start, **what,
                "branch": self.branch, "settings": self.settings.to_dict(),
                "code": code_version()}

    def key(self) -> str:
        """The cache key: a digest of the canonical JSON of :meth:`key_dict` (computed once:
        a scenario is immutable, and a front answer asks for its runs' keys several times)."""
        return self._key

    @functools.cached_property
    def _key(self) -> str:
        text = _KEY_JSON.encode(self.key_dict())
        return hashlib.sha256(text.encode()).hexdigest()[:32]

    def to_dict(self, compact: bool = False) -> dict[str, Any]:
        """Plain data for a worker process (and for humans); ``compact``: a program's long
        columns stay ``array('d')`` (a queued run's arguments; they pickle)."""
        return {"gel": self.gel.to_dict(), "t_start": self.t_start, "t_end": self.t_end,
                "protocol": None if self.protocol is None else [list(s) for s in self.protocol],
                "branch": self.branch, "settings": self.settings.to_dict(),
                **({} if self.program is None else {
                    "program": self.program if compact else plain(self.program),
                    "stop": self.stop}),
                **({} if self.stop_expelled is None
                   else {"stop_expelled": self.stop_expelled})}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Scenario:
        """Inverse of :meth:`to_dict`."""
        prot = d.get("protocol")
        return cls(Gel.from_dict(d["gel"]), d["t_start"], d.get("t_end"),
                   None if prot is None else tuple(tuple(s) for s in prot),
                   d.get("branch", "swollen"), SolverSettings(**d.get("settings", {})),
                   d.get("program"), d.get("stop"), d.get("stop_expelled"))

    def steps(self, horizon: float) -> list[Step]:
        """The protocol to simulate (a jump becomes one step of length ``horizon``)."""
        if self.protocol is not None:
            return list(self.protocol)
        return [(float(horizon), self.t_end)]


Trajectory = FullResult

# numpy reads an npz member's header with ast.literal_eval, and CPython 3.11's AST
# constructor can raise a spurious SystemError ("AST constructor recursion depth mismatch",
# python/cpython#106905) when threads compile at once: the store decodes one blob at a time
NPZ_LOCK = threading.Lock()


def decode(blob: bytes, meta: dict[str, Any]) -> Trajectory:
    """A stored run from its npz blob and metadata (one thread at a time: NPZ_LOCK)."""
    with NPZ_LOCK:
        return Trajectory.from_npz(blob, meta)
"""A stored full-solver run: the one run record, :class:`solver.full.result.FullResult`,
without profiles (:meth:`FullResult.without_profiles`), with its cache ``meta``."""

Solver = Callable[..., FullResult]
"""What the planner runs a scenario with: ``solver.full.simulate`` or a stand-in taking its
arguments (``gel, t_start, protocol=, grid=, n=, integrator=, rtol=, branch=,
interfacial_length=, max_seconds=``, and ``stop=`` for a jump run that may end at its dose)
and returning a :class:`FullResult`."""

# a jump's run ends where its radius reaches the dose's (simulate's terminal event): at the
# dose radius less this relative margin, so that the stored run covers the dose itself
# (the event's radius is exact to ~1e-8; 1e-6 of the radius moves an 80 % dose time by
# ~2e-6 relative, far inside every numerical bound)
STOP_MARGIN = 1e-6


def _simulate(sc: Scenario, horizon: float, budget: float, solver: Solver,
              stop: float | None = None, start: Any = None) -> FullResult:
    """One run of ``sc`` (a jump runs for ``horizon``, or until its radius reaches
    ``stop``) within ``budget`` s, as stored.  A protocol runs from ``start`` (a
    :class:`dosing.runs.restart.Start`, or t = 0) where the solver continues exactly, its record
    keeping the state after each step (``FullResult.boundary_states``)."""
    from . import restart

    s = sc.settings
    if sc.protocol is not None and restart.restartable(solver):
        res = rec = restart.run_protocol(sc, solver, budget, start)
    else:
        if sc.program is not None:  # a continuous temperature program (dosing.heating.grammar)
            from ..heating.program import solver_program

            kw = {"protocol": solver_program(sc.program), "stop": sc.stop}
        else:
            kw = {"protocol": sc.steps(horizon), **({} if stop is None else {"stop": stop})}
        res = solver(sc.gel, sc.t_start, **kw, grid=s.grid, n=s.n,
                     integrator=s.integrator, rtol=s.rtol, branch=sc.branch,
                     interfacial_length=s.interfacial_length, max_seconds=budget)
        rec = res.without_profiles()
    if rec.t.size < 2 or not (np.all(np.isfinite(rec.t)) and np.all(np.isfinite(rec.radius))):
        raise SolverError("the full solver returned no finite a(t)", {"scenario": sc.key_dict()})
    rec.diagnostics = {**json_safe(res.diagnostics, max_array=64), "spinodal": bool(res.spinodal)}
    return rec


def _interned(program: Any) -> Any:
    """A program as plain JSON data, one shared copy per program (issue 40, R7): a
    request's runs (the truth, its check, the ell range, ...) are scenarios of one program,
    and a 100,000-row trace's copy weighs megabytes.  Programs are read, never mutated."""
    from .lru import ByteLRU

    global _PROGRAMS
    if _PROGRAMS is None:
        _PROGRAMS = ByteLRU(64e6)  # canonical programs by their JSON's digest
    text = json.dumps(program, default=_listed)
    digest = hashlib.sha256(text.encode()).hexdigest()
    hit = _PROGRAMS.get(digest)
    if hit is None:
        hit = _compact(json.loads(text))
        _PROGRAMS[digest] = hit
    return hit


_PROGRAMS: Any = None
COMPACT_FROM = 256  # a list of this many floats is held as array('d'): 8 bytes a number


def _listed(obj: Any) -> Any:
    """json's ``default``: a compact column as the list it stands for."""
    if isinstance(obj, array):
        return obj.tolist()
    raise TypeError(f"{type(obj).__name__} is not JSON data")


def _compact(obj: Any) -> Any:
    """Long lists of floats as ``array('d')`` (a 100,000-row trace: 0.8 MB a column, not
    3.2 MB); :func:`plain` gives back the same lists (the same JSON, the same key)."""
    if isinstance(obj, list):
        if len(obj) >= COMPACT_FROM and all(type(x) is float for x in obj):
            return array("d", obj)
        return [_compact(x) for x in obj]
    if isinstance(obj, dict):
        return {k: _compact(v) for k, v in obj.items()}
    return obj


def plain(obj: Any) -> Any:
    """A program (or any JSON data) with its compact columns as plain lists."""
    if isinstance(obj, array):
        return obj.tolist()
    if isinstance(obj, (list, tuple)):
        return [plain(x) for x in obj]
    if isinstance(obj, dict):
        return {k: plain(v) for k, v in obj.items()}
    return obj


def run_scenario(scenario: dict[str, Any], horizon: float = 1.0, need_radius: float | None = None,
                 need_time: float = 0.0, max_horizon: float = 64.0, budget: float | None = None,
                 solver: Solver | None = None, stop: bool = True,
                 start: Any = None) -> tuple[dict, bytes]:
    """Run the full solver for a scenario: plain data in, (metadata, npz blob) out; top-level and
    free of shared state (any executor).  A jump runs to ``need_radius`` and ``need_time`` (horizon
    x4 up to ``max_horizon``; ``stop``: a terminal event), a protocol from ``start``; all in
    ``budget`` wall seconds (BudgetExceeded) on ``solver`` (docs/architecture.md, run store)."""
    if solver is None:
        from .full import full_solver

        solver = full_solver()
    sc = Scenario.from_dict(scenario)
    wall = time.perf_counter()
    budget = run_budget() if budget is None else float(budget)

    def left() -> float:  # what the next call may spend of the budget (the first: all)
        if runs == 0:
            return budget
        spent = time.perf_counter() - wall
        if spent >= budget:
            raise BudgetExceeded(
                f"the full-solver run ({sc.settings.grid} grid, N = {sc.settings.n}, "
                f"interfacial length {sc.settings.interfacial_length:g}) used its "
                f"{budget:.0f} s budget after {runs} solver calls",
                {"wall_seconds": spent, "scenario": sc.key_dict()})
        return budget - spent

    h = float(horizon)
    runs = 0
    end = (need_radius * (1.0 - STOP_MARGIN)
           if stop and sc.protocol is None and sc.program is None and need_radius is not None
           and sc.settings.integrator == "implicit" else None)  # events need the implicit one
    while True:
        traj = _simulate(sc, max(h, need_time), left(), solver, end, start)
        runs += 1
        if end is not None and traj.status == "stopped" and traj.horizon < need_time:
            traj = _simulate(sc, need_time, left(), solver)  # the truth's front-time need
            runs += 1
        if (sc.protocol is not None or sc.program is not None or need_radius is None
                or traj.radius.min() <= need_radius):
            break
        if h >= max_horizon:
            raise SolverError(
                f"a(t) does not reach {need_radius:.6g} by t = {traj.horizon:.4g} (it is "
                f"{traj.radius[-1]:.6g}): the dose is too close to the final equilibrium",
                {"scenario": sc.key_dict(), "horizon": traj.horizon})
        h = min(4.0 * h, max_horizon)
    meta = {"scenario": sc.key_dict(), "key": sc.key(), "horizon": traj.horizon,
            "wall_seconds": time.perf_counter() - wall, "runs": runs, "created": time.time(),
            "diagnostics": traj.diagnostics, **traj.meta}
    traj.meta = meta
    return meta, traj.to_npz()
