"""Work-precision report: error against run time for the full solver and the front model.

Run:  .venv/bin/python benchmarks/work_precision.py [--smoke | --full] [--out DIR]
      (the same report as ``thermogel bench``, which also runs the stability matrix)

For each of the paper's cases (ANB 302->308, 308->302, 308->304; HHT 304->308, 308->304,
304->307.6):
  * a reference: the finest grid at the tightest tolerance, Richardson-checked on a ladder of
    three grids (observed order and estimated error of a(t) and of the 80% time) and set against
    the other grid at the same N.  In the front cases the paper's model has no interfacial
    energy and does not converge under grid refinement (issue 3): with ``--ell 0`` the
    "reference" is the finest Eulerian run and the check reports the grid spread instead.  By
    default the front cases' reference is the planner's truth (issue 12): a direct run of the
    regularized model on the moving grid at ell = 1e-4 (which stands for ell -> 0) with the
    planner's n = 400 and rtol, Richardson-checked on n = 100, 200, 400;
  * the full solver (implicit) over a sweep of N on the fixed grids (in the front cases at the
    report's ell, 0.01 by default: what a uniform grid affords) and, in the front cases, on
    the moving grid at the truth's ell; and over a sweep of rtol;
  * the paper's explicit forward Euler (N and dt of the paper), timed from a short partial run
    and extrapolated to the whole run (its error is that of its semi-discretization);
  * the front model (and issue 8's sharp-interface one, where present) from the bare
    equilibrium and from the full solution at the paper's t0.
Per method: wall time (median of repeats after warm-up), max relative error of a(t) (dense, as
benchmarks/full_solver.py), max error of R_f(t) where the reference has a front, and the
relative error of the time to expel 80% of the stored fluid (swelling cases: to take up 80%
of the volume change).

The library functions here are reused by benchmarks/stability_matrix.py and by the
``thermogel bench`` command (api/commands/bench.py), which imports this module as
``benchmarks.work_precision``.
"""

from __future__ import annotations

import argparse
import csv
import functools
import math
import os
import platform
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.front_model import median_time
from benchmarks.full_solver import dense_radius, max_error
from dosing.runs.scenario import TRUTH
from solver.errors import BudgetExceeded, NotApplicableError, ParameterError, SolverError
from solver.front import fraction_radius, front_applicability, front_trajectory
from solver.full import FullResult, simulate
from solver.gel import Gel, preset
from solver.phase import classify_jump

try:  # issue 8's sharp-interface front model, where present
    from solver.front.sharp import sharp_front_trajectory
except ImportError:  # pragma: no cover - older trees
    sharp_front_trajectory = None

Log = Callable[[str], None]
FRONT_KINDS = ("front", "delayed_front")
OUTPUTS = 200  # output times per run (every = until / OUTPUTS), the same for every method
CONSERVATION = 1e-10  # relative solid-volume error a converged run must keep (issue 3)
CONVERGED = 1e-3  # largest Richardson error estimate (relative) of a converged reference
DEFAULT_ELL = 0.01  # interfacial length of the fixed grids' front runs (4 / ell cells afford it)
TRUTH_ELL = float(TRUTH.interfacial_length)  # the planner's truth without a bead: 1e-4
TRUTH_RTOL = float(TRUTH.rtol)
COLUMNS = ("case", "behaviour", "method", "grid", "n", "rtol", "dt", "ell", "wall_s", "timing",
           "steps", "rejected", "err_a", "err_a_same_n", "err_front", "err_t80", "t80",
           "status", "note")


def quiet(_: str) -> None:
    """A log that drops its messages."""


# --- cases and plans --------------------------------------------------------------------------

@dataclass(frozen=True)
class Case:
    """A jump of the paper: gel preset, temperatures (K), run length (tau) and, where the front
    model applies, the paper's start time t0 for its full-solver start."""

    gel: str
    t_start: float
    t_end: float
    until: float
    front_start: float | None = None

    @property
    def name(self) -> str:
        """'ANB 302->308'."""
        return f"{self.gel} {self.t_start:g}->{self.t_end:g}"

    @property
    def behaviour(self) -> str:
        """The jump classifier's verdict: smooth, front, delayed_front or spinodal."""
        return _behaviour(self.gel, self.t_start, self.t_end)


@functools.cache
def _behaviour(gel: str, t_start: float, t_end: float) -> str:
    return classify_jump(preset(gel), t_start, t_end).behaviour


CASES = (Case("ANB", 302.0, 308.0, 0.3, 0.001), Case("ANB", 308.0, 302.0, 1.0),
         Case("ANB", 308.0, 304.0, 1.0), Case("HHT", 304.0, 308.0, 0.3, 0.01),
         Case("HHT", 308.0, 304.0, 0.5), Case("HHT", 304.0, 307.6, 8.0))


