"""The heating that delivers a dose at an asked time (issue 39): the inverse of the planner.

The planner answers "when is the dose out under this heating"; here the heating is the
unknown.  One number of the heating varies (``mode``):

- ``jump``: the jump temperature T_end (K), held there (the paper's experiment);
- ``ramp``: the rate (K/min) of ``Heat to T_end K at r K/min`` (T_end given);
- ``bath``: the set point (K) of ``Bath at T K with a time constant of tau_b s``.

The search (:func:`design_heating`):

1. a scan of the variable's range answered from what the planner holds or its reduced
   models compute at once (the front model of a jump, the slow-heating model of a ramp or
   a bath inside its measured region: milliseconds each; ``dosing.question.envelope.
   StoredOnly``, so a point that would need a full-solver run is only marked);
2. a bracket of the target among the answered points (the edge of the reduced region and of
   the gel's reach, ``max_fraction``, found by bisection), then ``scipy.optimize.brentq``
   on the planner's seconds; a target only the full solver reaches is bracketed by blocking
   runs beyond the edge (cached), or refused;
3. with ``validate``: the truth (the full solver's validation) at the root, and the target
   corrected by the truth / model ratio and solved again on the model until the truth meets
   the target within ``rtol`` (a fixed point on a ratio that moves slowly with the heating:
   one or two validations);
4. the envelope at that heating (``dosing.question.plan``), the heatings whose envelope
   (its factors held at the root's) keeps the target inside, and with ``confidence`` P the
   heating whose time is below the target with probability P when each counted part is
   read as log-uniform over its bracket (a stated reading: the envelope is a bracket).

A target no heating in the range reaches is a ``ParameterError`` naming ``at`` (or
``fraction``) with the reachable range and the nearest reachable time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.optimize import brentq

from solver.errors import NotApplicableError, ParameterError, SolverError
from solver.limits import T_MAX, T_MIN

from ..answers import Pending

MODES = ("jump", "ramp", "bath")
VARIABLE = {"jump": ("t_end_K", "K"), "ramp": ("rate_K_per_min", "K/min"),
            "bath": ("set_point_K", "K")}
JUMP_SPAN_K = 20.0  # the default search range above T_start (a lab's bath or stage)
RATE_RANGE = (0.05, 2000.0)  # K/min, the default search range of a ramp's rate
TIME_CONSTANT_S = 30.0
XTOL = {"jump": 1e-4, "ramp": 1e-5, "bath": 1e-4}  # in the search variable (K, log rate)
VALIDATE_RTOL = 0.01
MAX_POLISH = 4
CONFIDENCE_SAMPLES = 200_000


@dataclass(frozen=True)
class HeatingTarget:
    """What the heating must do: the dose (``fraction`` of the fluid, or ``dose_ug`` of a drug
    carried at ``concentration_ug_per_ul``) out at ``at_seconds`` after heating starts from
    ``t_start``, for one bead (``dry_radius_um``) or a batch (``size_cv``, lognormal);
    ``mode`` jump | ramp (with ``t_end``) | bath (``time_constant_s``); ``bounds`` the
    search range (K, or K/min for a ramp); ``validate`` polishes on the truth;
    ``confidence`` P also finds the heating meeting the target with probability P."""

    gel: Any
    t_start: float
    at_seconds: float
    fraction: float | None = None
    dose_ug: float | None = None
    concentration_ug_per_ul: float | None = None
    dry_radius_um: float | None = None
    size_cv: float | None = None
    mode: str = "jump"
    t_end: float | None = None
    time_constant_s: float = TIME_CONSTANT_S
    bounds: tuple[float, float] | None = None
    validate: bool = False
    confidence: float | None = None
    constants: Any = None
    branch: str | None = None
    full: bool = True  # search where only the full solver answers (blocking runs)

    def __post_init__(self) -> None:
        if self.mode not in MODES:
            raise ParameterError("mode", self.mode, " | ".join(MODES))
        at = self.at_seconds
        if not (isinstance(at, (int, float)) and math.isfinite(at) and 0.0 < at <= 1e7):
            raise ParameterError("at", at, "a time after the heating starts, 0 < at <= 1e7 s")
        if (self.fraction is None) == (self.dose_ug is None):
            raise ParameterError("fraction", self.fraction, "one of fraction or dose_ug")
        if self.dose_ug is not None and self.concentration_ug_per_ul is None:
            raise ParameterError("concentration_ug_per_ul", None, "the drug's concentration "
                                 "in the stored fluid (ug/uL) with dose_ug")
        if self.dry_radius_um is None:
            raise ParameterError("dry_radius_um", None, "a bead size (um): the target is in "
                                 "seconds")
        if self.mode == "ramp" and self.t_end is None:
            raise ParameterError("t_end", None, "the ramp's final temperature (K)")
        if self.confidence is not None and not 0.0 < self.confidence < 1.0:
            raise ParameterError("confidence", self.confidence, "0 < P < 1")
        lo, hi = self.search_bounds
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise ParameterError("bounds", self.bounds, "low < high")
        if self.mode != "ramp" and not (float(self.t_start) < hi <= T_MAX and lo >= T_MIN):
            raise ParameterError("bounds", self.bounds, f"temperatures above t_start = "
                                 f"{self.t_start} K, at most {T_MAX} K")

    @property
    def search_bounds(self) -> tuple[float, float]:
        """The variable's range: K above T_start (jump, bath), K/min (ramp)."""
        if self.bounds is not None:
            return float(self.bounds[0]), float(self.bounds[1])
        if self.mode == "ramp":
            return RATE_RANGE
        t0 = float(self.t_start)
        return t0 + 0.05, min(t0 + JUMP_SPAN_K, T_MAX)

    def steps(self, x: float) -> list[str] | None:
        """The heating at ``x`` in the step grammar (None: a jump)."""
        if self.mode == "ramp":
            return [f"Heat to {float(self.t_end):.6g} K at {x:.8g} K/min"]
        if self.mode == "bath":
            return [f"Bath at {x:.8g} K with a time constant of {self.time_constant_s:.6g} s"]
        return None

    def words(self, x: float) -> str:
        """The heating in words (the step grammar; a jump as its hold)."""
        steps = self.steps(x)
        return "; ".join(steps) if steps else f"Hold at {x:.6g} K"

    def request(self, x: float, validate: bool = False) -> Any:
        """The planner's one request with the heating at ``x``."""
        from ..question import Batch, Dose, Heating, Jump, OneBead, Request

        steps = self.steps(x)
        heating = Jump(float(x)) if steps is None else Heating(steps)
        dose = Dose(fraction=self.fraction) if self.fraction is not None else Dose(
            drug_mass_ug=self.dose_ug, concentration_ug_per_ul=self.concentration_ug_per_ul)
        pop = OneBead() if not self.size_cv else Batch({"cv": float(self.size_cv)})
        return Request(self.gel, self.t_start, heating, dose, population=pop,
                       dry_radius_um=self.dry_radius_um, constants=self.constants,
                       branch=self.branch, validate=validate)

    def to_dict(self) -> dict[str, Any]:
        """Plain data (the echo of the question)."""
        g = self.gel
        name = getattr(g, "name", None)
        return {"gel": name if isinstance(name, str) and name != "custom" else
                (g.to_dict() if hasattr(g, "to_dict") else g),
                "t_start": self.t_start, "at_seconds": self.at_seconds,
                "fraction": self.fraction, "dose_ug": self.dose_ug,
                "concentration_ug_per_ul": self.concentration_ug_per_ul,
                "dry_radius_um": self.dry_radius_um, "size_cv": self.size_cv,
                "mode": self.mode, "t_end": self.t_end,
                "time_constant_s": self.time_constant_s if self.mode == "bath" else None,
                "bounds": list(self.search_bounds), "validate": self.validate,
                "confidence": self.confidence}


