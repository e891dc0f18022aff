"""simulate(): validate a scenario, build the grid and initial state, integrate, collect.

Time is in units of tau (eq. timescale).  A ``protocol`` treats tau as the same for every
step (the paper's choice: the few-kelvin changes of k_B T and viscosity are neglected); a
program (solver.heating) may carry the mobility factor m(T) (docs/heating.md).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from ..equilibrium import equilibrium
from ..errors import BudgetExceeded, ParameterError, SolverError
from ..gel import Gel, check_temperature, preset
from ..heating import DURATION_MAX, UNTIL_LIMIT, Program, Radius, Released
from . import front as fronts
from . import moving
from .grids import GRIDS, GridSpec, grid_spec
from .integrate import (
    Segment,
    Stats,
    StepControl,
    Watch,
    Workspace,
    run_explicit,
    run_implicit,
)
from .kernels import KernelParams
from .moving import MeshOptions, Rezoner
from .options import SolverOptions
from .result import DEFAULT_OUTPUTS, FullResult, uniform_output_times
from .state import COUNTERS, BoundaryState, protocol_boundaries
from .system import JAC_ANALYTIC, JAC_FD, porosity, solid_error

MAX_OUTPUTS = 100_000
MOVING_CODE = GRIDS["moving"].code
HOLD_AFTER = 1e3  # tau: how long a program run with ``stop`` holds after its last step

Initial = FullResult | BoundaryState | tuple[float, Sequence[float]] | None


def _protocol(t_end: float | None, until: float | None,
              protocol: Sequence[tuple[float, float]] | None) -> list[tuple[float, float]]:
    """The validated list of (duration, temperature) steps."""
    if protocol is None:
        if t_end is None or until is None:
            raise ParameterError("protocol", None, "a protocol, or both t_end and until")
        protocol = [(until, t_end)]
    elif t_end is not None or until is not None:
        raise ParameterError("protocol", protocol, "either a protocol or t_end/until, not both")
    steps = []
    try:
        items = list(protocol)
    except TypeError:
        raise ParameterError("protocol", protocol, "a list of (duration, temperature)") from None
    if not items:
        raise ParameterError("protocol", protocol, "at least one (duration, temperature) step")
    for k, item in enumerate(items):
        try:
            duration, temperature = item
            duration = float(duration)
        except (TypeError, ValueError):
            raise ParameterError(f"protocol[{k}]", item, "a (duration, temperature) pair") from None
        if not (math.isfinite(duration) and 0.0 < duration <= DURATION_MAX):
            raise ParameterError(f"protocol[{k}].duration", duration,
                                 f"0 < duration <= {DURATION_MAX:g}")
        steps.append((duration, check_temperature(temperature, f"protocol[{k}].temperature")))
    return steps


def _choice(field: str, value: Any, options: Sequence[str]) -> str:
    if value not in options:
        raise ParameterError(field, value, " or ".join(repr(o) for o in options))
    return str(value)


def _source_dry(initial: FullResult) -> tuple[np.ndarray, np.ndarray]:
    """(r, s) at the nodes of a result's last state: radius r enclosing the dry volume s."""
    phi = initial.phi[-1]
    spec = grid_spec(initial.grid)
    if spec.moving:
        nodes = initial.nodes[-1]
        y = moving.state_from_profile(float(initial.radius[-1]), phi, nodes)
        return np.concatenate([[0.0], y]), nodes**3
    src = spec.module
    y_src = src.state_from_profile(float(initial.radius[-1]), phi)
    return src.dry_profile(y_src, src.geometry(phi.size))


def _given_profile(initial: Any, n: int) -> tuple[float, np.ndarray]:
    """A validated (radius, phi) pair of ``initial``."""
    try:
        radius, phi = initial
        phi = np.asarray(phi, dtype=float)
        radius = float(radius)
    except (TypeError, ValueError):
        raise ParameterError("initial", initial, "a FullResult or (radius, phi profile)") from None
    if phi.shape != (n,) or not np.all((phi > 0.0) & (phi < 1.0)):
        raise ParameterError("initial", "phi", f"{n} cell porosities in (0, 1) on the grid")
    return radius, phi


