"""A batch of beads under a heating protocol (issues 24 and 26).

Under a jump every bead follows one dimensionless trajectory (``dosing.population.front``).  Under a
protocol in seconds it does not: a bead of dry radius R has tau(R) ~ R^2 (eq. timescale,
at the protocol's hottest temperature), so the same protocol is a different dimensionless
program for every size (a small bead sees a slower ramp per tau).  Inside the reduced
slow-heating model's region (``dosing.heating.reduced``) each quadrature node R_k gets its
own reduced trajectory (``solver.front.slow``, milliseconds), located exactly at the
crossings of a grid of released fractions (``FRACTIONS`` of what the gel can expel, and
the dose itself): F_k(t) is the fraction of its stored fluid bead k has released at t
seconds (eq. FluidVolExpelled), linear in t between exact crossings.  The batch's released
fraction is V(t) = sum_k v_k F_k(t) with the volume weights v_k of ``dosing.population.front`` (the
same ``DrySizes.nodes``), and its dose time T solves V(T) = f between the smallest and the
largest node's own times.  The node count is doubled (``NODE_LADDER``) until T moves by
less than ``QUADRATURE_TOL``; the last change is the quadrature error.

Every node is checked against the region at its own size (its own interfacial length and
program) and the batch's dose; the beads far from their own dose at T (small ones nearly
empty, large ones barely started) are read at fractions outside the measured table, which
the stated model-form part does not cover (the answer says so).  Without a planner a node
outside the region refuses the batch (:class:`OutsideRegion`, naming
``size_distribution``: the fast path, no full-solver run).  With one (``planner=``) each
node outside it gets its curve from the full solver instead (:class:`FullNodeCurve`): the
bead's own run of the protocol's program in its own tau at its own interfacial length
(``planner.trajectory``: cached, on the planner's solver; the staircase of holds on a
stand-in solver without programs, as ``dosing.heating.response``), run on past the largest
node's own dose time (the program, then a hold at its last temperature), F(t) on the run's
accepted steps.  Each node keeps its best model (the reduced one inside the region, and
the smallest beads holding under ``TAIL_WEIGHT`` of the fluid); the model reads
"front-slow-sharp+full" when both answered.  F jumps where the model changes (the reduced
model is within 5 % of the truth, not equal to it), so the rule is split there: two
Gauss-Legendre panels meeting at the radius where the region begins (bisected), n nodes
each.  Full-solver nodes cost a run each (about a second at 30-50 um under a 5 K/min ramp
on the moving grid, more for larger or slower beads), so their ladder stops at
``FULL_MAX_NODES`` per panel with a tolerance of ``FULL_QUADRATURE_TOL``; their n / 2 check
runs at one node only (the reference bead's when it is a full-solver node, else the full
node holding the most fluid), and the answer says so.
"""

from __future__ import annotations

import math
import types
from typing import Any

import numpy as np
from scipy.optimize import brentq

from solver.errors import NotApplicableError, ParameterError, SolverError

from ..answers import Verdict
from ..heating import reduced as heating_reduced
from ..heating.program import program_spec, solver_program
from ..runs.scenario import DIRECT_ELL_RANGE
from ..truth import Part
from ..units import timescale
from .front import PERCENTILES, BatchAnswer, NodesPart, Quadrature, batch_sizes

FRACTIONS = np.linspace(0.0, 1.0, 201)[1:-1]  # of the gel's expellable fluid (x max_fraction)
GRID_ERROR = 3e-5  # the batch time's change from 199 to 399 fractions (CV 0.2, 120 um, 5 K/min)
NODE_LADDER = (4, 8, 16, 32, 64)  # quadrature nodes; doubled until T moves < QUADRATURE_TOL
QUADRATURE_TOL = 1e-4
TAIL_WEIGHT = 1e-3  # the smallest beads holding this much of the fluid: not region-checked
FULL_MAX_NODES = 32  # with full-solver nodes the ladder stops here (per panel; a run a node)
FULL_QUADRATURE_TOL = 1e-3  # ... converging to this (ANB 50 um CV 0.2 80 %: 1.4e-4 at 16)
EXTEND_MARGIN = 0.01  # a full node's run goes this far past the largest node's own time


