"""Time integration drivers: adaptive RODASP (implicit) and forward Euler (explicit).

Both march the semi-discrete system of one grid through the protocol's segments (each at
a fixed temperature), hand every output time's state to a callback (implicit: cubic
Hermite interpolation between accepted steps), record a(t) and da/dt at every step, and
enforce a step budget.  Failures raise :class:`SolverError` with the diagnostics.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from typing import Protocol

import numpy as np
from numba import njit

from ..errors import SolverError
from . import rosenbrock as ros
from .kernels import KernelParams
from .system import (
    JAC_ANALYTIC,
    MODULES,
    dense_output,
    edge_porosity,
    fd_jacobian,
    porosity,
    rhs,
)


class Rezoner(Protocol):
    """Mesh adaptation hook of the moving grid (``moving.Rezoner``)."""

    every: int

    def __call__(self, y: np.ndarray, geo: np.ndarray) -> bool: ...

    def reset(self, y: np.ndarray, geo: np.ndarray) -> None: ...


OutputFn = Callable[[float, np.ndarray], None]
ProgressFn = Callable[[float], None]


@dataclass
class Segment:
    """A stretch of the protocol at one temperature: [t0, t1] with kernel parameters."""

    t0: float
    t1: float
    temperature: float
    par: KernelParams


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

    def record(self, t: float, a: float, da: float, edge: float) -> None:
        """Append one accepted step's time, radius, da/dt and edge-cell porosity."""
        self.t.append(t)
        self.a.append(a)
        self.da.append(da)
        self.edge.append(edge)