def _initial_state(spec: GridSpec, gel: Gel, t_start: float, first_t: float,
                   branch: str | None, initial: Initial, n: int, mesh: MeshOptions,
                   ell: float, t0: float = 0.0) -> tuple[np.ndarray, np.ndarray, str]:
    """(state, geometry, branch) on the grid: uniform equilibrium, a FullResult's last state
    (remapped conservatively; the moving grid's first mesh is adapted to it), (a, phi), or
    a BoundaryState (its profile on its own nodes, at ``t0``, the run's start)."""
    mod = spec.module
    if initial is None:
        if branch is None:
            branch = "swollen" if first_t >= t_start else "shrunken"
        _choice("branch", branch, ("swollen", "shrunken"))
        eq = equilibrium(gel, t_start, branch)  # type: ignore[arg-type]
        if spec.moving:
            nodes = moving.initial_nodes(eq.stretch, lambda x: np.full(x.size - 1, eq.porosity),
                                         n, mesh, ell)
            return (moving.state(moving.state_from_profile(eq.stretch, np.full(n, eq.porosity),
                                                           nodes)),
                    moving.geometry(nodes), branch)
        return mod.state_from_profile(eq.stretch, np.full(n, eq.porosity)), mod.geometry(n), branch
    if isinstance(initial, FullResult):
        r, s = _source_dry(initial)
        if spec.moving:
            def phi_of(x: np.ndarray) -> np.ndarray:
                y = np.cbrt(np.interp(x[1:] ** 3, s, r**3))
                return 1.0 - np.diff(x**3) / np.diff(np.concatenate([[0.0], y**3]))

            nodes = moving.initial_nodes(float(r[-1]), phi_of, n, mesh, ell)
            return (moving.state(np.cbrt(np.interp(nodes[1:] ** 3, s, r**3))),
                    moving.geometry(nodes), "given")
        return mod.state_from_dry(r, s, n), mod.geometry(n), "given"
    nodes = None
    if isinstance(initial, BoundaryState):  # a protocol boundary: its profile and mesh
        nodes = initial.nodes
        if spec.moving and (nodes is None or np.shape(nodes) != (n + 1,)):
            raise ParameterError("initial.nodes", None if nodes is None else np.shape(nodes),
                                 f"the moving grid's {n + 1} dry node radii of the state")
        initial = (initial.radius, initial.phi)
    elif mesh.nodes is not None:
        nodes = np.asarray(mesh.nodes)
    radius, phi = _given_profile(initial, n)
    if spec.moving:  # a profile on the mesh's given nodes, else on uniform cells (the
        # first mesh check adapts them); the state's time is the run's start
        nodes = np.asarray(nodes, dtype=float) if nodes is not None else np.arange(n + 1) / n
        y = moving.state(moving.state_from_profile(radius, phi, nodes), t0)
        geo = moving.geometry(nodes)
        a = float(y[-2])
    else:
        y, geo = mod.state_from_profile(radius, phi), mod.geometry(n)
        a = mod.radius(y)
    if not (math.isfinite(radius) and abs(a - radius) <= 1e-3 * a):
        raise ParameterError("initial.radius", radius,
                             f"the radius implied by the profile, {a:.6g} (solid volume 1)")
    return y, geo, "given"


def _resume_at(state: BoundaryState, steps: list[tuple[float, float]]) -> tuple[int, float]:
    """(protocol steps done, their end in protocol time, summed as the segments are) of a
    BoundaryState to continue ``steps`` from; ParameterError if it is not one of their
    boundaries before the last."""
    j = state.steps
    if state.stopped or not (isinstance(j, int) and 0 < j < len(steps)):
        raise ParameterError("initial.steps", j, f"a boundary of the protocol's {len(steps)} "
                             "steps before its end (not a stopped run's end)")
    t = protocol_boundaries(steps)[j]
    if not abs(float(state.t) - t) <= 1e-9 * max(1.0, t):
        raise ParameterError("initial.t", state.t, f"the end of the protocol's first {j} "
                             f"steps, {t:.12g}")
    return j, t


