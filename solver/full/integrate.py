"""Time integration drivers: adaptive RODASP (implicit) and forward Euler (explicit).

Both march the semi-discrete system of one grid through the protocol's segments (each at
a fixed temperature), hand every output time's state to a callback (implicit: cubic
Hermite interpolation between accepted steps), record a(t) and da/dt at every step, and
enforce a step budget.  Failures raise :class:`SolverError` with the diagnostics.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from functools import partial
from typing import Protocol

import numpy as np
from numba import njit

from ..crossing import hermite_root
from ..errors import SolverError
from ..heating import HEAD, temperature_rate
from . import rosenbrock as ros
from .dense import DENSE_C, DENSE_D, stage_output
from .kernels import KernelParams
from .system import (
    JAC_ANALYTIC,
    MODULES,
    MOVING,
    dense_output,
    edge_porosity,
    fd_jacobian,
    par_at,
    porosity,
    rhs,
)


class Rezoner(Protocol):
    """Mesh adaptation hook of the moving grid (``moving.Rezoner``)."""

    every: int
    land: bool

    def __call__(self, y: np.ndarray, geo: np.ndarray) -> bool: ...

    def reset(self, y: np.ndarray, geo: np.ndarray) -> None: ...


OutputFn = Callable[[float, np.ndarray], None]
ProgressFn = Callable[[float], None]
PROGRESS_TICKS = 200  # progress points a run reports (each one stops the stepping loop)


NO_HEAT = np.zeros((0, HEAD))


@dataclass
class Segment:
    """A stretch of the protocol: [t0, t1] with kernel parameters ``par`` at one
    ``temperature``, or, with ``heat`` (a solver.heating header row and one piece row),
    at the program's T(t) from ``temperature`` at t0.  ``until``: a radius that ends the
    segment early (its time is then ``ended``); ``jump``: the temperature jumps at t0 (the
    integrator restarts with a small step)."""

    t0: float
    t1: float
    temperature: float
    par: KernelParams
    heat: np.ndarray = field(default_factory=lambda: NO_HEAT)
    until: float | None = None
    jump: bool = True
    ended: float | None = None

    def temperature_at(self, t: float) -> float:
        """T at time t of this segment."""
        if self.heat.shape[0] == 0:
            return self.temperature
        return float(temperature_rate(self.heat, float(t))[0])

    def par_at(self, t: float) -> KernelParams:
        """The kernel parameters at time t."""
        return par_at(self.par, self.heat, float(t))


@dataclass
class Watch:
    """What the drivers call besides the outputs and ``progress``: ``check(t)`` wherever
    the compiled stepping loop returns (outputs, mesh checks, record flushes: at least
    every 4096 accepted steps; and a pause after every rosenbrock.PAUSE_ATTEMPTS step
    attempts, accepted or rejected, after which the loop goes on as if it had not
    returned), so a wall-clock budget raises there without stopping the integration
    anywhere it would not stop (``progress``'s ticks do stop it); and
    ``boundary(seg, y)`` with the state at the end of every segment the run completes."""

    check: Callable[[float], None] | None = None
    boundary: Callable[[Segment, np.ndarray], None] | None = None


@dataclass
class Stats:
    """Counters and the per-step record of the radius (for dense crossing times) and of the
    edge cell's porosity (for the time a front nucleates)."""

    steps: int = 0
    rejected: int = 0
    jacobians: int = 0
    rhs_calls: int = 0
    merges: int = 0
    t: list = field(default_factory=list)
    a: list = field(default_factory=list)
    da: list = field(default_factory=list)
    edge: list = field(default_factory=list)
    t_stop: float | None = None  # the terminal event's time (the run stopped there)

    def truncate(self, t: float) -> None:
        """Drop the record past time t (a step that overshot an event)."""
        k = len(self.t)
        while k and self.t[k - 1] > t:
            k -= 1
        for rec in (self.t, self.a, self.da, self.edge):
            del rec[k:]

    def record(self, t: float, a: float, da: float, edge: float) -> None:
        """Append one accepted step's time, radius, da/dt and edge-cell porosity."""
        self.t.append(t)
        self.a.append(a)
        self.da.append(da)
        self.edge.append(edge)


class Workspace:
    """Preallocated arrays for one grid and size: the kernels' bundles ``band``
    (rosenbrock.Band: Jacobian and its factorization) and ``buf`` (rosenbrock.Buffers:
    stage and work buffers)."""

    def __init__(self, grid: int, geo: np.ndarray, interfacial: bool = False) -> None:
        mod = MODULES[grid]
        self.grid = grid
        self.geo = geo
        self.n = geo.shape[1] - 1 + getattr(mod, "EXTRA", 0)  # state size (moving grid: + t)
        self.ia = self.n - 1 - getattr(mod, "EXTRA", 0)  # index of the radius a
        self.lower, self.upper, p = mod.structure(interfacial)
        m = self.n - p
        kv = self.lower + self.upper
        self.band = ros.Band(
            int(self.lower), int(self.upper), np.zeros((kv + 1, m)), np.zeros((m, p)),
            np.zeros((p, m)), np.zeros((p, p)), np.zeros((2 * self.lower + self.upper + 1, m)),
            np.zeros(m, dtype=np.int64), np.zeros((m, p)), np.zeros((p, m)), np.zeros((m, p)),
            np.zeros((p, p)), np.zeros(p, dtype=np.int64), np.zeros(p))
        n = self.n
        self.buf = ros.Buffers(
            np.zeros((mod.WORK_ROWS, n + 1)),
            np.zeros((ros.RODASP.m.size + 1, n)),  # stages and df/dt
            np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n))

    def __getattr__(self, name: str) -> np.ndarray:
        """The bundles' arrays read as attributes (``ws.jband``, ``ws.work``)."""
        for part in (self.__dict__.get("band"), self.__dict__.get("buf")):
            if part is not None and name in part._fields:
                return getattr(part, name)
        raise AttributeError(name)

    def rhs(self, y: np.ndarray, par: KernelParams) -> np.ndarray | None:
        """f(y) as a new array, or None for an unphysical state."""
        out = np.zeros(self.n)
        return out if rhs(self.grid, y, par, self.geo, out, self.work) else None