@dataclass(frozen=True)
class Plan:
    """What one report measures: cases, sweeps, reference ladder, explicit and timing policy.

    The tolerance sweep and the explicit scheme run on the Eulerian grid at N = ``tol_n``;
    ``ref_ns`` is the Richardson ladder (its last N is the reference's); ``paper_ns``: the
    paper's model on the Eulerian grid, run besides the regularized one in the front cases
    when the report uses an interfacial length; a run whose first
    (warm) call takes w seconds is repeated min(max_repeats, repeat_budget / w) times and
    the median kept when that is at least 2 repeats.
    """

    label: str
    cases: tuple[str, ...]
    ns: tuple[int, ...]
    rtol: float
    rtols: tuple[float, ...]
    tol_n: int
    ref_ns: tuple[int, int, int]
    ref_rtol: float
    explicit_dts: tuple[float, ...]
    explicit_steps: int
    max_repeats: int
    repeat_budget: float
    front_repeats: int
    guard_seconds: float
    paper_ns: tuple[int, ...] = ()
    grids: tuple[str, ...] = ("eulerian", "lagrangian")
    truth_ns: tuple[int, int, int] = (100, 200, TRUTH.n)  # the moving grid's ladder
    moving_ns: tuple[int, ...] = (100, 200, TRUTH.n)  # its N sweep in the front cases


FULL = Plan("full", tuple(c.name for c in CASES), (50, 100, 200, 400, 800, 1600), 1e-6,
            (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8), 400, (400, 800, 1600), 1e-9,
            (1e-8, 5e-9, 2e-9, 1e-9), 50_000, 5, 6.0, 200, 600.0, (100, 400, 1600),
            moving_ns=(100, 200, 400, 800))  # 50 cells cannot hold ell = 1e-4: step budget
SMOKE = Plan("smoke", ("ANB 308->302", "ANB 302->308"), (50, 100), 1e-6, (1e-4, 1e-6, 1e-8),
             100, (50, 100, 200), 1e-9, (1e-8, 5e-9), 2_000, 3, 0.5, 20, 60.0)
PLANS = {"full": FULL, "smoke": SMOKE}


def case_by_name(name: str) -> Case:
    """The case called ``name`` ('ANB 302->308')."""
    for case in CASES:
        if case.name == name:
            return case
    raise ParameterError("case", name, " or ".join(c.name for c in CASES))


def report_ell(requested: float | None) -> float | None:
    """The interfacial length the front cases run with: None (the paper's model) when
    ``requested`` is 0, else ``requested`` or DEFAULT_ELL."""
    if requested is not None and not (math.isfinite(requested) and requested >= 0.0):
        raise ParameterError("interfacial_length", requested, "a finite number >= 0")
    if requested == 0.0:
        return None
    return DEFAULT_ELL if requested is None else float(requested)


def case_ell(case: Case, ell: float | None) -> float | None:
    """The interfacial length for this case: ``ell`` where a front crosses the spinodal region
    from the start (the classifier's 'front', issue 8), None elsewhere."""
    return ell if case.behaviour == "front" else None


# --- running and timing -----------------------------------------------------------------------

def gel_label(gel: Gel) -> str:
    """The gel's name, with Omega and beta when they differ from its preset's."""
    try:
        base = preset(gel.name)
    except ParameterError:
        base = None
    if base is not None and base.key() == gel.key():
        return gel.name
    beta = f", beta={gel.permeability.beta:g}" if gel.permeability.code else ""
    return f"{gel.name} (Omega={gel.omega:g}{beta})"


@dataclass
class Outcome:
    """A full-solver run: its result (None on failure), median wall time, repeats, status
    ('ok', 'flagged', 'failed', 'guard' or 'bug') and message."""

    result: FullResult | None
    wall: float
    repeats: int
    status: str
    message: str
    diagnostics: dict[str, Any] = field(default_factory=dict)


def verdict(res: FullResult) -> tuple[str, str]:
    """(status, message) of a finished run: 'bug' with NaN anywhere, 'flagged' for a
    spinodal collapse or solid lost beyond CONSERVATION, else 'ok'."""
    arrays = (res.t, res.radius, res.phi, res.solid_error, res.expelled_volume)
    if not all(np.all(np.isfinite(a)) for a in arrays):
        return "bug", "non-finite values in the result"
    if res.spinodal:
        return "flagged", str(res.diagnostics.get("message", "spinodal collapse"))
    lost = float(np.max(res.solid_error))
    if lost > CONSERVATION:
        return "flagged", f"solid volume conserved only to {lost:.1e} (> {CONSERVATION:g})"
    return "ok", "ok"