class Workspace:
    """Preallocated arrays for one grid and size (band, border, stage and work buffers)."""

    def __init__(self, grid: int, geo: np.ndarray, interfacial: bool = False) -> None:
        mod = MODULES[grid]
        self.grid = grid
        self.geo = geo
        self.n = geo.shape[1] - 1 + getattr(mod, "EXTRA", 0)  # state size (moving grid: + t)
        self.ia = self.n - 1 - getattr(mod, "EXTRA", 0)  # index of the radius a
        self.lower, self.upper, p = mod.structure(interfacial)
        m = self.n - p
        kv = self.lower + self.upper
        self.work = np.zeros((mod.WORK_ROWS, self.n + 1))
        self.jband = np.zeros((kv + 1, m))
        self.jc = np.zeros((m, p))
        self.jd = np.zeros((p, m))
        self.je = np.zeros((p, p))
        self.lu = np.zeros((2 * self.lower + self.upper + 1, m))
        self.ipiv = np.zeros(m, dtype=np.int64)
        self.cm = np.zeros((m, p))
        self.dm = np.zeros((p, m))
        self.xm = np.zeros((m, p))
        self.em = np.zeros((p, p))
        self.spiv = np.zeros(p, dtype=np.int64)
        self.zbuf = np.zeros(p)
        self.u = np.zeros((ros.RODASP.m.size, self.n))
        self.ytmp = np.zeros(self.n)
        self.ftmp = np.zeros(self.n)
        self.ynew = np.zeros(self.n)
        self.fnew = np.zeros(self.n)
        self.errv = np.zeros(self.n)
        self.scale = np.zeros(self.n)

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
    and the Jacobian (``system.JAC_ANALYTIC`` or ``JAC_FD``)."""

    rtol: float = 1e-6
    atol: float = 1e-9
    max_steps: int = 500_000
    jac_mode: int = JAC_ANALYTIC


def run_implicit(ws: Workspace, y: np.ndarray, segments: list[Segment], out_times: np.ndarray,
                 on_output: OutputFn, control: StepControl, progress: ProgressFn | None,
                 stats: Stats, ticks: int = 200, method: ros.Method = ros.RODASP,
                 rezoner: Rezoner | None = None) -> np.ndarray:
    """Integrate with adaptive RODASP through every segment; returns the final state.

    The stepping loop runs in numba (rosenbrock.rodas_run) between stops: output times,
    ``ticks`` progress points, record-buffer flushes and, on the moving grid, every
    ``rezoner.every`` accepted steps a mesh check.  Outputs are cubic Hermite
    interpolants of the last step.  A rezoner changes y and ``ws.geo`` in place after the
    outputs up to the current time are out; the integrator restarts there with a fresh
    Jacobian and without the step controller's history (a one-step method needs nothing
    else).
    """
    rtol, atol, max_steps, jac_mode = (control.rtol, control.atol, control.max_steps,
                                       control.jac_mode)
    counters = np.zeros(6, dtype=np.int64)
    rec = np.zeros((4, 4096))
    tt = np.zeros(2)
    total = segments[-1].t1
    h0 = 1e-7 * max(1.0, total)
    ctrl = np.array([h0, 0.0, 0.0, 0.0])
    y = y.copy()
    yold, fold = np.zeros_like(y), np.zeros_like(y)
    ia = ws.ia
    k_out = 0
    reasons = {ros.RUN_BUDGET: f"step budget exhausted ({max_steps} steps)",
               ros.RUN_UNDERFLOW: "step size underflow",
               ros.RUN_BAD_STATE: "unphysical state"}
    for seg in segments:
        f = ws.rhs(y, seg.par)
        if f is None:
            raise _failure("unphysical state at the start of a protocol step", stats, seg.t0)
        tt[0] = seg.t0
        if not stats.t or stats.t[-1] != seg.t0:
            stats.record(seg.t0, y[ia], f[ia], edge_porosity(ws.grid, y, ws.geo))
        ctrl[0], ctrl[1], ctrl[3] = min(ctrl[0], h0), 0.0, 0.0
        if rezoner is not None:
            rezoner.reset(y, ws.geo)  # a new temperature: the mesh stops until it is re-aimed
        k_out = _emit(out_times, k_out, seg.t0, lambda _t: y.copy(), on_output)
        while tt[0] < seg.t1:
            t_stop = seg.t1
            if progress is not None:
                t_stop = min(t_stop, (np.floor(tt[0] / total * ticks + 1e-9) + 1.0) * total / ticks)
            if k_out < out_times.size:
                t_stop = min(t_stop, out_times[k_out])
            budget = max_steps
            t_land = seg.t1
            if rezoner is not None and rezoner.every > 0:
                budget = min(max_steps, int(counters[ros.C_STEPS]) + rezoner.every)
                # land on output times: the moving nodes' radii are smooth in time, but their
                # differences across a thin cell are not well interpolated over a long step
                if k_out < out_times.size and out_times[k_out] > tt[0]:
                    t_land = min(t_land, float(out_times[k_out]))
            status = ros.rodas_run(
                ws.grid, y, f, yold, fold, tt, t_stop, t_land, seg.par, ws.geo, ws.work,
                ws.lower, ws.upper, ws.jband, ws.jc, ws.jd, ws.je, ws.lu, ws.ipiv, ws.cm,
                ws.dm, ws.xm, ws.em, ws.spiv, ws.zbuf, ws.u, ws.ytmp, ws.ftmp, ws.ynew,
                ws.fnew, ws.errv, ws.scale, rtol, atol, method.tableau, method.a, method.c,
                method.m, method.e, counters, ctrl, rec, budget, jac_mode)
            _flush(stats, rec, counters)
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
            k_out = _emit(out_times, k_out, t1,
                          partial(_dense_state, ws, t0, t1, yold, y, fold, f), on_output)
            if check and rezoner is not None and rezoner(y, ws.geo):
                ctrl[1], ctrl[3] = 0.0, 0.0  # restart: new Jacobian, no controller history
            if progress is not None:
                progress(min(1.0, t1 / total))
    return y


@njit(cache=True)
def _euler_steps(grid, y, par, geo, work, f, dt, nsteps):
    """nsteps forward Euler steps in place; returns the number done before a bad state."""
    for k in range(nsteps):
        if not rhs(grid, y, par, geo, f, work):
            return k
        for i in range(y.size):
            y[i] += dt * f[i]
    return nsteps


@njit(cache=True)
def _stability_step(grid, y, f0, par, geo, work, lower, upper, jband, jc, jd, je,
                    ytmp, ftmp, scale):
    """Largest stable forward Euler step 2 / rho(J), rho bounded by Gershgorin row sums."""
    if fd_jacobian(grid, y, f0, par, geo, work, lower, upper, jband, jc, jd, je,
                   ytmp, ftmp, scale) < 0:
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
    return float(_stability_step(ws.grid, y, f, par, ws.geo, ws.work, ws.lower, ws.upper,
                                 ws.jband, ws.jc, ws.jd, ws.je, ws.ytmp, ws.ftmp, ws.scale))


_RESTEP = 64


def run_explicit(ws: Workspace, y: np.ndarray, segments: list[Segment], out_times: np.ndarray,
                 on_output: OutputFn, dt: float | None, max_steps: int,
                 progress: ProgressFn | None, stats: Stats) -> np.ndarray:
    """The paper's forward Euler scheme on the same semi-discretization (appendix step 6).

    dt defaults to 0.8 of the Gershgorin stability limit, re-estimated every ``_RESTEP``
    steps (the limit falls as a front sharpens).  Output times are hit exactly (the last
    step of an interval is shortened).
    """
    y = y.copy()
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
                    step = 0.8 * stable_step(ws, y, seg.par)
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
                done = _euler_steps(ws.grid, y, seg.par, ws.geo, ws.work, f, h, nsteps)
                stats.steps += done
                stats.rhs_calls += done
                if done < nsteps or not np.all(np.isfinite(y)):
                    raise _failure(f"explicit Euler became unstable near t={t + done * h:.6g} "
                                   f"(dt={h:.3g}): reduce dt", stats, t + done * h, {"dt": h})
                t = stop if nsteps * h >= remaining * (1 - 1e-12) else t + nsteps * h
                if progress is not None:
                    progress(min(1.0, t / total))
            t = stop
            fcur = ws.rhs(y, seg.par)
            if fcur is None:
                raise _failure(f"unphysical state at t={t:.6g}", stats, t)
            stats.record(t, y[a_idx], fcur[a_idx], edge_porosity(ws.grid, y, ws.geo))
            while k_out < out_times.size and out_times[k_out] <= t + 1e-14 * max(1.0, t):
                on_output(out_times[k_out], y)
                k_out += 1
            if progress is not None:
                progress(min(1.0, t / total))
    return y