def _state_builder(code: int, geo: np.ndarray, stats: Stats, rezoner: Rezoner | None,
                   base: dict[str, float]) -> Callable[[int, float, np.ndarray],
                                                      BoundaryState]:
    """(steps, t, y) -> the BoundaryState of grid state y (``geo``: the grid's live
    geometry, the moving grid's nodes included), its counters ``base`` plus the run's."""

    def build(steps: int, t: float, y: np.ndarray) -> BoundaryState:
        phi = np.zeros(geo.shape[1] - 1)
        a = porosity(code, y, geo, phi)
        now = {"steps": stats.steps, "rejected": stats.rejected, "jacobians": stats.jacobians,
               "rhs_calls": stats.rhs_calls, "merges": stats.merges}
        if rezoner is not None:
            now.update(mesh_checks=rezoner.checks, remaps=rezoner.remaps)
        counters = {k: base.get(k, 0) + now.get(k, 0) for k in COUNTERS
                    if k in base or k in now}
        return BoundaryState(t=float(t), steps=int(steps), radius=float(a), phi=phi,
                             nodes=geo[0].copy() if code == MOVING_CODE else None,
                             counters=counters)

    return build


def _program_segments(program: Program, gel: Gel, t_start: float, a0: float, ell: float,
                      horizon: float, hold: bool, out: list[Segment], ends: dict[int, float]
                      ) -> Iterator[Segment]:
    """The program's pieces as segments, one at a time (an until-step's piece ends at its
    event: ``seg.ended``, read here before the next is made, and kept in ``ends`` by step),
    then the hold at the last temperature up to ``horizon`` if ``hold``; each is appended
    to ``out``."""
    perm = gel.permeability
    header = program.header(gel)

    def par(temp: float) -> KernelParams:
        return KernelParams(float(gel.omega), float(gel.chi0(temp)), float(gel.chi1(temp)),
                            int(perm.code), float(perm.beta), float(ell * ell),
                            program.rate_factor(temp))

    t, temp = 0.0, float(t_start)
    for k, step in enumerate(program.steps):
        for piece in step.pieces(t, temp, k, a0):
            if t >= horizon:
                return
            t1 = min(piece.t1, horizon)
            if piece.constant:
                seg = Segment(t, t1, piece.t_start, par(piece.t_start), until=piece.until,
                              jump=piece.t_start != temp or t == 0.0)
            else:
                seg = Segment(t, t1, piece.t_start, par(piece.t_start),
                              np.vstack([header, piece.row()]), piece.until,
                              jump=piece.t_start != temp or t == 0.0)
            out.append(seg)
            yield seg
            if seg.ended is not None:
                seg.t1 = seg.ended
                ends[k] = seg.ended
                t, temp = seg.ended, piece.temperature(seg.ended)
                break
            t, temp = t1, piece.temperature(t1)
    if hold and t < horizon:
        seg = Segment(t, horizon, temp, par(temp), jump=False)
        out.append(seg)
        yield seg


def _planned(program: Program, t_start: float) -> tuple[float, float]:
    """(length without the unbounded until-waits, length with them at UNTIL_LIMIT)."""
    pieces = program.pieces(t_start)
    full = float(sum(p.t1 - p.t0 for p in pieces))
    short = float(sum(p.t1 - p.t0 for p in pieces
                      if not (p.until is not None and p.t1 - p.t0 == UNTIL_LIMIT)))
    return short, full


def _output_times(short: float, horizon: float) -> np.ndarray:
    """The default outputs of a program run: 200 over its planned length, then 100
    geometrically spaced to the horizon."""
    if short <= 0.0:
        short = min(horizon, 1.0)
    times = np.linspace(0.0, short, DEFAULT_OUTPUTS + 1)
    if horizon > short:
        times = np.concatenate([times, short + np.geomspace(short / DEFAULT_OUTPUTS,
                                                            horizon - short, 100)])
    return np.unique(times[times <= horizon])


def _check_saveat(saveat: Any, horizon: float) -> np.ndarray:
    try:
        times = np.asarray(saveat, dtype=float).ravel()
    except (TypeError, ValueError):
        raise ParameterError("saveat", saveat, "a list of output times") from None
    if not (1 <= times.size <= MAX_OUTPUTS) or not np.all(np.isfinite(times)) or np.any(
            times < 0.0) or np.any(times > horizon * (1 + 1e-12)) or np.any(np.diff(times) < 0):
        raise ParameterError("saveat", saveat, f"1-{MAX_OUTPUTS} nondecreasing times in "
                             f"[0, {horizon:.6g}]")
    return np.unique(np.minimum(times, horizon))