def warm_up() -> None:
    """Load (or compile) every kernel the report calls, so that no timing pays for it."""
    for grid in ("eulerian", "lagrangian"):
        simulate("ANB", 302, 308, until=1e-3, grid=grid, n=20)
    simulate("ANB", 302, 308, until=1e-3, grid="moving", n=20, interfacial_length=0.01)
    simulate("ANB", 308, 302, until=1e-5, n=20, integrator="explicit", dt=1e-7)
    front_trajectory(preset("ANB"), 302, 308)


class Runner:
    """Runs the full solver once per distinct setting (memoized: the reference, the sweeps
    and the stability matrix share runs), times it and classifies the outcome."""

    def __init__(self, plan: Plan, log: Log = quiet) -> None:
        self.plan, self.log = plan, log
        self._memo: dict[tuple, Outcome] = {}

    def run(self, gel: Gel | str, t_start: float, t_end: float, until: float, *,
            grid: str = "eulerian", n: int = 400, rtol: float = 1e-6,
            ell: float | None = None, timing: bool = True) -> Outcome:
        """One jump; ``timing=False`` skips the repeats (the wall time is the single run's)."""
        gel = preset(gel) if isinstance(gel, str) else gel
        kwargs: dict[str, Any] = {"gel": gel, "t_start": t_start, "t_end": t_end,
                                  "until": until, "grid": grid, "n": n, "rtol": rtol,
                                  "every": until / OUTPUTS}
        if ell is not None:
            kwargs["interfacial_length"] = ell
        key = (gel.key(), t_start, t_end, until, grid, n, rtol, ell)
        if key not in self._memo:
            self._memo[key] = self._measure(kwargs, timing)
        return self._memo[key]

    def _measure(self, kwargs: dict[str, Any], timing: bool) -> Outcome:
        label = (f"{gel_label(kwargs['gel'])} {kwargs['t_start']:g}->{kwargs['t_end']:g} "
                 f"{kwargs['grid']} N={kwargs['n']} rtol={kwargs['rtol']:g}"
                 + (f" ell={kwargs['interfacial_length']:g}" if "interfacial_length" in kwargs
                    else ""))
        started = time.perf_counter()
        try:
            res = simulate(**kwargs, max_seconds=self.plan.guard_seconds)
        except BudgetExceeded as exc:
            wall = time.perf_counter() - started
            self.log(f"  {label}: {exc}")
            return Outcome(None, wall, 1, "guard", f"wall-clock guard: {exc}")
        except SolverError as exc:
            wall = time.perf_counter() - started
            self.log(f"  {label}: failed after {wall:.2f} s: {exc}")
            return Outcome(None, wall, 1, "failed", str(exc), dict(exc.diagnostics))
        except Exception as exc:
            wall = time.perf_counter() - started
            self.log(f"  {label}: CRASH {type(exc).__name__}: {exc}")
            return Outcome(None, wall, 1, "bug", f"{type(exc).__name__}: {exc}")
        wall = time.perf_counter() - started
        repeats = 1
        extra = min(self.plan.max_repeats, int(self.plan.repeat_budget / max(wall, 1e-3)))
        if timing and extra >= 2:
            walls = []
            for _ in range(extra):
                t0 = time.perf_counter()
                simulate(**kwargs)
                walls.append(time.perf_counter() - t0)
            wall, repeats = float(np.median(walls)), extra
        status, message = verdict(res)
        self.log(f"  {label}: {wall:.3f} s (x{repeats}), {res.diagnostics['steps']} steps, "
                 f"{status}")
        return Outcome(res, wall, repeats, status, message, res.diagnostics)


# --- the reference ------------------------------------------------------------------------------

def target_radius(case: Case, a0: float) -> float:
    """The radius at 80% of the fluid exchange: 80% of the stored fluid expelled when
    shrinking (a^3 = 0.2 a0^3 + 0.8, eq. FluidVolExpelled); 80% of the volume change to the
    final equilibrium when swelling."""
    if case.t_end > case.t_start:
        return float(fraction_radius(a0, 0.8))
    a_end = classify_jump(preset(case.gel), case.t_start, case.t_end).final_stretch
    return float(np.cbrt(a0**3 + 0.8 * (a_end**3 - a0**3)))


def crossing(res: FullResult | None, radius: float) -> float | None:
    """First time the radius reaches ``radius``, or None (no result, never reached)."""
    if res is None:
        return None
    try:
        return float(res.time_to_radius(radius))
    except ValueError:
        return None