def _dense_state(ws: Workspace, t0: float, t1: float, y0: np.ndarray, y1: np.ndarray,
                 f0: np.ndarray, f1: np.ndarray, t: float) -> np.ndarray:
    """State at t in [t0, t1] (see :func:`system.dense_output`)."""
    if t >= t1 or t1 <= t0:
        return y1.copy()
    out = np.zeros(ws.n)
    dense_output(ws.grid, ws.geo, t0, t1, y0, y1, f0, f1, t, out, np.zeros(ws.geo.shape[1] - 1))
    return out


def _stage_state(ws: Workspace, t0: float, t1: float, y0: np.ndarray, y1: np.ndarray,
                 t: float) -> np.ndarray:
    """State at t in [t0, t1] on the moving grid: RODASP's continuous output from the
    stages of the accepted step t0 -> t1 still in ``ws.buf.u`` (see :mod:`.dense`)."""
    if t >= t1 or t1 <= t0:
        return y1.copy()
    out = np.zeros(ws.n)
    stage_output(ws.grid, ws.geo, y0, y1, ws.buf.u, ros.RODASP.m, DENSE_C, DENSE_D,
                 (t - t0) / (t1 - t0), t, out, np.zeros(ws.geo.shape[1] - 1))
    return out


def _failure(message: str, stats: Stats, t: float, extra: dict | None = None) -> SolverError:
    diag = {"steps": stats.steps, "rejected": stats.rejected, "jacobians": stats.jacobians,
            "rhs_calls": stats.rhs_calls, "t": t}
    diag.update(extra or {})
    return SolverError(message, diag)


def _flush(stats: Stats, rec: np.ndarray, counters: np.ndarray) -> None:
    """Move the numba-side per-step record into ``stats`` and sync the counters."""
    k = int(counters[5])
    stats.t.extend(rec[0, :k].tolist())
    stats.a.extend(rec[1, :k].tolist())
    stats.da.extend(rec[2, :k].tolist())
    stats.edge.extend(rec[3, :k].tolist())
    counters[5] = 0
    stats.rhs_calls = int(counters[ros.C_RHS])
    stats.jacobians = int(counters[ros.C_JAC])
    stats.steps = int(counters[ros.C_STEPS])
    stats.rejected = int(counters[ros.C_REJECTED])
    stats.merges = int(counters[ros.C_MERGES])