def _check_stop(stop: Any, a0: float | None = None) -> float | None:
    """The stop radius: a number, or a solver.heating Radius/Released (of start radius a0)."""
    if stop is None:
        return None
    if isinstance(stop, (Radius, Released)):
        stop = stop.check("stop")
        return stop.radius(a0) if a0 is not None else 2.0  # checked again at a0
    try:
        a = float(stop)
    except (TypeError, ValueError):
        a = math.nan
    if isinstance(stop, bool) or not (math.isfinite(a) and 1.0 < a <= 1e3):
        raise ParameterError("stop", stop, "None or a radius > 1 (dry radii)")
    return a


def simulate(gel: Gel | str, t_start: float, t_end: float | None = None, *,
             until: float | None = None,
             protocol: Sequence[tuple[float, float]] | Program | None = None,
             stop: float | None = None, saveat: Sequence[float] | float | None = None,
             branch: str | None = None, initial: Initial = None,
             progress: Callable[[float], None] | None = None,
             options: SolverOptions | None = None, **option_fields: Any) -> FullResult:
    """Run the full poro-elastic model (eqs. PDE_Dimless to Boundary_Dimless).

    The gel starts from a uniform equilibrium at ``t_start`` (``branch``: default swollen
    when the first step heats, shrunken when it cools) or from ``initial`` (a FullResult's
    final state, remapped conservatively, or (radius, phi) on this grid), then follows
    ``protocol`` [(duration, temperature), ...] from t = 0; without a protocol it is
    [(until, t_end)].  A protocol run records its state after every step it completes
    (``FullResult.boundary_states``, :class:`~solver.full.state.BoundaryState`); with
    ``initial`` one of them (of this protocol's first j steps, on this grid and N) the run
    continues the protocol from there exactly, in protocol time (the moving grid keeps its
    nodes; outputs from the state's time, which is the first): one run of the whole
    protocol, up to round-off and, on the moving grid, the mesh motion's history (every step
    restarts the integrator and stops the nodes); ``result.after(prefix)`` joins it to the
    record of the steps before.  Or ``protocol`` is a :class:`solver.heating.Program` of
    Hold/Ramp/Bath/Trace steps with T(t) continuous inside the kernels and the mobility
    factor m(T) (docs/heating.md); ``until`` is then the run's horizon (default: the
    program's end, or with ``stop`` the program plus HOLD_AFTER at its last temperature).

    ``stop`` (a radius, dry radii, or a solver.heating ``Radius``/``Released`` condition,
    the latter of the radius at t = 0) is a terminal event: the run ends when the radius reaches
    it from the side it starts on (it falls to a smaller target, rises to a larger one),
    located inside the accepted step (implicit integrator); the record says so
    (``status`` 'stopped', ``t_events``, ``terminal_time``; 'finished' when the horizon came
    first).  ``saveat`` selects the output times, or is the output interval (a number; the
    keyword ``every`` is the same); a stopped run's last output is its terminal time.

    How it is discretised and integrated is a
    :class:`~solver.full.options.SolverOptions`, given whole as ``options`` and/or field by
    field as keywords (scipy's ``solve_ivp(..., **options)``): ``grid`` 'eulerian' (the
    paper's, appendix Numerical scheme, the default), 'lagrangian' (uniform in the dry
    coordinate) or 'moving' (non-uniform Lagrangian cells that follow the interface,
    rezoned every few steps; ``mesh``, a solver.full.moving.MeshOptions; phi snapshots are
    then on each output's own cells, ``FullResult.nodes``); ``n`` cells; ``integrator``
    'implicit' (adaptive RODASP, ``rtol``/``atol`` on porosity and radius, ``jacobian``) or
    'explicit' (the paper's forward Euler; ``dt``, the largest step, defaults to 0.8 of the
    stability limit; output times are hit exactly); ``interfacial_length`` ell (dry radii)
    adds the interfacial energy (ell^2/2)|grad_X J|^2 (docs/interfacial.md; 0, the default,
    is the paper's model): the interface is about 10 ell wide, resolve it with n >= 2/ell
    cells on the Lagrangian grid (the Eulerian grid needs several times more and uses the
    finite-difference Jacobian with the term) or use the moving grid; ``max_steps`` and
    ``max_seconds`` (a wall-clock budget, checked wherever the stepping loop stops anyway,
    at least every 4096 steps, so it changes no step: past it the run stops with
    BudgetExceeded, a SolverError).
    By default 200 outputs (a program: 200 over its length, 100 after);
    ``progress(fraction)`` is called as the run advances.  Raises ParameterError for bad
    input and SolverError (with diagnostics) for numerical failure.
    """
    started = time.perf_counter()
    every = option_fields.pop("every", None)
    if isinstance(saveat, (int, float)) and not isinstance(saveat, bool):
        if every is not None:
            raise ParameterError("saveat", saveat, "either saveat or every, not both")
        saveat, every = None, saveat
    program = protocol if isinstance(protocol, Program) else None
    if program is not None:
        protocol = None
    if isinstance(gel, str):
        gel = preset(gel)
    if not isinstance(gel, Gel):
        raise ParameterError("gel", gel, "a Gel or a preset name")
    t_start = check_temperature(t_start, "t_start")
    stop_given = stop
    stop = _check_stop(stop)
    if program is not None:
        if t_end is not None:
            raise ParameterError("protocol", "a program with t_end",
                                 "either a program or t_end, not both")
        steps = None
        short, full = _planned(program, t_start)
        has_until = any(p.until is not None for p in program.pieces(t_start))
        if until is not None:
            try:
                total = float(until)
            except (TypeError, ValueError):
                total = math.nan
            if not (math.isfinite(total) and 0.0 < total <= DURATION_MAX):
                raise ParameterError("until", until,
                                     f"a horizon 0 < until <= {DURATION_MAX:g} (tau)")
        else:
            total = full + (HOLD_AFTER if stop is not None else 0.0)
        if total <= 0.0:
            raise ParameterError("until", until, "a horizon > 0: the program has no length")
        pieces = program.pieces(t_start)
        first_t = pieces[0].temperature(pieces[0].t1) if pieces else t_start
    else:
        steps = _protocol(t_end, until, protocol)
        total = float(sum(d for d, _ in steps))
        has_until = False
    resume = initial if isinstance(initial, BoundaryState) else None
    j_begin, t_begin = 0, 0.0
    if resume is not None:
        if steps is None:
            raise ParameterError("initial", "a BoundaryState",
                                 "a (duration, temperature) protocol to continue")
        j_begin, t_begin = _resume_at(resume, steps)
    if steps is not None:
        short = total
        first_t = steps[j_begin][1]
    opts = SolverOptions.build(options, **option_fields)
    spec = grid_spec(opts.grid)
    grid, n, integrator, mesh = spec.name, opts.n, opts.integrator, opts.mesh
    ell, rtol, atol, dt = opts.interfacial_length, opts.rtol, opts.atol, opts.dt
    max_steps, max_seconds = opts.step_budget, opts.max_seconds
    jac_mode = JAC_FD if opts.jacobian == "fd" or (ell > 0.0 and grid == "eulerian") \
        else JAC_ANALYTIC
    if progress is not None and not callable(progress):
        raise ParameterError("progress", progress, "a callable taking the fraction done")
    if integrator != "implicit" and (stop is not None or has_until):
        raise ParameterError("integrator", integrator,
                             "'implicit' for runs with events (stop, until-steps)")
    if saveat is not None:
        if every is not None:
            raise ParameterError("saveat", saveat, "either saveat or every, not both")
        out_times = _check_saveat(saveat, total)
    else:
        if every is None and program is not None:
            out_times = _output_times(short, total)
        else:
            if every is None:
                every = total / DEFAULT_OUTPUTS
            if not (isinstance(every, (int, float)) and math.isfinite(every) and every > 0.0):
                raise ParameterError("every", every, "an output interval > 0")
            if total / every > MAX_OUTPUTS:
                raise ParameterError("every", every, f">= {total / MAX_OUTPUTS:.3g} "
                                     f"(at most {MAX_OUTPUTS} outputs)")
            out_times = uniform_output_times(total, every)
    if resume is not None:  # from the state's time, the first output
        out_times = np.concatenate([[t_begin], out_times[out_times > t_begin]])

    code = spec.code
    mod = spec.module
    y0, geo, branch_used = _initial_state(spec, gel, t_start, first_t, branch, initial, n,
                                          mesh, ell, t_begin)
    a0 = float(y0[-2] if spec.moving else mod.radius(y0))
    if isinstance(stop_given, (Radius, Released)):
        stop = _check_stop(stop_given, a0)
    perm = gel.permeability
    done: list[Segment] = []
    ends: dict[int, float] = {}
    segments: Any
    if steps is not None:
        segments, t0 = [], 0.0
        for duration, temp in steps:
            par = KernelParams(float(gel.omega), float(gel.chi0(temp)), float(gel.chi1(temp)),
                               int(perm.code), float(perm.beta), float(ell * ell))
            segments.append(Segment(t0, t0 + duration, temp, par))
            t0 += duration
        segments[-1].t1 = total
        segments = segments[j_begin:]
        done = segments
    else:
        segments = _program_segments(program, gel, t_start, a0, ell, total,
                                     stop is not None or until is not None, done, ends)
        if integrator != "implicit":
            segments = list(segments)

    ws = Workspace(code, geo, interfacial=ell > 0.0)
    collector = _Collector(mod, code, geo, done, out_times.size + 2, n,
                           fronts.diffuse_window(ell, n) if ell > 0.0 else fronts.WINDOW,
                           moving=spec.moving, ell=ell)
    rezoner = Rezoner(mesh, ell) if spec.moving else None
    stats = Stats()
    diag: dict[str, Any] = {
        "grid": grid, "n": n, "integrator": integrator, "rtol": rtol, "atol": atol,
        "jacobian": "fd" if jac_mode == JAC_FD else "analytic", "interfacial_length": ell,
        "gel": gel.to_dict(), "t_start": t_start, "branch": branch_used}
    if steps is not None:
        diag["protocol"] = [list(s) for s in steps]
    else:
        diag["program"] = program.to_dict()
    if resume is not None:
        diag["start"] = {"t": t_begin, "steps": j_begin}
    if stop is not None:
        diag["stop"] = stop
    if spec.moving:
        diag["mesh"] = mesh.to_dict()
    watch = Watch()
    if max_seconds is not None:
        watch.check = _budget_check(started, float(max_seconds), total, stats,
                                    f"{grid} grid, N = {n}, interfacial length {ell:g}")
    states: list[BoundaryState] = []
    state_of = _state_builder(code, geo, stats, rezoner,
                              {} if resume is None else dict(resume.counters))
    if steps is not None:
        def boundary(seg: Segment, y: np.ndarray) -> None:
            states.append(state_of(j_begin + len(states) + 1, seg.t1, y))

        watch.boundary = boundary
    try:
        if integrator == "implicit":
            y_end = run_implicit(ws, y0, segments, out_times, collector,
                                 StepControl(rtol, atol, max_steps, jac_mode, stop), progress,
                                 stats, watch, rezoner=rezoner, total=total)
        else:
            diag["dt"] = dt
            y_end = run_explicit(ws, y0, segments, out_times, collector, dt, max_steps,
                                 progress, stats, watch)
    except SolverError as exc:
        exc.diagnostics.update(diag)
        exc.diagnostics["wall_time"] = time.perf_counter() - started
        if collector.spinodal_time is None or isinstance(exc, BudgetExceeded):
            raise
        exc.diagnostics["spinodal_time"] = collector.spinodal_time
        raise SolverError(f"{exc} (spinodal collapse detected from t="
                          f"{collector.spinodal_time:.4g}: interior cells collapse at grid "
                          f"scale, the start is inside the spinodal region)",
                          exc.diagnostics) from exc
    t_final = stats.t_stop if stats.t_stop is not None else (done[-1].t1 if done else 0.0)
    if (saveat is None or stats.t_stop is not None) and (
            collector.k == 0 or collector.t[collector.k - 1] < t_final):
        collector(t_final, y_end)  # a program that ended before its planned horizon
    diag.update(steps=stats.steps, rejected=stats.rejected, jacobians=stats.jacobians,
                rhs_calls=stats.rhs_calls, merges=stats.merges,
                wall_time=time.perf_counter() - started,
                status="stopped" if stats.t_stop is not None else "finished",
                t_events=[] if stats.t_stop is None else [stats.t_stop])
    if steps is None:
        diag["until_events"] = {str(k): t for k, t in ends.items()}
    if rezoner is not None:
        diag.update(mesh_checks=rezoner.checks, remaps=rezoner.remaps)
    if steps is not None and stats.t_stop is not None:  # where the stop event ended it
        states.append(replace(state_of(j_begin + len(states) + 1, stats.t_stop, y_end),
                              stopped=True))
    result = collector.result(diag, stats)
    result.boundary_states = states
    return result