def observed_order(d_coarse: float, d_fine: float, ratio: float) -> tuple[float, float]:
    """(observed order p, estimated error of the finest run) from the differences between
    successive runs of a ladder refined by ``ratio``: p = log(d_coarse / d_fine) / log(ratio),
    error d_fine / (ratio^p - 1); (nan, inf) when the differences do not shrink."""
    if d_fine == 0.0:
        return math.inf, 0.0
    if d_coarse <= d_fine:
        return math.nan, math.inf
    p = math.log(d_coarse / d_fine) / math.log(ratio)
    return p, d_fine / (ratio**p - 1.0)


@dataclass
class Reference:
    """A case's reference run and its convergence check.

    ``order_a``/``error_a``: observed order and Richardson error estimate of the finest run's
    a(t) (max relative difference between ladder runs); ``order_t80``/``error_t80`` the same
    for the 80% time (relative); ``spread_t80``: relative gap to the other grid at the same
    N; ``converged``: both estimates below CONVERGED.
    """

    case: Case
    result: FullResult
    grid: str
    n: int
    rtol: float
    ell: float | None
    a80: float
    t80: float | None
    order_a: float
    error_a: float
    order_t80: float
    error_t80: float
    spread_t80: float | None
    converged: bool
    note: str

    def row(self) -> dict[str, Any]:
        """Plain-data summary (for the references table)."""
        return {"case": self.case.name, "behaviour": self.case.behaviour, "grid": self.grid,
                "n": self.n, "rtol": self.rtol, "ell": self.ell, "a80": self.a80,
                "t80": self.t80, "order_a": self.order_a, "error_a": self.error_a,
                "order_t80": self.order_t80, "error_t80": self.error_t80,
                "spread_t80": self.spread_t80, "converged": self.converged, "note": self.note}


REFERENCE_COLUMNS = ("case", "behaviour", "grid", "n", "rtol", "ell", "a80", "t80", "order_a",
                     "error_a", "order_t80", "error_t80", "spread_t80", "converged", "note")


def reference_setting(case: Case, plan: Plan,
                      ell: float | None) -> tuple[str, float, tuple[int, ...], float | None]:
    """(grid, rtol, ladder, ell) of the reference.  Smooth cases: Eulerian at ``ref_rtol``.
    Delayed fronts: Eulerian at the rtol sweep's tightest (shared with it; ``ref_rtol`` on
    the finest grid costs minutes there).  Fronts, regularized: the planner's truth (the
    moving grid at ``TRUTH_ELL`` and the planner's rtol, ladder ``truth_ns`` ending at its
    n); fronts with the paper's model (``ell`` None): the paper's Eulerian grid at the
    sweep's rtol (its front speed keeps moving with N: no converged reference exists)."""
    if case.behaviour == "front":
        if ell is not None:
            return "moving", TRUTH_RTOL, plan.truth_ns, TRUTH_ELL
        return "eulerian", plan.rtol, plan.ref_ns, None
    if case.behaviour == "delayed_front":
        return "eulerian", min(plan.rtols), plan.ref_ns, ell
    return "eulerian", plan.ref_rtol, plan.ref_ns, ell


def reference(case: Case, plan: Plan, runner: Runner, ell: float | None) -> Reference:
    """The finest run of the Richardson ladder, checked (SolverError if it fails)."""
    grid, rtol, ns, ell = reference_setting(case, plan, case_ell(case, ell))
    ladder = [runner.run(case.gel, case.t_start, case.t_end, case.until, grid=grid, n=n,
                         rtol=rtol, ell=ell) for n in ns]
    for n, out in zip(ns, ladder, strict=True):
        if out.result is None:
            raise SolverError(f"reference {case.name} {grid} N={n} failed: {out.message}",
                              out.diagnostics)
    fine = ladder[-1].result
    ratio = ns[2] / ns[1]
    a80 = target_radius(case, float(fine.radius[0]))
    order_a, error_a = observed_order(max_error(ladder[1].result, ladder[0].result, case.until),
                                      max_error(fine, ladder[1].result, case.until), ratio)
    t80s = [crossing(o.result, a80) for o in ladder]
    order_t, error_t = math.nan, math.inf
    if None not in t80s:
        order_t, error_t = observed_order(abs(t80s[1] - t80s[0]) / t80s[-1],
                                          abs(t80s[2] - t80s[1]) / t80s[-1], ratio)
    spread = None
    if grid != "moving":  # no fixed grid affords the truth's ell: 4 / ell = 40,000 cells
        other = "lagrangian" if grid == "eulerian" else "eulerian"
        twin = runner.run(case.gel, case.t_start, case.t_end, case.until, grid=other,
                          n=ns[-1], rtol=rtol, ell=ell)
        t_twin = crossing(twin.result, a80)
        spread = abs(t_twin / t80s[-1] - 1.0) if t_twin is not None and t80s[-1] else None
    converged = error_a < CONVERGED and (t80s[-1] is None or error_t < CONVERGED)
    if grid == "moving":
        note = (f"the planner's truth: a direct run at ell = {ell:g} (standing for ell -> 0) "
                f"on the moving grid, Richardson over n = {', '.join(map(str, ns))}: "
                + ("converged" if converged else "NOT converged by the Richardson check"))
    elif converged:
        note = "grid-converged (Richardson)"
    elif case.behaviour in FRONT_KINDS and ell is None:
        note = ("NOT converged: the paper's model has no interfacial energy, the front speed "
                "depends on the grid (issue 3); errors are against the finest Eulerian run and "
                "show the grid spread")
    else:
        note = "NOT converged by the Richardson check"
    return Reference(case, fine, grid, ns[-1], rtol, ell, a80, t80s[-1], order_a,
                     error_a, order_t, error_t, spread, converged, note)