def _emit(out_times: np.ndarray, k_out: int, t: float, fn: Callable[[float], np.ndarray],
          on_output: OutputFn) -> int:
    """Hand every output time <= t to ``on_output``; returns the next output index."""
    while k_out < out_times.size and out_times[k_out] <= t + 1e-13 * max(1.0, abs(t)):
        on_output(float(out_times[k_out]), fn(float(out_times[k_out])))
        k_out += 1
    return k_out


@dataclass(frozen=True)
class StepControl:
    """What bounds the implicit steps: tolerances on porosity and radius, the step budget,
    the Jacobian (``system.JAC_ANALYTIC`` or ``JAC_FD``) and the terminal event ``stop``
    (a radius; None: none)."""

    rtol: float = 1e-6
    atol: float = 1e-9
    max_steps: int = 500_000
    jac_mode: int = JAC_ANALYTIC
    stop: float | None = None


def _copy(y: np.ndarray, _t: float) -> np.ndarray:
    return y.copy()


def _direction(a: float, target: float | None) -> float:
    """-1 if a must fall to ``target``, +1 if it must rise, 0 without a target."""
    if target is None:
        return 0.0
    return -1.0 if a > target else 1.0


def _hermite_slope(t0: float, t1: float, a0: float, a1: float, f0: float, f1: float,
                   t: float) -> float:
    """d/dt of the cubic Hermite of one step (values a0, a1, slopes f0, f1) at t."""
    h = t1 - t0
    if h <= 0.0:
        return f1
    x = (t - t0) / h
    return ((6 * x * x - 6 * x) * (a0 - a1) / h + (3 * x * x - 4 * x + 1) * f0
            + (3 * x * x - 2 * x) * f1)


def _event_time(t0: float, t1: float, y0: np.ndarray, y1: np.ndarray, f0: np.ndarray,
                f1: np.ndarray, ia: int, targets: list[tuple[float, float]]) -> float:
    """The first time in [t0, t1] at which the radius (cubic Hermite of the accepted step,
    the dense output of the state) reaches one of ``targets`` [(target, direction)]."""
    best = t1
    a0, a1 = float(y0[ia]), float(y1[ia])
    for target, d in targets:
        if d == 0.0 or (a1 - target) * d < 0.0:
            continue
        if (a0 - target) * d >= 0.0:
            return t0
        best = min(best, hermite_root(t0, t1, a0, a1, float(f0[ia]), float(f1[ia]), target))
    return best