@dataclass(frozen=True)
class Probe:
    """The planner at one heating: ``status`` 'answered' (``seconds``, ``model``), 'full'
    (only a new full-solver run answers), 'never' (the dose is not reached: ``why``)."""

    x: float
    status: str
    seconds: float | None = None
    model: str | None = None
    why: str = ""


def _needs_runs() -> tuple[type[BaseException], ...]:
    from ..question import envelope

    exc = getattr(envelope, "_NeedsRuns", None)
    return (exc,) if isinstance(exc, type) else ()


class _Search:
    """The planner's seconds over the variable, memoised (every probe kept for the report)."""

    def __init__(self, planner: Any, target: HeatingTarget) -> None:
        self.planner, self.target = planner, target
        self.probes: dict[float, Probe] = {}
        self.blocking = 0

    def u(self, x: float) -> float:
        """The search coordinate: log rate for a ramp, else the temperature."""
        return math.log(x) if self.target.mode == "ramp" else x

    def x(self, u: float) -> float:
        return math.exp(u) if self.target.mode == "ramp" else u

    def probe(self, x: float) -> Probe:
        """Answered at once, needing runs, or never (memoised)."""
        x = float(x)
        if x in self.probes:
            return self.probes[x]
        from ..question.envelope import StoredOnly

        try:
            req = self.target.request(x)
            out = req.cell.now(StoredOnly(self.planner), req)
        except _needs_runs():
            p = Probe(x, "full")
        except (ParameterError, NotApplicableError) as exc:
            p = Probe(x, "never", why=str(exc))
        else:
            if out is None or isinstance(out, Pending) or out.seconds is None:
                p = Probe(x, "full")
            else:
                p = Probe(x, "answered", float(out.seconds), str(out.model))
        self.probes[x] = p
        return p

    def run(self, x: float) -> Probe:
        """The planner's blocking answer at ``x`` (a full-solver run where needed)."""
        p = self.probe(x)
        if p.status != "full":
            return p
        self.blocking += 1
        req = self.target.request(x)
        try:
            out = req.cell.run(self.planner, req)
        except (ParameterError, NotApplicableError) as exc:
            p = Probe(x, "never", why=str(exc))
        except SolverError as exc:
            p = Probe(x, "failed", why=str(exc))
        else:
            p = Probe(x, "answered", float(out.seconds), str(out.model))
        self.probes[x] = p
        return p

    def report(self) -> list[dict[str, Any]]:
        return [{"x": p.x, "status": p.status, "seconds": p.seconds, "model": p.model}
                for p in sorted(self.probes.values(), key=lambda p: p.x)]