# --- error measures and rows --------------------------------------------------------------------

def front_error(times: np.ndarray, front: np.ndarray, ref: FullResult) -> float | None:
    """Max |R_f - R_f,ref| at the reference's output times where both have a sharp front;
    None where the reference has none.  ``front`` is sampled at ``times``."""
    if not np.any(np.isfinite(ref.front)):
        return None
    inside = (ref.t >= times[0]) & (ref.t <= times[-1])
    x = np.interp(ref.t[inside], times, front)
    both = np.isfinite(x) & np.isfinite(ref.front[inside])
    return float(np.max(np.abs(x[both] - ref.front[inside][both]))) if both.any() else None


def relative(value: float | None, ref: float | None) -> float | None:
    """|value / ref - 1|, or None when either is missing."""
    if value is None or not ref:
        return None
    return abs(value / ref - 1.0)


def full_row(case: Case, method: str, out: Outcome, ref: Reference, rtol: float, n: int,
             grid: str, ell: float | None, same_n: Outcome | None = None) -> dict[str, Any]:
    """A table row for a full-solver run measured against the reference."""
    res = out.result
    row: dict[str, Any] = dict.fromkeys(COLUMNS)
    row.update(case=case.name, behaviour=case.behaviour, method=method, grid=grid, n=n,
               rtol=rtol, ell=ell, wall_s=out.wall, status=out.status,
               timing=f"median of {out.repeats}" if out.repeats > 1 else "single run",
               note="" if out.status == "ok" else out.message)
    row["steps"] = out.diagnostics.get("steps")
    row["rejected"] = out.diagnostics.get("rejected")
    if res is None:
        return row
    row["err_a"] = max_error(res, ref.result, case.until)
    if same_n is not None and same_n.result is not None and same_n is not out:
        row["err_a_same_n"] = max_error(res, same_n.result, case.until)
    row["err_front"] = front_error(res.t, res.front, ref.result)
    row["t80"] = crossing(res, ref.a80)
    row["err_t80"] = relative(row["t80"], ref.t80)
    return row


def sweep_rows(case: Case, plan: Plan, runner: Runner, ref: Reference,
               ell: float | None) -> list[dict[str, Any]]:
    """The implicit full solver over N (the fixed grids at the report's ell, rtol =
    plan.rtol; in regularized front cases the moving grid at the truth's ell and rtol over
    ``plan.moving_ns``) and over rtol (Eulerian, N = plan.tol_n), and, when regularized, the
    paper's model over ``plan.paper_ns`` (Eulerian); rtol-sweep rows also carry the error
    against the tightest rtol at the same N (the time-integration error alone, as
    benchmarks/full_solver.py)."""
    ell = case_ell(case, ell)
    rows = []
    sweeps = [(grid, n, plan.rtol, ell) for grid in plan.grids for n in plan.ns]
    if ell is not None:
        sweeps += [("moving", n, TRUTH_RTOL, TRUTH_ELL) for n in plan.moving_ns]
    for grid, n, rtol, grid_ell in sweeps:
        out = runner.run(case.gel, case.t_start, case.t_end, case.until, grid=grid, n=n,
                         rtol=rtol, ell=grid_ell)
        rows.append(full_row(case, f"full {grid} (N sweep)", out, ref, rtol, n, grid,
                             grid_ell))
    for n in plan.paper_ns if ell is not None else ():
        out = runner.run(case.gel, case.t_start, case.t_end, case.until, n=n, rtol=plan.rtol)
        rows.append(full_row(case, "full eulerian, paper's model (N sweep)", out, ref,
                             plan.rtol, n, "eulerian", None))
    tight = runner.run(case.gel, case.t_start, case.t_end, case.until, n=plan.tol_n,
                       rtol=min(plan.rtols), ell=ell)
    for rtol in plan.rtols:
        out = runner.run(case.gel, case.t_start, case.t_end, case.until, n=plan.tol_n,
                         rtol=rtol, ell=ell)
        rows.append(full_row(case, f"full eulerian (rtol sweep, N={plan.tol_n})", out, ref,
                             rtol, plan.tol_n, "eulerian", ell, same_n=tight))
    return rows