def run_implicit(ws: Workspace, y: np.ndarray, segments: Iterable[Segment],
                 out_times: np.ndarray, on_output: OutputFn, control: StepControl,
                 progress: ProgressFn | None, stats: Stats, watch: Watch | None = None,
                 method: ros.Method = ros.RODASP, rezoner: Rezoner | None = None,
                 total: float | None = None) -> np.ndarray:
    """Integrate with adaptive RODASP through every segment; returns the final state.

    The stepping loop runs in numba (rosenbrock.rodas_run) between stops: output times,
    ``PROGRESS_TICKS`` progress points (with ``progress``), record-buffer flushes and, on
    the moving grid, every ``rezoner.every`` accepted steps a mesh check.  Outputs are read
    between accepted steps: cubic Hermite interpolants of the last step.  A rezoned moving
    grid lands a step on every output time unless ``rezoner.land`` is False; it then reads
    them from RODASP's own continuous output from the step's stages (:mod:`.dense`).  A
    rezoner changes y and ``ws.geo`` in place after the outputs up to the current time are
    out; the integrator restarts there with a fresh Jacobian and without the step
    controller's history (a one-step method needs nothing else).

    Events: ``control.stop`` (a radius) ends the run when the radius reaches it, from the side it
    is on at the first segment's start; a segment's ``until`` ends that segment (its time
    in ``seg.ended``; the segments iterable may be a generator that reads it).  The time
    is the root of the accepted step's cubic Hermite radius, the state there its dense
    output; it is the last output of a stopped run (``stats.t_stop``), and the per-step
    record ends there.  ``total`` is the planned end (default: the last segment's t1).
    ``watch`` (:class:`Watch`): a check at every stop, the state at every segment's end.
    """
    rtol, atol, max_steps, jac_mode = (control.rtol, control.atol, control.max_steps,
                                       control.jac_mode)
    stop = control.stop
    ticks = PROGRESS_TICKS
    watch = watch or Watch()
    if total is None:
        segments = list(segments)
        total = segments[-1].t1
    counters = np.zeros(6, dtype=np.int64)
    rec = np.zeros((4, 4096))
    tt = np.zeros(2)
    h0 = 1e-7 * max(1.0, total)
    ctrl = np.zeros(ros.CTRL_SIZE)
    ctrl[0] = h0
    control = ros.Control(float(rtol), float(atol), int(jac_mode), counters, ctrl, rec)
    y = y.copy()
    yold, fold = np.zeros_like(y), np.zeros_like(y)
    ia = ws.ia
    k_out = 0
    reasons = {ros.RUN_BUDGET: f"step budget exhausted ({max_steps} steps)",
               ros.RUN_UNDERFLOW: "step size underflow",
               ros.RUN_BAD_STATE: "unphysical state"}
    first = True
    rezoned = rezoner is not None and rezoner.every > 0
    land = rezoned and rezoner.land  # output times end steps
    staged = ws.grid == MOVING and rezoned and not land  # outputs from the stages
    for seg in segments:
        f = ws.rhs(y, seg.par_at(seg.t0))
        if f is None:
            raise _failure("unphysical state at the start of a protocol step", stats, seg.t0)
        state = ros.State(y, f, yold, fold, tt)
        tt[0] = seg.t0
        if not stats.t or stats.t[-1] != seg.t0:
            stats.record(seg.t0, y[ia], f[ia], edge_porosity(ws.grid, y, ws.geo))
        if first:
            ctrl[4], ctrl[5] = (stop or 0.0), _direction(float(y[ia]), stop)
            first = False
        ctrl[6], ctrl[7] = (seg.until or 0.0), _direction(float(y[ia]), seg.until)
        if seg.jump:
            ctrl[0], ctrl[1] = min(ctrl[0], h0), 0.0
        ctrl[3] = 0.0
        if rezoner is not None and seg.jump:
            rezoner.reset(y, ws.geo)  # a new temperature: the mesh stops until it is re-aimed
        k_out = _emit(out_times, k_out, seg.t0, partial(_copy, y), on_output)
        if ros.crossed(ctrl, y[ia]):  # already there: the event is at the segment's start
            if ctrl[5] != 0.0 and (y[ia] - ctrl[4]) * ctrl[5] >= 0.0:
                stats.t_stop = seg.t0
                on_output(seg.t0, y.copy())
                return y
            seg.ended = seg.t0
            continue
        while tt[0] < seg.t1:
            t_stop = seg.t1
            if progress is not None:
                t_stop = min(t_stop, (np.floor(tt[0] / total * ticks + 1e-9) + 1.0) * total / ticks)
            if k_out < out_times.size:
                t_stop = min(t_stop, out_times[k_out])
            budget = max_steps
            t_land = seg.t1
            if rezoned:
                budget = min(max_steps, int(counters[ros.C_STEPS]) + rezoner.every)
                # land on output times (MeshOptions.land): the old cubic Hermite misplaced
                # thin cells' nodes between steps (docs/moving_mesh.md sec. 8)
                if land and k_out < out_times.size and out_times[k_out] > tt[0]:
                    t_land = min(t_land, float(out_times[k_out]))
            while True:  # a pause changes no step: the call goes on where it returned
                status = ros.rodas_run(ws.grid, state, t_stop, t_land, budget, seg.par,
                                       seg.heat, ws.geo, ws.band, ws.buf, method, control)
                _flush(stats, rec, counters)
                if watch.check is not None:
                    watch.check(float(tt[0]))
                if status != ros.RUN_PAUSED:
                    break
            check = status == ros.RUN_BUDGET and budget < max_steps
            if check:
                status = ros.RUN_REACHED
            if status in reasons:
                phi = np.zeros(ws.geo.shape[1] - 1)
                porosity(ws.grid, y, ws.geo, phi)
                hint = ""
                if phi.max() > 1.0 - 1e-3:
                    hint = (f"; cell {int(phi.argmax())} is being emptied of solid (phi = "
                            f"{phi.max():.6f}), a grid-scale cavitation of this discretization")
                raise _failure(f"implicit integration failed at t={tt[0]:.6g}: "
                               f"{reasons[status]}{hint}", stats, float(tt[0]),
                               {"h": float(ctrl[0]), "phi_max": float(phi.max()),
                                "phi_min": float(phi.min())})
            t0, t1 = float(tt[1]), float(tt[0])
            dense = partial(_dense_state, ws, t0, t1, yold, y, fold, f)
            # outputs between steps: a rezoned grid's from the step's stages (its cubic
            # Hermite's stiff slopes misplace thin cells' nodes, docs/moving_mesh.md sec. 8);
            # an event's state stays on the cubic its time is the root of
            between = partial(_stage_state, ws, t0, t1, yold, y) if staged else dense
            if status == ros.RUN_EVENT:
                t_stop_ev = _event_time(t0, t1, yold, y, fold, f, ia,
                                        [(ctrl[4], ctrl[5])])
                t_until = _event_time(t0, t1, yold, y, fold, f, ia, [(ctrl[6], ctrl[7])])
                t_e = min(t_stop_ev, t_until)
                k_out = _emit(out_times, k_out, t_e, between, on_output)
                y_e = dense(t_e)
                stats.truncate(t_e)
                if t_stop_ev <= t_until and ctrl[5] != 0.0 and (
                        (y[ia] - ctrl[4]) * ctrl[5] >= 0.0):
                    stats.t_stop = t_e
                    # da/dt at the event from the step's own cubic (the rhs at the dense
                    # state is not consistent with it: garbage on the Lagrangian grid)
                    stats.record(t_e, ctrl[4], _hermite_slope(t0, t1, float(yold[ia]),
                                                              float(y[ia]), float(fold[ia]),
                                                              float(f[ia]), t_e),
                                 edge_porosity(ws.grid, y_e, ws.geo))
                    if k_out == 0 or out_times[k_out - 1] != t_e:
                        on_output(t_e, y_e)
                    return y_e
                seg.ended = t_e
                y = y_e
                break
            k_out = _emit(out_times, k_out, t1, between, on_output)
            if check and rezoner is not None and rezoner(y, ws.geo):
                ctrl[1], ctrl[3] = 0.0, 0.0  # restart: new Jacobian, no controller history
            if progress is not None:
                progress(min(1.0, t1 / total))
        if watch.boundary is not None and seg.ended is None:
            watch.boundary(seg, y)
    return y