@dataclass
class HeatingDesign:
    """The heating found: ``value`` of the variable (``variable``, ``unit``), the heating
    in the step grammar, its seconds (model and, validated, truth), the envelope there, the
    range of heatings keeping the target inside the envelope, the confidence heating, and
    how the search went."""

    target: HeatingTarget
    value: float
    seconds: float
    model: str
    result: Any  # the planner's answer at the heating (DoseResult, with its envelope)
    validated_seconds: float | None = None
    polish: list[dict[str, Any]] = field(default_factory=list)
    inside_range: dict[str, Any] | None = None
    confidence: dict[str, Any] | None = None
    search: dict[str, Any] = field(default_factory=dict)

    @property
    def variable(self) -> str:
        return VARIABLE[self.target.mode][0]

    @property
    def unit(self) -> str:
        return VARIABLE[self.target.mode][1]

    @property
    def heating(self) -> str:
        return self.target.words(self.value)

    def to_dict(self) -> dict[str, Any]:
        """Plain data: the heating first, then its answer and envelope."""
        env = self.result.envelope
        e = env.to_dict() if env is not None else None
        secs = (e or {}).get("seconds")
        return {"question": "design heating", "mode": self.target.mode,
                "variable": self.variable, "unit": self.unit, "value": self.value,
                self.variable: self.value, "heating": self.heating,
                "steps": self.target.steps(self.value),
                "target_seconds": self.target.at_seconds, "seconds": self.seconds,
                "model": self.model, "validated_seconds": self.validated_seconds,
                "validated_error": None if self.validated_seconds is None else
                self.validated_seconds / self.target.at_seconds - 1.0,
                "polish": self.polish,
                "envelope_seconds": secs[0] if secs else None,
                "envelope_factor": None if e is None else e["high"] / e["low"],
                "dominant_uncertainty": None if e is None else e["dominant"],
                "envelope": e, "inside_envelope": self.inside_range,
                "confidence": self.confidence, "search": self.search,
                "target": self.target.to_dict(), "answer": self.result.to_dict()}

    def lines(self) -> list[str]:
        """The text answer."""
        t = self.target
        what = f"{t.fraction:.0%} of the fluid" if t.fraction is not None else \
            f"{t.dose_ug:g} ug"
        out = [f"{self.heating}: {what} out at {self.seconds:.4g} s ({self.model}; target "
               f"{t.at_seconds:g} s)"]
        if self.validated_seconds is not None:
            out.append(f"validated: {self.validated_seconds:.4g} s "
                       f"({100 * (self.validated_seconds / t.at_seconds - 1):+.2f}% from the "
                       f"target; {len(self.polish)} validation(s))")
        if self.result.envelope is not None:
            out += self.result.envelope.lines("the dose at this heating after")
        r = self.inside_range
        if r:
            out.append(f"heatings keeping {t.at_seconds:g} s inside the envelope: "
                       f"{_fmt(r['low'])}-{_fmt(r['high'])} {self.unit}"
                       + (" (clipped at the search range)" if r.get("clipped") else ""))
        c = self.confidence
        if c:
            out.append(f"met with probability {c['probability']:.0%} (parts log-uniform): "
                       + (f"{c['value']:.5g} {self.unit} ({c['seconds']:.4g} s point)"
                          if c.get("value") is not None else c.get("note", "not reached")))
        return out