def explicit_row(case: Case, plan: Plan, runner: Runner, ref: Reference) -> dict[str, Any]:
    """The paper's forward Euler (the paper's model, Eulerian grid, N = plan.tol_n) at the
    first stable dt of ``plan.explicit_dts``: timed over ``explicit_steps`` steps and
    extrapolated to the whole run.  Its errors are those of its semi-discretization (the
    implicit run at the same N and the tightest rtol); the note gives how closely the partial
    run matched that implicit run."""
    gel, n = preset(case.gel), plan.tol_n
    base = runner.run(gel, case.t_start, case.t_end, case.until, n=n, rtol=min(plan.rtols))
    row = full_row(case, "explicit Euler (paper)", base, ref, min(plan.rtols), n, "eulerian",
                   None)
    row.update(rtol=None, rejected=0, wall_s=None, err_a_same_n=None)
    unstable = []
    for dt in plan.explicit_dts:
        horizon = plan.explicit_steps * dt
        common = {"gel": gel, "t_start": case.t_start, "t_end": case.t_end, "until": horizon,
                  "n": n, "every": horizon / 10}
        started = time.perf_counter()
        try:
            part = simulate(**common, integrator="explicit", dt=dt)
        except SolverError:
            unstable.append(f"{dt:g}")
            continue
        wall = time.perf_counter() - started
        steps = math.ceil(case.until / dt - 1e-9)
        implicit = simulate(**common, rtol=min(plan.rtols))
        gap = float(np.max(np.abs(part.radius / implicit.radius - 1.0)))
        row.update(dt=dt, wall_s=wall / part.diagnostics["steps"] * steps, steps=steps,
                   timing=f"extrapolated from {part.diagnostics['steps']} steps "
                          f"(t <= {horizon:.2g}) timed in {wall:.2f} s",
                   note=(f"errors: its semi-discretization's (the paper's model, implicit "
                         f"N={n}, rtol {min(plan.rtols):g}); the partial run matched it to "
                         f"{gap:.1e}"
                         + (f"; unstable at dt = {', '.join(unstable)}" if unstable else "")))
        return row
    row.update(status="failed", err_a=None, err_front=None, err_t80=None, t80=None,
               note=f"forward Euler unstable at every dt tried ({', '.join(unstable)})")
    return row


def front_models() -> list[tuple[str, Callable[..., Any]]]:
    """(label, trajectory function): the paper's front model and, where present, issue 8's
    sharp-interface-consistent one."""
    models: list[tuple[str, Callable[..., Any]]] = [("front model", front_trajectory)]
    if sharp_front_trajectory is not None:
        models.append(("sharp front model", sharp_front_trajectory))
    return models


def front_rows(case: Case, plan: Plan, ref: Reference) -> list[dict[str, Any]]:
    """Each front model from the bare equilibrium and from the reference's state at the
    paper's t0 ('full@t0', conservative form), where the model applies (else no rows).  The
    a(t) error covers the model's range [t0, front at the centre]."""
    gel = preset(case.gel)
    if case.behaviour != "front" or not front_applicability(gel, case.t_start, case.t_end)[0]:
        return []
    starts: list[tuple[str, tuple[float, float, float] | None]] = [("equilibrium", None)]
    if case.front_start is not None:
        a, rf, _ = ref.result.state_at(case.front_start)
        starts.append(("full@t0", (case.front_start, a, rf)))
    return [front_row(case, plan, ref, model, fun, start_label, start)
            for model, fun in front_models() for start_label, start in starts]