def _budget_check(started: float, seconds: float, total: float, stats: Stats,
                  what: str) -> Callable[[float], None]:
    """A wall-clock check at time t of the run: past ``seconds`` it raises BudgetExceeded."""

    def check(t: float) -> None:
        spent = time.perf_counter() - started
        fraction = min(1.0, t / total) if total > 0.0 else 1.0
        if spent > seconds:
            raise BudgetExceeded(
                f"the full-solver run ({what}) used its {seconds:.0f} s budget at "
                f"{fraction:.0%} of the simulated time (t = {fraction * total:.4g}, "
                f"{stats.steps} steps): this scenario is too stiff for these settings",
                {"wall_seconds": spent, "fraction": fraction, "steps": stats.steps})

    return check


class _Collector:
    """Receives the state at every output time and builds the result arrays."""

    def __init__(self, mod: Any, code: int, geo: np.ndarray, segments: list[Segment],
                 size: int, n: int, window: int = fronts.WINDOW, moving: bool = False,
                 ell: float = 0.0) -> None:
        self.mod, self.code, self.geo, self.segments = mod, code, geo, segments
        self.window = window
        self.ell = ell
        self.nodes = np.zeros((size, n + 1)) if moving else np.zeros((0, 0))
        self.t = np.zeros(size)
        self.radius = np.zeros(size)
        self.phi = np.zeros((size, n))
        self.solid = np.zeros(size)
        self.k = 0
        self.spinodal_time: float | None = None

    def __call__(self, t: float, y: np.ndarray) -> None:
        k = self.k
        a = porosity(self.code, y, self.geo, self.phi[k])
        self.t[k], self.radius[k] = t, a
        if self.nodes.size:
            self.nodes[k] = self.geo[0]
        self.solid[k] = solid_error(self.code, y, self.geo, self.phi[k])
        if self.spinodal_time is None and fronts.spinodal_collapse(self.phi[k]):
            self.spinodal_time = t
        self.k = k + 1

    def _temperature(self, t: float) -> float:
        """Temperature at output t: the protocol step with t0 < t <= t1 (the first at t = 0)."""
        for seg in self.segments:
            if t <= seg.t1:
                return seg.temperature_at(t)
        return self.segments[-1].temperature_at(t)

    def result(self, diag: dict[str, Any], stats: Stats) -> FullResult:
        k = self.k
        t, radius, phi = self.t[:k], self.radius[:k], self.phi[:k]
        coords = self.geo[1, : phi.shape[1]].copy()
        nodes = self.nodes[:k].copy() if self.nodes.size else np.zeros((0, 0))
        front = np.full(k, np.nan)
        jump = np.full(k, np.nan)
        res = FullResult(t=t, radius=radius, front=front, jump=jump, phi=phi, coords=coords,
                         temperature=np.array([self._temperature(x) for x in t]),
                         expelled_volume=4.0 * np.pi / 3.0 * (radius[0] ** 3 - radius ** 3),
                         solid_error=self.solid[:k], spinodal=self.spinodal_time is not None,
                         diagnostics=diag, step_t=np.array(stats.t),
                         step_radius=np.array(stats.a), step_rate=np.array(stats.da),
                         step_edge=np.array(stats.edge), nodes=nodes)
        radii = res.cell_radii()
        for i in range(k):
            window = self.window
            if nodes.size:
                window = fronts.moving_window(nodes[i], phi[i], self.ell)
            front[i], jump[i] = fronts.locate_front(radii[i], phi[i], window)
        ell = float(diag.get("interfacial_length") or 0.0)
        if res.spinodal and ell > 0.0:
            diag["spinodal_time"] = self.spinodal_time
            diag["message"] = (f"spinodal decomposition: several interfaces from "
                               f"t={self.spinodal_time:.4g}; the interfacial energy (ell = "
                               f"{ell:g}, {ell * phi.shape[1]:.2g} cells per ell) makes them "
                               f"well-posed, so refine N to check the answer converges")
        elif res.spinodal:
            diag["spinodal_time"] = self.spinodal_time
            diag["message"] = (f"spinodal collapse: interior cells collapsed at grid scale "
                               f"from t={self.spinodal_time:.4g}; the solution depends on the "
                               f"grid and is not converged")
        else:
            diag["message"] = "ok"
        return res