def _fmt(v: float | None) -> str:
    return "-" if v is None else f"{v:.5g}"


# ------------------------------------------------------------------ the search
def _grid(search: _Search) -> np.ndarray:
    lo, hi = search.target.search_bounds
    if search.target.mode == "ramp":
        return np.geomspace(lo, hi, 25)
    n = int(min(max(math.ceil((hi - lo) / 0.5), 8), 80)) + 1
    return np.linspace(lo, hi, n)


def _edge(search: _Search, a: float, b: float, iters: int = 14) -> float:
    """Bisect between an answered ``a`` and an unanswered ``b``: the last answered point
    (in the search coordinate, towards b)."""
    ua, ub = search.u(a), search.u(b)
    for _ in range(iters):
        um = 0.5 * (ua + ub)
        if search.probe(search.x(um)).status == "answered":
            ua = um
        else:
            ub = um
    return search.x(ua)


def _solve(search: _Search, a: float, b: float, target_s: float, blocking: bool) -> float:
    """brentq on seconds(x) - target between a and b (search coordinate)."""
    get = search.run if blocking else search.probe

    def f(u: float) -> float:
        p = get(search.x(u))
        if p.status != "answered":
            raise _Unanswered(p)
        return math.log(p.seconds / target_s)

    try:
        u = brentq(f, search.u(a), search.u(b), xtol=XTOL[search.target.mode], rtol=1e-10,
                   maxiter=60 if not blocking else 14)
    except _Unanswered:
        if blocking or not search.target.full:
            raise
        return _solve(search, a, b, target_s, True)
    return search.x(u)


class _Unanswered(Exception):
    def __init__(self, p: Probe) -> None:
        super().__init__(p.status)
        self.probe = p


def _segments(points: list[Probe]) -> list[list[Probe]]:
    """Runs of consecutive answered probes along the grid."""
    out: list[list[Probe]] = []
    cur: list[Probe] = []
    for p in points:
        if p.status == "answered":
            cur.append(p)
        elif cur:
            out.append(cur)
            cur = []
    if cur:
        out.append(cur)
    return out


def find(search: _Search, target_s: float, full: bool | None = None
         ) -> tuple[float, dict[str, Any]]:
    """The variable at which the planner's seconds equal ``target_s``; ParameterError
    naming ``at`` (or ``fraction``) when nothing in the range reaches it.  ``full``: also
    bracket with blocking full-solver runs (default the target's own ``full``)."""
    full = search.target.full if full is None else full
    grid = [search.probe(x) for x in _grid(search)]
    segs = _segments(grid)
    info: dict[str, Any] = {"method": "brentq", "grid_points": len(grid)}
    # 1. a bracket between answered grid neighbours
    for seg in segs:
        for p, q in zip(seg, seg[1:], strict=False):
            if (p.seconds - target_s) * (q.seconds - target_s) <= 0.0:
                info["bracket"] = [p.x, q.x]
                return _solve(search, p.x, q.x, target_s, False), info
    # 2. the edges of each answered run, bisected towards their unanswered neighbours
    xs = [p.x for p in grid]
    for seg in segs:
        i, j = xs.index(seg[0].x), xs.index(seg[-1].x)
        for k, nb in ((i, i - 1), (j, j + 1)):
            if not 0 <= nb < len(grid):
                continue
            e = _edge(search, grid[k].x, grid[nb].x)
            pe = search.probe(e)
            if (pe.seconds - target_s) * (grid[k].seconds - target_s) <= 0.0:
                info["bracket"] = sorted([grid[k].x, e])
                return _solve(search, grid[k].x, e, target_s, False), info
    # 3. where only the full solver answers: blocking runs beyond the edges
    if full:
        for seg in segs or [[]]:
            for p0, nb in _beyond(grid, seg):
                q = search.run(nb.x)
                if q.status == "answered" and p0 is not None and \
                        (q.seconds - target_s) * (p0.seconds - target_s) <= 0.0:
                    info.update(bracket=sorted([p0.x, q.x]), full_solver=True)
                    return _solve(search, p0.x, q.x, target_s, True), info
    raise _unreachable(search, target_s)