def front_row(case: Case, plan: Plan, ref: Reference, model: str, fun: Callable[..., Any],
              start_label: str, start: tuple[float, float, float] | None) -> dict[str, Any]:
    """One front-model trajectory timed (median of plan.front_repeats) and measured."""
    gel = preset(case.gel)

    def solve() -> Any:
        return fun(gel, case.t_start, case.t_end, start=start)

    res = solve()
    wall = median_time(solve, plan.front_repeats)
    times = np.linspace(0.0, case.until, 4001)
    inside = times[(times >= res.t[0]) & (times <= res.t_stop)]
    x = res.curve.front_at(inside)
    b = dense_radius(ref.result, inside)
    row: dict[str, Any] = dict.fromkeys(COLUMNS)
    row.update(case=case.name, behaviour=case.behaviour, method=f"{model} ({start_label} start)",
               wall_s=wall, timing=f"median of {plan.front_repeats}", status="ok",
               err_a=float(np.max(np.abs(res.curve.radius(x) / b - 1.0))),
               err_front=front_error(inside, x, ref.result),
               note=(f"t0 = {start[0]:g}; " if start else "")
               + f"a(t) and R_f(t) compared over t = {res.t[0]:g}..{res.t_stop:.3g} "
                 "(front at the centre)")
    try:
        row["t80"] = res.time_to_radius(ref.a80)
    except (ParameterError, NotApplicableError) as exc:
        row["note"] += f"; no 80% time: {exc}"
    row["err_t80"] = relative(row["t80"], ref.t80)
    return row


# --- the report ---------------------------------------------------------------------------------

@dataclass
class Report:
    """Everything the work-precision part measured."""

    plan: Plan
    ell: float | None
    references: list[Reference]
    rows: list[dict[str, Any]]
    machine: dict[str, Any]
    wall: float


def machine() -> dict[str, Any]:
    """nproc, CPU model, RAM, load average and versions of this machine."""
    cpu = "unknown"
    ram = math.nan
    try:
        cpu = next(line.split(":", 1)[1].strip() for line in
                   Path("/proc/cpuinfo").read_text().splitlines() if line.startswith("model name"))
        kb = next(int(line.split()[1]) for line in Path("/proc/meminfo").read_text().splitlines()
                  if line.startswith("MemTotal"))
        ram = kb / 2**20
    except (OSError, StopIteration, ValueError):
        pass
    import numba
    import scipy

    return {"nproc": os.cpu_count(), "cpu": cpu, "ram_gib": round(ram, 1),
            "load_average": tuple(round(x, 2) for x in os.getloadavg()),
            "python": platform.python_version(), "numpy": np.__version__,
            "scipy": scipy.__version__, "numba": numba.__version__}


def work_precision(plan: Plan, ell: float | None = None, log: Log = quiet,
                   runner: Runner | None = None) -> Report:
    """Measure every case of ``plan``: reference, sweeps, explicit scheme, front model."""
    started = time.perf_counter()
    runner = runner or Runner(plan, log)
    info = machine()
    log(f"warm-up; load average {info['load_average']}")
    warm_up()
    refs, rows = [], []
    for name in plan.cases:
        case = case_by_name(name)
        log(f"{case.name} ({case.behaviour}): reference")
        ref = reference(case, plan, runner, ell)
        refs.append(ref)
        log(f"{case.name}: sweeps, explicit scheme, front model")
        rows += sweep_rows(case, plan, runner, ref, ell)
        rows.append(explicit_row(case, plan, runner, ref))
        rows += front_rows(case, plan, ref)
    info["load_average_end"] = tuple(round(x, 2) for x in os.getloadavg())
    return Report(plan, ell, refs, rows, info, time.perf_counter() - started)


def headline(report: Report) -> list[dict[str, Any]]:
    """Per case: the reference's 80% time, the paper's explicit scheme (extrapolated), the
    paper's model as the paper ran it (e400: Eulerian, N=400, rtol 1e-6), the
    cheapest full-solver run within 1% of the reference on both a(t) and the 80% time, and
    the front models (the paper's, and issue 8's sharp one) from the bare equilibrium."""
    out = []
    for ref in report.references:
        rows = [r for r in report.rows if r["case"] == ref.case.name]
        full = [r for r in rows if r["method"].startswith("full") and r["status"] == "ok"]
        ok = [r for r in full if r["err_a"] is not None and r["err_a"] <= 0.01
              and (r["err_t80"] is None or r["err_t80"] <= 0.01)]
        best = min(ok, key=lambda r: r["wall_s"], default=None)
        default = next((r for r in full if r["grid"] == "eulerian" and r["n"] == 400
                        and r["rtol"] == 1e-6 and r["ell"] is None
                        and "N sweep" in r["method"]), None)
        expl = next((r for r in rows if r["method"].startswith("explicit")), None)
        front = next((r for r in rows if r["method"] == "front model (equilibrium start)"), None)
        sharp = next((r for r in rows if r["method"] == "sharp front model (equilibrium start)"),
                     None)
        out.append({
            "case": ref.case.name, "behaviour": ref.case.behaviour, "t80": ref.t80,
            "reference": ("converged" if ref.converged else "not converged")
                         + f" ({ref.grid} N={ref.n})",
            "explicit_wall_s": expl and expl["wall_s"],
            "e400_wall_s": default and default["wall_s"],
            "e400_err_a": default and default["err_a"],
            "e400_err_t80": default and default["err_t80"],
            "best_within_1pct": best and f"{best['grid']} N={best['n']} rtol={best['rtol']:g}",
            "best_wall_s": best and best["wall_s"],
            "front_wall_s": front and front["wall_s"],
            "front_err_t80": front and front["err_t80"],
            "sharp_err_t80": sharp and sharp["err_t80"]})
    return out