class NodeCurve:
    """One bead size under the protocol: exact crossing times (s) of a fraction grid."""

    model = heating_reduced.MODEL

    def __init__(self, req: Any, radius_um: float, mobility: str) -> None:
        from solver.front.slow import slow_front_trajectory

        self.radius_um = radius_um
        self.tau_s = timescale(radius_um, req.t_end, req.constants).seconds
        a0 = req.start_radius
        fr = np.union1d(FRACTIONS * req.jump.max_fraction, [req.fraction])
        radii = (a0**3 - fr * (a0**3 - 1.0)) ** (1.0 / 3.0)
        self.pieces = req.heating.program(self.tau_s)
        prog = solver_program(program_spec(self.pieces, mobility, req.t_end))
        res = slow_front_trajectory(req.gel, req.t_start, prog, targets=tuple(radii))
        hits = np.array([res.hits.get(float(r), math.nan) for r in radii])
        ok = np.isfinite(hits)
        self.f = np.concatenate([[0.0], fr[ok]])
        self.t = np.maximum.accumulate(np.concatenate([[0.0], hits[ok]])) * self.tau_s
        own = res.hits.get(float(radii[np.searchsorted(fr, req.fraction)]), math.nan)
        self.own_seconds = float(own) * self.tau_s

    def released(self, t_s: float) -> float:
        """F(t): the fraction of its stored fluid released by ``t_s`` seconds."""
        return float(np.interp(t_s, self.t, self.f))


def _node_request(req: Any, radius_um: float) -> Any:
    """The request as the region check reads it for a bead of ``radius_um``: its own
    interfacial length (xi_dry / a_d within the direct runs' range, as every truth's), the
    batch's dose."""
    lo, hi = DIRECT_ELL_RANGE
    ell = min(max(req.constants.interfacial_lengths(radius_um)[0], lo), hi)
    return types.SimpleNamespace(settings=req.settings.with_length(ell), fraction=req.fraction,
                                 t_start=req.t_start, t_end=req.t_end)


class OutsideRegion(ParameterError):
    """A batch refused (naming ``size_distribution``) because a node is outside the reduced
    model's region and no planner was given to run the full solver there."""


def _region(req: Any, radius_um: float, validate: bool) -> Verdict:
    """The reduced model's verdict on the bead of ``radius_um`` (its own ell and program)."""
    tau_s = timescale(float(radius_um), req.t_end, req.constants).seconds
    return heating_reduced.choose(_node_request(req, float(radius_um)),
                                  req.heating.program(tau_s), validate)