def _beyond(grid: list[Probe], seg: list[Probe]) -> list[tuple[Probe | None, Probe]]:
    """(answered edge, the next grid point needing the full solver) on each side."""
    if not seg:
        return []
    xs = [p.x for p in grid]
    i, j = xs.index(seg[0].x), xs.index(seg[-1].x)
    out = []
    if i > 0 and grid[i - 1].status == "full":
        out.append((seg[0], grid[i - 1]))
    if j + 1 < len(grid) and grid[j + 1].status == "full":
        out.append((seg[-1], grid[j + 1]))
    return out


def _unreachable(search: _Search, target_s: float) -> ParameterError:
    t = search.target
    got = [p for p in search.probes.values() if p.status == "answered"]
    name, unit = VARIABLE[t.mode]
    lo, hi = t.search_bounds
    if not got:
        never = [p for p in search.probes.values() if p.status == "never"]
        if never and len(never) == len(search.probes):
            field_ = "fraction" if t.fraction is not None else "dose_ug"
            return ParameterError(field_, t.fraction if t.fraction is not None else t.dose_ug,
                                  f"a dose some heating of {lo:g}-{hi:g} {unit} delivers",
                                  never[-1].why[:300])
        return ParameterError("at", t.at_seconds, "a time the planner's models reach at once "
                              f"over {lo:g}-{hi:g} {unit}: none answers without the full "
                              "solver here (allow the full solver's search)")
    fast = min(got, key=lambda p: p.seconds)
    slow = max(got, key=lambda p: p.seconds)
    nearest = fast if target_s < fast.seconds else slow
    side = (f"at least {fast.seconds:.4g} s" if nearest is fast
            else f"at most {slow.seconds:.4g} s")
    return ParameterError(
        "at", t.at_seconds,
        f"{side} (reached {fast.seconds:.4g}-{slow.seconds:.4g} s over {name} "
        f"{_fmt(slow.x)}-{_fmt(fast.x)} {unit} of the search range {lo:g}-{hi:g} {unit})",
        f"no {t.mode} in the range delivers the dose at {t.at_seconds:g} s; the nearest "
        f"reachable time is {nearest.seconds:.4g} s ({t.words(nearest.x)})"
        + ("" if t.full else "; searched where the reduced models answer at once (the full "
           "solver's region was not searched)"))


# ------------------------------------------------------------------ the truth
def _truth_seconds(result: Any) -> float | None:
    """The validated (truth's) seconds of an answer, when it carries one."""
    ans = result.answer
    val = getattr(ans, "validation", None) if ans is not None else None
    t = getattr(val, "time", None) if val is not None else None
    if t is None or not result.time:
        model = str(result.model)
        return float(result.seconds) if model == "full" and result.seconds else None
    return float(t) * float(result.seconds) / float(result.time)


def _polish(search: _Search, x0: float, info: dict[str, Any]) -> tuple[float, Any, float,
                                                                        list[dict[str, Any]]]:
    """Validate at the root; correct the target by the truth / model ratio and solve on the
    model again until the truth is within VALIDATE_RTOL."""
    from ..question import plan

    t = search.target
    x, goal, rows = x0, t.at_seconds, []
    res = truth = None
    for _ in range(MAX_POLISH):
        res = plan(t.request(x, validate=True), search.planner)
        truth = _truth_seconds(res)
        if truth is None:
            rows.append({"x": x, "model_seconds": res.seconds, "truth_seconds": None,
                         "note": "this answer carries no validation"})
            break
        rows.append({"x": x, "model_seconds": res.seconds, "truth_seconds": truth,
                     "truth_over_model": truth / res.seconds})
        if abs(truth / t.at_seconds - 1.0) <= VALIDATE_RTOL:
            break
        goal = goal * t.at_seconds / truth
        x = find(search, goal)[0]
    assert res is not None
    return x, res, truth, rows