HEADLINE_COLUMNS = ("case", "behaviour", "t80", "reference", "explicit_wall_s", "e400_wall_s",
                    "e400_err_a", "e400_err_t80", "best_within_1pct", "best_wall_s",
                    "front_wall_s", "front_err_t80", "sharp_err_t80")


def fmt(value: Any) -> str:
    """A table cell: floats in 3 significant digits, None/NaN as '-'."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, (float, np.floating)):
        v = float(value)
        if v == 0.0 or math.isinf(v):
            return f"{v:g}"
        return f"{v:.3g}" if 1e-3 <= abs(v) < 1e4 else f"{v:.2e}"
    return str(value)


def markdown(rows: Sequence[dict[str, Any]], columns: Sequence[str]) -> str:
    """A Markdown table of ``rows`` (dicts) over ``columns``."""
    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    lines += ["| " + " | ".join(fmt(r.get(c)).replace("|", "/") for c in columns) + " |"
              for r in rows]
    return "\n".join(lines)


def write_csv(path: Path, rows: Sequence[dict[str, Any]], columns: Sequence[str]) -> Path:
    """Write ``rows`` as CSV (None as an empty cell)."""
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(columns)
        for r in rows:
            w.writerow(["" if r.get(c) is None else r.get(c) for c in columns])
    return path


def machine_line(info: dict[str, Any]) -> str:
    """One line describing the machine and its load."""
    end = info.get("load_average_end")
    return (f"{info['nproc']} cores ({info['cpu']}), {info['ram_gib']} GiB RAM; load average "
            f"{info['load_average'][0]} at start" + (f", {end[0]} at end" if end else "")
            + f"; Python {info['python']}, numpy {info['numpy']}, scipy {info['scipy']}, "
            f"numba {info['numba']}")


def report_markdown(report: Report) -> str:
    """The work-precision report as Markdown: machine, headline, references, full table."""
    ell = ("the paper's model" if report.ell is None
           else f"interfacial length ell = {report.ell:g} on the fixed grids in the front "
                f"cases; their reference is the planner's truth (moving grid, ell = "
                f"{TRUTH_ELL:g})")
    parts = [f"# Work-precision report ({report.plan.label})", "",
             f"Machine: {machine_line(report.machine)}. Wall time of the report "
             f"{report.wall:.0f} s. Full solver: {ell}.", "", "## Headline", "",
             markdown(headline(report), HEADLINE_COLUMNS), "",
             "## References (Richardson check)", "",
             markdown([r.row() for r in report.references], REFERENCE_COLUMNS), "",
             "## All runs", "",
             "err_a: max relative error of a(t); err_front: max |R_f - R_f,ref| (dry radii) "
             "where the reference has a front; err_t80: relative error of the 80% time; "
             "err_a_same_n: against the tightest rtol at the same N (time error alone).", "",
             markdown(report.rows, COLUMNS), ""]
    return "\n".join(parts)


def save(report: Report, out: Path) -> dict[str, Path]:
    """CSV and Markdown files of the report in ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    paths = {"csv": write_csv(out / "work_precision.csv", report.rows, COLUMNS),
             "references": write_csv(out / "references.csv",
                                     [r.row() for r in report.references], REFERENCE_COLUMNS),
             "markdown": out / "work_precision.md"}
    paths["markdown"].write_text(report_markdown(report))
    return paths


def main(argv: list[str] | None = None) -> int:
    """Run the report and print it (stability matrix: benchmarks/stability_matrix.py)."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    mode = ap.add_mutually_exclusive_group()
    mode.add_argument("--smoke", action="store_true", help="the reduced CI subset (default)")
    mode.add_argument("--full", action="store_true", help="every case and setting")
    ap.add_argument("--out", type=Path, default=Path("bench-out"))
    ap.add_argument("--interfacial-length", type=float, default=None)
    args = ap.parse_args(argv)
    plan = FULL if args.full else SMOKE
    report = work_precision(plan, report_ell(args.interfacial_length),
                            log=lambda m: print(m, file=sys.stderr, flush=True))
    save(report, args.out)
    print(report_markdown(report))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