@njit(cache=True)
def _euler_steps(grid, y, par, heat, t0, geo, work, f, dt, nsteps):
    """nsteps forward Euler steps in place from time t0 (``heat``: the segment's temperature
    program, solver.heating); returns the number done before a bad state."""
    for k in range(nsteps):
        if not rhs(grid, y, par_at(par, heat, t0 + k * dt), geo, f, work):
            return k
        for i in range(y.size):
            y[i] += dt * f[i]
    return nsteps


@njit(cache=True)
def _stability_step(grid, y, f0, par, geo, band, buf):
    """Largest stable forward Euler step 2 / rho(J), rho bounded by Gershgorin row sums."""
    lower, upper = band.lower, band.upper
    jband, jc, jd, je = band.jband, band.jc, band.jd, band.je
    if fd_jacobian(grid, y, f0, par, geo, buf.work, lower, upper, jband, jc, jd, je,
                   buf.ytmp, buf.ftmp, buf.scale) < 0:
        return -1.0
    m = jband.shape[1]
    p = je.shape[0]
    rho = 0.0
    for i in range(m + p):
        acc = 0.0
        if i < m:
            for j in range(max(0, i - lower), min(m, i + upper + 1)):
                acc += abs(jband[upper + i - j, j])
            for k in range(p):
                acc += abs(jc[i, k])
        else:
            for j in range(m):
                acc += abs(jd[i - m, j])
            for k in range(p):
                acc += abs(je[i - m, k])
        rho = max(rho, acc)
    return 2.0 / rho if rho > 0.0 else np.inf