# ------------------------------------------------------------------ the envelope's use
def _inside_range(search: _Search, env: Any) -> dict[str, Any] | None:
    """The heatings whose envelope (factors held at the root's) keeps the target inside:
    target / high <= point(x) <= target / low."""
    if env is None:
        return None
    t = search.target
    out: dict[str, Any] = {"low": None, "high": None, "clipped": False,
                           "note": "the envelope's factors held at the root's heating"}
    ends = []
    for goal in (t.at_seconds / env.low, t.at_seconds / env.high):
        try:
            ends.append(find(search, goal, full=False)[0])
        except ParameterError:
            ends.append(None)
    got = [e for e in ends if e is not None]
    lo, hi = t.search_bounds
    if len(got) < 2:
        out["clipped"] = True
        seg = [p.x for p in search.probes.values() if p.status == "answered"]
        if seg:  # the answered end in the direction that did not close
            got = got + [min(seg) if all(g > min(seg) for g in got) else max(seg)]
    if got:
        out["low"], out["high"] = min(got), max(got)
    out["search_range"] = [lo, hi]
    return out


def _quantile(env: Any, p: float) -> float:
    """The P-quantile of the product of the counted parts, each log-uniform over its
    bracket (fixed seed)."""
    rng = np.random.default_rng(39)
    logs = np.zeros(CONFIDENCE_SAMPLES)
    for part in env.parts:
        if part.counted and part.high > part.low > 0.0:
            logs += rng.uniform(math.log(part.low), math.log(part.high), CONFIDENCE_SAMPLES)
    return float(math.exp(np.quantile(logs, p)))


def _confidence(search: _Search, env: Any, p: float) -> dict[str, Any]:
    """The heating at which the time is at most the target with probability p."""
    from ..question import plan

    q = _quantile(env, p)
    goal = search.target.at_seconds / q
    out: dict[str, Any] = {"probability": p, "quantile_factor": q,
                           "reading": "each counted part log-uniform over its bracket, "
                                      "independent (the envelope is a bracket, not a "
                                      "distribution: this is a stated reading)"}
    try:
        x = find(search, goal, full=False)[0]
        env2 = plan(search.target.request(x), search.planner).envelope
        q = _quantile(env2, p)  # once more with the parts at that heating
        x = find(search, search.target.at_seconds / q, full=False)[0]
    except ParameterError as exc:
        out.update(value=None, note=f"not reached in the range: {exc}")
        return out
    out.update(value=x, quantile_factor=q, seconds=search.probe(x).seconds,
               heating=search.target.words(x))
    return out


def design_heating(target: HeatingTarget, planner: Any = None) -> HeatingDesign:
    """The heating at which the dose is out at ``target.at_seconds`` (module doc)."""
    if planner is None:
        from ..planner import one_shot

        p = one_shot(None, None)
        try:
            return design_heating(target, p)
        finally:
            p.close()
            p.jobs.executor.shutdown(wait=True)
    from ..question import plan

    search = _Search(planner, target)
    try:
        x, info = find(search, target.at_seconds)
    except _Unanswered as exc:  # the bracket crossed into the full solver's region
        raise SolverError(f"the search left the answered region at {exc.probe.x:g}") from exc
    truth, rows = None, []
    if target.validate:
        x, res, truth, rows = _polish(search, x, info)
    else:
        res = plan(target.request(x), planner)
    env = res.envelope
    inside = _inside_range(search, env)
    conf = None if target.confidence is None or env is None else \
        _confidence(search, env, target.confidence)
    info.update(probes=search.report(), blocking_runs=search.blocking,
                xtol=XTOL[target.mode], coordinate="log rate" if target.mode == "ramp"
                else "temperature")
    return HeatingDesign(target, x, float(res.seconds), str(res.model), res,
                         validated_seconds=truth, polish=rows, inside_range=inside,
                         confidence=conf, search=info)


__all__ = ["MODES", "HeatingDesign", "HeatingTarget", "Probe", "design_heating", "find"]