def _checked(radii: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """The radii, smallest first, less the smallest holding under ``TAIL_WEIGHT``."""
    order = np.argsort(radii)
    tail = np.cumsum(np.asarray(weights, dtype=float)[order]) < TAIL_WEIGHT
    return np.asarray(radii, dtype=float)[order][~tail]


def check_region(req: Any, radii: np.ndarray, weights: np.ndarray, validate: bool) -> None:
    """Refuse (naming size_distribution) a batch with a node outside the reduced region;
    the smallest nodes holding together under ``TAIL_WEIGHT`` of the batch's fluid are not
    checked (they move V(t) by less than that whatever their error)."""
    for r in _checked(radii, weights):
        choice = _region(req, float(r), validate)
        if not choice.applies:
            raise OutsideRegion(
                "size_distribution", req.size_distribution.describe(),
                "a batch whose beads are all inside the reduced slow-heating model's region "
                f"({heating_reduced.REGION_TEXT})",
                f"its {r:.4g} um bead is not: {choice.why}; the full solver per size runs "
                "only on a planner (a job: dosing.question.run)")


def outside_region(req: Any, radii: np.ndarray, weights: np.ndarray,
                   validate: bool) -> set[float]:
    """The checked nodes (as :func:`check_region`) outside the reduced model's region."""
    return {float(r) for r in _checked(radii, weights)
            if not _region(req, float(r), validate).applies}


# ----------------------------------------------------------------------------- full solver
class _NotCached(Exception):
    """A full-solver run the answer needs is not in the cache (``wait`` False)."""


class Runs:
    """The planner's full-solver runs for a batch's nodes: blocking (``wait``: cached, on
    the planner's solver, several at once) or only from the cache (a missing run raises
    ``_NotCached``); ``mode`` how a protocol runs (``dosing.heating.response.Mode``)."""

    def __init__(self, planner: Any, wait: bool, validate: bool, mode: Any) -> None:
        self.planner, self.wait, self.validate, self.mode = planner, wait, validate, mode

    def get(self, scs: list[Any], target: float, after: float) -> list[Any]:
        """The runs (a ``dosing.heating.response`` getter: a failed run is returned)."""
        if self.wait:
            return self.planner._trajectories(scs, None, 0.0)
        out = [self.planner.cached(sc) for sc in scs]
        if any(t is None for t in out):
            raise _NotCached
        return out

    def many(self, scs: list[Any]) -> list[Any]:
        """The runs, a failure raised."""
        out = self.get(scs, 0.0, 0.0)
        for traj in out:
            if isinstance(traj, BaseException):
                raise traj
        return out

    def each(self, fn: Any, items: list[Any]) -> None:
        """``fn(item)`` for every item, side by side when runs are waited for."""
        if not self.wait or len(items) < 2:
            for x in items:
                fn(x)
            return
        from concurrent.futures import ThreadPoolExecutor

        with ThreadPoolExecutor(min(len(items), 8)) as pool:
            for fut in [pool.submit(fn, x) for x in items]:
                fut.result()


def node_request(req: Any, radius_um: float) -> Any:
    """The single-bead protocol dose of a node: the batch's protocol, dose and settings at a
    bead of ``radius_um`` (its own interfacial length ell = xi_dry / a_d when the batch's
    reference runs at its own, as ``dosing.population.bands.size_settings``)."""
    from ..request import DoseRequest, _clamp_length
    from ..runs.scenario import SolverSettings

    d = req.settings.request_dict()
    own = _clamp_length(req.constants.interfacial_lengths(req.bead_dry_radius_um)[0])
    if req.settings.direct and math.isclose(d["interfacial_length"] or own, own,
                                            rel_tol=1e-9):
        d["interfacial_length"] = None  # the bead's own ell: set per node
    return DoseRequest(req.gel, req.t_start, protocol=req.heating, dose_fraction=req.fraction,
                       dry_radius_um=radius_um, constants=req.constants, branch=req.branch,
                       settings=SolverSettings(**d),
                       concentration_ug_per_ul=req.concentration_ug_per_ul)


def _end_temperature(program: Any, t_start: float) -> tuple[float, float]:
    """(length in tau, temperature at its end) of a ``solver.heating.Program``."""
    from solver.heating import LINEAR

    pieces = program.pieces(t_start)
    if not pieces:
        return 0.0, t_start
    p = pieces[-1]
    s = p.t1 - p.t0
    temp = (p.t_start + p.p * s if p.kind == LINEAR
            else p.q + (p.t_start - p.q) * math.exp(-s / p.p))
    return float(sum(q.t1 - q.t0 for q in pieces)), float(temp)


class FullNodeCurve:
    """One bead size under the protocol from the full solver (module doc): F(t) on its run's
    accepted steps (s), its own dose time exact (the run to it, or a run past it)."""

    model = "full"

    def __init__(self, req: Any, radius_um: float, runs: Runs, reference: bool) -> None:
        from ..heating.response import _tau_seconds, resolve_untils
        from ..units import radius_after_dose

        self.radius_um, self.runs, self.reference = radius_um, runs, reference
        self.req = node_request(req, radius_um)
        self.mode = runs.mode
        self.tau_s = float(_tau_seconds(self.req))
        prot, _ = resolve_untils(self.req, runs.get, self.mode)
        self.pieces = prot.program(self.tau_s)
        self.a0 = self.req.start_radius
        self.fraction = self.req.fraction
        self.target = radius_after_dose(self.a0, self.fraction)
        self.own_seconds: float | None = None
        self.t = np.zeros(1)
        self.f = np.zeros(1)
        self._raw: tuple[np.ndarray, np.ndarray] | None = None  # the longest run's F(t)
        self.check_gap: float | None = None  # the n / 2 check run's gap (relative)
        self.extended: Any = None  # the scenario run past the own dose, and its crossing
        self._extended_time: float | None = None

    @property
    def covered(self) -> float:
        """The last time (s) the curve holds."""
        return float(self.t[-1])

    def reach(self) -> None:
        """The bead's own run to its dose (``dosing.heating.response._reach``: the single
        bead's run, a terminal event at the dose radius on the real solver); the reference
        bead's with the check runs a single dose of it has (its n / 2 run: ``check_gap``)."""
        from ..heating.response import _event_time, _reach

        check = ("range" if self.runs.validate else True) if self.reference else False
        time, traj, _, trajs = _reach(self.req, self.runs.get, self.pieces, self.target, 0.0,
                                      "dose_fraction", check, self.mode)
        self.own_seconds = float(time) * self.tau_s
        if self.reference and len(trajs) > 1 and not isinstance(trajs[1], BaseException):
            t2 = _event_time(trajs[1], self.target)
            if t2 is not None and time > 0.0:
                self.check_gap = abs(t2 / time - 1.0)
        self._read(traj)

    def past(self, horizon_s: float) -> Any:
        """The scenario of the program followed by a hold at its last temperature until
        ``horizon_s`` seconds (no stop)."""
        from ..heating.response import TAIL, _open
        from ..runs.scenario import Scenario

        until = horizon_s / self.tau_s
        r = self.req
        if self.mode.continuous:
            spec = program_spec(self.pieces, self.mode.mobility, r.t_end)
            length, temp = _end_temperature(solver_program(spec), r.t_start)
            if until > length:
                spec["steps"].append(["hold", temp, until - length])
            return Scenario(r.gel, r.t_start, program=spec, branch=r.branch,
                            settings=r.settings)
        length = sum(d for d, _ in _open(self.pieces, 0.0))
        steps = _open(self.pieces, max(until - length, TAIL))
        return Scenario(r.gel, r.t_start, protocol=tuple(steps), branch=r.branch,
                        settings=r.settings)

    def take(self, sc: Any, traj: Any) -> None:
        """A run past the own dose: the curve from it; the own time if not known yet (its
        crossing, None if the run ends short of it)."""
        self.extended = sc
        try:
            self._extended_time = float(traj.time_to_radius(self.target))
        except ValueError:
            self._extended_time = None
        if self.own_seconds is None and self._extended_time is not None:
            self.own_seconds = self._extended_time * self.tau_s
        self._read(traj)

    def run_check(self) -> float | None:
        """The n / 2 run of the run past the own dose: its crossing's relative gap."""
        if self.extended is None or self._extended_time is None:
            return None
        from dataclasses import replace

        sc = replace(self.extended, settings=self.extended.settings.check())
        try:
            t2 = float(self.runs.many([sc])[0].time_to_radius(self.target))
        except ValueError:
            return None
        self.check_gap = abs(t2 / self._extended_time - 1.0)
        return self.check_gap

    def _read(self, traj: Any) -> None:
        """F(t) (s) on the run's accepted steps (outputs without them), non-decreasing, from
        the run reaching furthest; exactly the dose at the own time once it is known."""
        t, a = ((traj.step_t, traj.step_radius) if len(traj.step_t) >= 2
                else (traj.t, traj.radius))
        ts = np.maximum.accumulate(np.asarray(t, dtype=float)) * self.tau_s
        if self._raw is None or ts[-1] >= self._raw[0][-1]:
            a3 = self.a0**3
            self._raw = (ts, np.maximum.accumulate((a3 - np.asarray(a, dtype=float) ** 3)
                                                   / (a3 - 1.0)))
        ts, f = self._raw
        own = self.own_seconds
        if own is not None:
            k = int(np.searchsorted(ts, own))
            ts = np.insert(ts, k, own)
            f = np.insert(f, k, self.fraction)
            f[:k] = np.minimum(f[:k], self.fraction)
            f[k + 1:] = np.maximum(f[k + 1:], self.fraction)
        self.t, self.f = ts, f

    def released(self, t_s: float) -> float:
        """F(t): the fraction of its stored fluid released by ``t_s`` seconds."""
        return float(np.interp(t_s, self.t, self.f))


class BatchCurves:
    """V(t) over the nodes of ``n`` points (curves memoised by radius); with ``runs`` (a
    planner's) the nodes outside the reduced model's region on the full solver."""

    def __init__(self, req: Any, mobility: str, validate: bool,
                 runs: Runs | None = None) -> None:
        self.req, self.mobility, self.validate = req, mobility, validate
        self.sizes = batch_sizes(req)
        self._memo: dict[float, NodeCurve | FullNodeCurve] = {}
        self.runs = runs
        self.full_used = False  # a rule's node ran on the full solver
        self.last: tuple[np.ndarray, np.ndarray, list[Any]] | None = None  # the last rule
        self._cut: float | None = None  # where the region begins (a panel edge)

    def curve(self, radius_um: float) -> NodeCurve:
        """The node's curve (memoised); with a planner, the full solver's outside the
        region."""
        key = float(radius_um)
        if key not in self._memo:
            if self.runs is None:
                self._memo[key] = NodeCurve(self.req, key, self.mobility)
            else:
                self._memo[key] = self._made(key, _region(self.req, key,
                                                          self.validate).applies)
        return self._memo[key]

    def _made(self, radius_um: float, inside: bool) -> NodeCurve | FullNodeCurve:
        """The reduced curve inside the region (and where it answers), else the full
        solver's (with a planner)."""
        assert self.runs is not None
        if inside:
            try:
                c = NodeCurve(self.req, radius_um, self.mobility)
            except (NotApplicableError, SolverError):
                c = None
            if c is not None and math.isfinite(c.own_seconds):
                return c
        ref = math.isclose(radius_um, self.sizes.mean_um, rel_tol=1e-12)
        return FullNodeCurve(self.req, radius_um, self.runs, ref)

    def nodes(self, n: int) -> tuple[np.ndarray, np.ndarray, list[NodeCurve]]:
        """(radii, volume weights, curves) of the n-point rule (the rows of a table)."""
        r, v = self.sizes.nodes(n)
        if self.runs is None:
            check_region(self.req, r, v, self.validate)
            return r, v, [self.curve(float(x)) for x in r]
        out = outside_region(self.req, r, v, self.validate)
        cut = self._boundary(r, v, out) if out else None
        if cut is not None:  # the rule split where the model changes (F jumps there)
            r, v = self.sizes.nodes(n, (cut,))
            out = outside_region(self.req, r, v, self.validate)
        for x in r:
            key = float(x)
            if key not in self._memo:
                self._memo[key] = self._made(key, key not in out)
        curves = [self._memo[float(x)] for x in r]
        if any(isinstance(c, FullNodeCurve) for c in curves):
            self.full_used = True
            self._run_full(curves)
        return r, v, curves

    def _boundary(self, radii: np.ndarray, weights: np.ndarray,
                  out: set[float]) -> float | None:
        """The radius where the region begins (bisected to 1e-9) when the checked nodes
        outside it are all smaller than those inside (the usual case: the small beads'
        larger interfacial length and slower ramp per tau); else None (no split)."""
        if self._cut is not None:
            return self._cut or None
        checked = _checked(radii, weights)
        inside = [float(r) for r in checked if float(r) not in out]
        if not inside or max(out) >= min(inside):
            return None
        lo, hi = max(out), min(inside)
        while hi - lo > 1e-9 * hi:
            mid = 0.5 * (lo + hi)
            if _region(self.req, mid, self.validate).applies:
                hi = mid
            else:
                lo = mid
        self._cut = hi
        return hi

    def _run_full(self, curves: list[Any]) -> None:
        """Every full node's own time and its curve past the largest own time of the rule:
        first that largest (the reduced nodes', else the largest full bead's own run), then
        one run per full node past it (side by side); a node short of its dose there gets
        its own run and the horizon moves."""
        assert self.runs is not None
        full = [c for c in curves if isinstance(c, FullNodeCurve)]
        horizon = max((c.own_seconds for c in curves if not isinstance(c, FullNodeCurve)),
                      default=0.0)
        if horizon <= 0.0:
            top = max(full, key=lambda c: c.radius_um)
            if top.own_seconds is None:
                top.reach()
            horizon = float(top.own_seconds)
        for _ in range(8):
            need = [c for c in full if c.covered < horizon * (1.0 - 1e-12)]
            if need:
                scs = [c.past(horizon * (1.0 + EXTEND_MARGIN)) for c in need]
                for c, sc, traj in zip(need, scs, self.runs.many(scs), strict=True):
                    c.take(sc, traj)
            short = [c for c in full if c.own_seconds is None]
            self.runs.each(FullNodeCurve.reach, short)
            top = max(float(c.own_seconds) for c in full)
            if top <= horizon:
                return
            horizon = top
        raise SolverError("the full-solver nodes' runs do not settle on the batch's horizon")

    def own(self, radii: list[float]) -> list[NodeCurve | FullNodeCurve]:
        """The curves of beads whose own dose time alone is read (the mean, percentiles);
        the full solver's own runs side by side."""
        curves = [self.curve(r) for r in radii]
        if self.runs is not None:
            self.runs.each(FullNodeCurve.reach, list({id(c): c for c in curves if isinstance(
                c, FullNodeCurve) and c.own_seconds is None}.values()))
        return curves

    def dose_time(self, n: int) -> tuple[float, int]:
        """T (s) with V(T) = f on the n-point rule, and the nodes used."""
        r, v, curves = self.nodes(n)
        self.last = (r, v, curves)
        own = [c.own_seconds for c in curves]
        if not all(math.isfinite(x) for x in own):
            raise ParameterError("dose_fraction", self.req.fraction, "a dose every bead of "
                                 "the batch reaches under the protocol (the reduced model)")
        lo, hi = min(own), max(own)
        if hi <= lo * (1.0 + 1e-15):
            return lo, len(v)

        def g(t: float) -> float:
            return sum(w * c.released(t) for w, c in zip(v, curves, strict=True)) \
                - self.req.fraction

        return float(brentq(g, lo, hi, xtol=1e-12 * hi, rtol=1e-12)), len(v)


def converge(bc: BatchCurves, tol: float = QUADRATURE_TOL) -> tuple[float, Quadrature]:
    """The batch's dose time (s), the node count doubled until it moves by under ``tol``
    (with full-solver nodes: up to ``FULL_MAX_NODES``, to ``FULL_QUADRATURE_TOL``)."""
    rule = ("exact: the sum over the table's distinct sizes" if bc.sizes.exact else
            "Gauss-Legendre over the volume-weighted law (dosing.population.sizes), one "
            "reduced trajectory per node")
    if bc.sizes.exact:
        t, k = bc.dose_time(0)
        return t, Quadrature(rule, k, 0.0, True, [(k, t)], k)
    table: list[tuple[int, float]] = []
    err = math.inf
    per_panel = 0
    for n in NODE_LADDER:
        if bc.full_used and n > FULL_MAX_NODES:
            break
        t, k = bc.dose_time(n)
        per_panel = n
        if table:
            err = abs(t - table[-1][1]) / t
        table.append((k, t))
        if err < (max(tol, FULL_QUADRATURE_TOL) if bc.full_used else tol):
            break
    if not bc.full_used:
        return table[-1][1], Quadrature(rule, table[-1][0], err, err < tol, table,
                                        table[-1][0])
    tol = max(tol, FULL_QUADRATURE_TOL)
    split = (f"split at {bc._cut:.4g} um, where the reduced model's region begins (the "
             "model changes there), " if bc._cut else "")
    rule = ("Gauss-Legendre over the volume-weighted law (dosing.population.sizes), "
            f"{split}{per_panel} nodes per panel; one reduced trajectory per node inside the "
            "reduced model's region and one full-solver run per node outside it (a run "
            f"each: the nodes are doubled up to {FULL_MAX_NODES} per panel, until the time "
            f"moves by under {tol:.0e})")
    return table[-1][1], Quadrature(rule, table[-1][0], err, err < tol, table, per_panel)


def batch_protocol_answer(req: Any, validate: bool = False, tol: float = QUADRATURE_TOL,
                          planner: Any = None, wait: bool = True) -> BatchAnswer | None:
    """The batch's dose under ``req.heating`` (module doc); times in the number-weighted
    mean bead's tau and in seconds from the protocol's start; the mobility as the protocol
    dose's (water's viscosity when chosen, else k_B T).  Without ``planner`` every node on
    the reduced model (a node outside its region refuses: :class:`OutsideRegion`); with one
    the nodes outside it on the planner's full solver (blocking; ``wait`` False: only from
    the cache, None when a run is missing)."""
    mobility = req.constants.mobility
    runs = None
    if planner is not None:
        from ..heating.response import mode_for

        runs = Runs(planner, wait, validate, mode_for(planner, req))
    bc = BatchCurves(req, mobility, validate, runs)
    try:
        return _answer(req, bc, tol, validate)
    except _NotCached:
        return None


def _answer(req: Any, bc: BatchCurves, tol: float, validate: bool) -> BatchAnswer:
    t_s, quad = converge(bc, tol)
    sizes = bc.sizes
    ref = sizes.mean_um
    pr = np.asarray(sizes.quantile(np.array(PERCENTILES)), dtype=float)
    if bc.runs is None:
        mean = bc.curve(ref)
        check_region(req, np.array([ref]), np.ones(1), validate)
        pcs = [bc.curve(float(r)) for r in pr]
    else:
        mean, *pcs = bc.own([ref, *(float(r) for r in pr)])
    tau = mean.tau_s
    ps = np.array([c.own_seconds for c in pcs])
    # the beads that have delivered their own dose by T: those whose own time (growing
    # with size: made monotone) is at most T, read off the converged rule's nodes
    rk = np.array(sorted(bc._memo))
    tk = np.maximum.accumulate([bc._memo[r].own_seconds for r in rk])
    if tk[-1] <= t_s:
        delivered = 1.0
    elif tk[0] > t_s:
        delivered = 0.0
    else:
        delivered = float(sizes.cdf(float(np.interp(t_s, tk, rk))))
    if any(isinstance(c, FullNodeCurve) for c in bc._memo.values()):
        model, unc, note = _mixed_parts(bc, quad, t_s, [mean, *pcs])
    else:
        model, unc, note = heating_reduced.MODEL, *_reduced_parts(bc, quad, t_s, mean)
    return BatchAnswer(
        distribution=sizes.spec.to_dict(), description=sizes.spec.describe(),
        model=model, dose_fraction=req.fraction, reference_dry_radius_um=ref,
        time=t_s / tau, seconds=t_s, timescale_seconds=tau,
        mean_bead_time=mean.own_seconds / tau, mean_bead_seconds=mean.own_seconds,
        delay=t_s / mean.own_seconds - 1.0, fraction_delivered=delivered,
        percentile_radii_um=pr.tolist(), percentile_times=(ps / tau).tolist(),
        percentile_seconds=ps.tolist(), quadrature=quad, note=note, uncertainty=unc)


def _reduced_parts(bc: BatchCurves, quad: Quadrature, t_s: float,
                   mean: Any) -> tuple[dict[str, Part], str]:
    """The uncertainty and note of a batch answered by the reduced model alone."""
    req, sizes, ref = bc.req, bc.sizes, bc.sizes.mean_um
    stated = heating_reduced.STATED_ERROR
    unc = {
        "numerical": Part(heating_reduced.NUMERICAL, (
            f"numerical: under {heating_reduced.NUMERICAL:.0e} per trajectory (the reduced "
            f"model's integration); the fraction grid ({len(FRACTIONS)} exact crossings per "
            f"bead, linear between them) {GRID_ERROR:.0e} (measured against twice as many at "
            f"CV 0.2); quadrature {quad.error:.1e} ({quad.nodes} nodes)")),
        "interfacial_length_range": Part(None, (
            "interfacial length: not separate: the reduced model is the sharp-interface "
            "limit; each node was checked at its own interfacial length")),
        "model_form": Part(stated, (
            f"model form: {stated:.0%}, the reduced model's largest measured gap to the truth "
            "at doses of 30-90 % in its region; beads far from their own dose at the batch's "
            "time are read outside the measured doses (not covered)")),
    }
    note = (f"{heating_reduced.MODEL_TEXT}: one reduced trajectory per bead size, each its own "
            f"dimensionless program (tau ~ R^2); the batch ({sizes.spec.describe()}) releases "
            f"{req.fraction:.0%} of its fluid at {t_s:.4g} s from the protocol's start, "
            f"{t_s / mean.own_seconds - 1.0:+.1%} against its number-weighted mean bead "
            f"({ref:.4g} um dry, {mean.own_seconds:.4g} s). Quadrature: {quad.rule}, "
            f"{quad.nodes} nodes, error {quad.error:.1e}.")
    return unc, note


def _um(radii: list[float]) -> str:
    return ", ".join(f"{r:.4g}" for r in sorted(radii)) or "none"


def _check(bc: BatchCurves, mean: Any) -> tuple[float | None, str]:
    """The full-solver nodes' n / 2 check: the reference bead's (its single dose's check
    run) when it ran on the full solver, else one run at the full node of the converged
    rule holding the most fluid; (relative gap, where) or (None, why not)."""
    if isinstance(mean, FullNodeCurve) and mean.check_gap is not None:
        return mean.check_gap, f"the reference bead ({mean.radius_um:.4g} um)"
    _, v, curves = bc.last or (None, [], [])
    full = sorted(((w, c) for w, c in zip(v, curves, strict=True)
                   if isinstance(c, FullNodeCurve) and c.extended is not None),
                  key=lambda x: -x[0])
    for _, c in full:
        gap = c.check_gap if c.check_gap is not None else c.run_check()
        if gap is not None:
            return gap, f"the {c.radius_um:.4g} um node (the full node holding the most fluid)"
    return None, "no full-solver node of the converged rule"


def _mixed_parts(bc: BatchCurves, quad: Quadrature, t_s: float,
                 own: list[Any]) -> tuple[str, dict[str, Part | NodesPart], str]:
    """The model, uncertainty and note of a batch with full-solver nodes: which nodes ran
    on which model, the check at one full node, the reduced nodes' stated part; ``own``
    the beads whose own time alone is read (the mean bead first, then the percentiles)."""
    req, sizes, ref = bc.req, bc.sizes, bc.sizes.mean_um
    mean = own[0]
    _, v, curves = bc.last or (None, [], [])
    w_full = float(sum(w for w, c in zip(v, curves, strict=True)
                       if isinstance(c, FullNodeCurve)))
    full_r = [c.radius_um for c in curves if isinstance(c, FullNodeCurve)]
    red_r = [c.radius_um for c in curves if not isinstance(c, FullNodeCurve)]
    own_full = sorted({c.radius_um for c in own if isinstance(c, FullNodeCurve)})
    models = [m for m, rs in ((heating_reduced.MODEL, red_r), ("full", full_r + own_full))
              if rs]
    model = "+".join(models) if models else "full"
    gap, where = _check(bc, mean)
    stated = heating_reduced.STATED_ERROR
    numerical = max(heating_reduced.NUMERICAL, gap or 0.0)
    check_text = (f"the n vs n/2 check of the full solver run at {where} only: {gap:.1e}, "
                  "taken for every full-solver node (not measured at the others)"
                  if gap is not None else
                  f"the full solver's n vs n/2 check not run ({where})")
    unc: dict[str, Part | NodesPart] = {
        "numerical": Part(numerical, (
            f"numerical: {check_text}; the reduced nodes under "
            f"{heating_reduced.NUMERICAL:.0e} per trajectory, their fraction grid "
            f"{GRID_ERROR:.0e}; the full nodes' F(t) linear between the run's accepted "
            f"steps; quadrature {quad.error:.1e} ({quad.nodes} nodes; with full-solver "
            f"nodes the ladder stops at {FULL_MAX_NODES} per panel and converges to "
            f"{FULL_QUADRATURE_TOL:.0e})")),
        "interfacial_length_range": Part(None, (
            "interfacial length: not run: each full-solver node ran at its own interfacial "
            "length only (the xi_lo / xi_hi runs of a single dose are not run per node); the "
            "reduced model is the sharp-interface limit")),
        "model_form": Part(stated if red_r else None, (
            (f"model form: {stated:.0%} on the reduced-model nodes ({1.0 - w_full:.1%} of the "
             "fluid), the reduced model's largest measured gap to the truth at doses of "
             "30-90 % in its region (beads far from their own dose at the batch's time are "
             "read outside the measured doses, not covered); " if red_r else "model form: ")
            + f"the full-solver nodes ({w_full:.1%} of the fluid) are the truth at their own "
            "interfacial length (the reduced model's gap to them is not computed per node)")),
        "nodes": NodesPart(
            relative=None, full_um=sorted(full_r), reduced_um=sorted(red_r),
            full_fluid_fraction=w_full, own_time_full_um=own_full, text=(
                f"nodes: {len(full_r)} of the converged rule's {len(curves)} on the full "
                f"solver ({_um(full_r)} um; {w_full:.1%} of the fluid: outside the reduced "
                f"model's region, or where it does not answer), {len(red_r)} on the reduced "
                f"model ({_um(red_r)} um; inside its region, or the smallest beads holding "
                f"under {TAIL_WEIGHT:.0e} of the fluid); own times alone (mean bead, "
                f"percentiles) on the full solver: {_um(own_full)} um")),
    }
    note = (f"one trajectory per bead size, each its own dimensionless program (tau ~ R^2): "
            f"{len(red_r)} nodes on {heating_reduced.MODEL_TEXT}, {len(full_r)} on the full "
            f"solver ({_um(full_r)} um: outside the reduced model's region); the batch "
            f"({sizes.spec.describe()}) releases {req.fraction:.0%} of its fluid at "
            f"{t_s:.4g} s from the protocol's start, {t_s / mean.own_seconds - 1.0:+.1%} "
            f"against its number-weighted mean bead ({ref:.4g} um dry, "
            f"{mean.own_seconds:.4g} s, {mean.model}). Quadrature: {quad.rule}, "
            f"{quad.nodes} nodes, error {quad.error:.1e}.")
    return model, unc, note


__all__ = ["FullNodeCurve", "OutsideRegion", "batch_protocol_answer", "check_region",
           "converge", "node_request", "outside_region"]