def stable_step(ws: Workspace, y: np.ndarray, par: KernelParams) -> float:
    """Gershgorin estimate of the forward Euler stability limit at state y."""
    f = ws.rhs(y, par)
    if f is None:
        return -1.0
    return float(_stability_step(ws.grid, y, f, par, ws.geo, ws.band, ws.buf))


_RESTEP = 64


def run_explicit(ws: Workspace, y: np.ndarray, segments: list[Segment], out_times: np.ndarray,
                 on_output: OutputFn, dt: float | None, max_steps: int,
                 progress: ProgressFn | None, stats: Stats,
                 watch: Watch | None = None) -> np.ndarray:
    """The paper's forward Euler scheme on the same semi-discretization (appendix step 6).

    dt defaults to 0.8 of the Gershgorin stability limit, re-estimated every ``_RESTEP``
    steps (the limit falls as a front sharpens).  Output times are hit exactly (the last
    step of an interval is shortened).  ``watch`` as in :func:`run_implicit` (its check
    after every batch of steps).
    """
    y = y.copy()
    watch = watch or Watch()
    total = segments[-1].t1
    f = np.zeros(ws.n)
    a_idx = ws.n - 1
    k_out = 0
    for seg in segments:
        stops = np.unique(np.concatenate([[seg.t1], out_times[(out_times > seg.t0)
                                                              & (out_times < seg.t1)]]))
        t = seg.t0
        while k_out < out_times.size and out_times[k_out] <= t + 1e-14 * max(1.0, t):
            on_output(out_times[k_out], y)
            k_out += 1
        for stop in stops:
            while t < stop - 1e-14 * max(1.0, stop):
                remaining = stop - t
                step = dt
                if step is None:
                    step = 0.8 * stable_step(ws, y, seg.par_at(t))
                    if not step > 0.0:
                        raise _failure(f"unphysical state at t={t:.6g}", stats, t)
                nsteps = int(np.ceil(remaining / step - 1e-9))
                if dt is None and nsteps > _RESTEP:
                    nsteps, h = _RESTEP, step  # re-estimate the limit as stiffness grows
                else:
                    h = remaining / max(nsteps, 1)
                if stats.steps + nsteps > max_steps:
                    raise _failure(f"step budget exhausted: reaching t={stop:.6g} needs more "
                                   f"than {max_steps} explicit steps of dt={step:.3g} "
                                   f"(max_steps={max_steps})", stats, t, {"dt": step})
                done = _euler_steps(ws.grid, y, seg.par, seg.heat, t, ws.geo, ws.work, f, h,
                                    nsteps)
                stats.steps += done
                stats.rhs_calls += done
                if done < nsteps or not np.all(np.isfinite(y)):
                    raise _failure(f"explicit Euler became unstable near t={t + done * h:.6g} "
                                   f"(dt={h:.3g}): reduce dt", stats, t + done * h, {"dt": h})
                t = stop if nsteps * h >= remaining * (1 - 1e-12) else t + nsteps * h
                if watch.check is not None:
                    watch.check(t)
                if progress is not None:
                    progress(min(1.0, t / total))
            t = stop
            fcur = ws.rhs(y, seg.par_at(t))
            if fcur is None:
                raise _failure(f"unphysical state at t={t:.6g}", stats, t)
            stats.record(t, y[a_idx], fcur[a_idx], edge_porosity(ws.grid, y, ws.geo))
            while k_out < out_times.size and out_times[k_out] <= t + 1e-14 * max(1.0, t):
                on_output(out_times[k_out], y)
                k_out += 1
            if progress is not None:
                progress(min(1.0, t / total))
        if watch.boundary is not None:
            watch.boundary(seg, y)
    return y
