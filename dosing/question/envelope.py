"""The envelope of an answer: what the user cannot rule out with what they gave (issue 36).

Every answer (each cell of ``dosing.question.cells``) carries typed :class:`Part` objects and an
:class:`Envelope`: the point answer times every counted part's low ends to their high ends (a
bracket, not a confidence interval); ``dominant_uncertainty`` is the widest counted part.
Parts (reduction, numerical, interfacial length, front law, eq. timescale...): docs/envelope.md."""

from __future__ import annotations

import dataclasses
import json
import math
import threading
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from solver.errors import BudgetExceeded, NotApplicableError, ParameterError, SolverError

from ..answers import Pending
from ..truth import Part as TruthPart
from ..truth import Uncertainty, delayed_settings
from ..units import HOW_TO_PIN, k0_temperature_factor, radius_after_dose, timescale_uncertainty

# the review's measured delayed / Maxwell ratios span 1.05-2.65 (ANB and HHT, jumps and
# ramps: ../shared/design/honest-answers.md sec. 1): the bracket stated when the lattice
# run is not available
FRONT_LAW_PRIOR = (1.0, 3.0)
LATTICE_BUDGET_S = 30.0
PIN = {
    "timescale": HOW_TO_PIN,
    "front_law": ("fit one measured shrinking curve under both front laws (thermogel fit "
                  "kinetics FILE.csv ... --compare-laws: the AIC picks the law), or measure "
                  "a ramp's release: the laws differ most for small doses"),
    "reduction": "ask for the truth: --validate (HTTP \"validate\": true) runs the full solver",
    "numerical": "ask for finer truth settings (SolverSettings n, rtol)",
    "interfacial_length": ("measure the gel's mesh size (swollen mesh from the shear modulus "
                           "or SAXS) and give it as mesh_length_nm"),
    "quadrature": "more quadrature nodes (the batch's own setting)",
    "mesh": ("measure the drug's release from a swollen bead at T_start (sieving) or the "
             "gel's mesh size"),
    "parameters": "more swelling points near the transition, then fit the gel again",
    "k0_temperature": ("kinetics fits at two or more jump temperatures measure D(T), hence "
                       "k0(T) (thermogel fit kinetics at each T_end)"),
}


@dataclass(frozen=True)
class Part:
    """One part of an answer's uncertainty: the time's factor at its ``low`` and ``high``
    ends (low <= 1 <= high), in words, and how to pin it.  ``counted``: in the envelope
    (False: listed only, e.g. numerical inside reduction, or not measured)."""

    name: str
    low: float
    high: float
    text: str
    counted: bool = True
    measured: bool = True
    details: dict[str, Any] = field(default_factory=dict)

    @property
    def factor(self) -> float:
        """high / low: the part's width as a factor."""
        return self.high / self.low if self.low > 0.0 else math.inf

    @property
    def relative(self) -> float:
        """The larger relative move of the time: max(1 - low, high - 1)."""
        return max(1.0 - self.low, self.high - 1.0)

    def to_dict(self) -> dict[str, Any]:
        """Plain data: the factors, the words, how to pin it, and the part's own numbers
        (``ratio`` of the front law, ``source`` of the timescale, ...)."""
        return {"name": self.name, "low": self.low, "high": self.high, "factor": self.factor,
                "relative": self.relative, "counted": self.counted,
                "measured": self.measured, "text": self.text,
                "how_to_pin": PIN.get(self.name, ""), **self.details}


def symmetric(name: str, relative: float, text: str, **kw: Any) -> Part:
    """A +-relative part (a gap measured either way)."""
    r = min(abs(float(relative)), 0.99)
    return Part(name, 1.0 - r, 1.0 + r, text, **kw)


@dataclass(frozen=True)
class Envelope:
    """The bracket over the counted parts around ``point`` (dimensionless times, one per
    heating of a schedule) and ``seconds`` (None without a bead size)."""

    point: tuple[float, ...]
    seconds: tuple[float, ...] | None
    parts: tuple[Part, ...]

    @property
    def low(self) -> float:
        """The product of the counted parts' low factors."""
        return math.prod(p.low for p in self.parts if p.counted)

    @property
    def high(self) -> float:
        """The product of the counted parts' high factors."""
        return math.prod(p.high for p in self.parts if p.counted)

    def time_range(self) -> list[list[float]]:
        """[lo, hi] of each point (dimensionless; the timescale part does not apply)."""
        lo = math.prod(p.low for p in self.parts if p.counted and p.name != "timescale")
        hi = math.prod(p.high for p in self.parts if p.counted and p.name != "timescale")
        return [[t * lo, t * hi] for t in self.point]

    def seconds_range(self) -> list[list[float]] | None:
        """[lo, hi] of each point in seconds (every counted part)."""
        if self.seconds is None:
            return None
        return [[s * self.low, s * self.high] for s in self.seconds]

    @property
    def dominant(self) -> Part | None:
        """The widest counted part (the timescale only when there are seconds)."""
        counted = [p for p in self.parts if p.counted
                   and (self.seconds is not None or p.name != "timescale")]
        return max(counted, key=lambda p: p.factor, default=None)

    def dominant_dict(self) -> dict[str, Any] | None:
        """``dominant_uncertainty``: name, factor, how to pin it."""
        d = self.dominant
        return None if d is None else {"name": d.name, "factor": d.factor,
                                       "how_to_pin": PIN.get(d.name, ""), "text": d.text}

    def to_dict(self) -> dict[str, Any]:
        """Plain data: the ranges, the parts by name, the dominant part."""
        return {"seconds": self.seconds_range(), "time": self.time_range(),
                "low": self.low, "high": self.high,
                "parts": {p.name: p.to_dict() for p in self.parts},
                "dominant": self.dominant_dict()}

    def lines(self, what: str) -> list[str]:
        """The three lines a text answer leads with: the answer with its envelope, the
        dominant part (and the next), how to pin it; seconds to 2 significant figures
        while the timescale is uncalibrated."""
        rng = self.seconds_range()
        unit = "s" if rng is not None else "tau"
        rows = rng if rng is not None else self.time_range()
        pts = self.seconds if self.seconds is not None else self.point
        digits = 2 if any(p.name == "timescale" and p.factor > 1.5 for p in self.parts
                          if p.counted) else 3
        spans = ", ".join(f"{_sig(lo, digits)}-{_sig(hi, digits)} {unit}" for lo, hi in rows)
        pt = ", ".join(_sig(x, 4) for x in pts)
        out = [f"{what} {spans} (point {pt} {unit})"]
        ranked = sorted((p for p in self.parts if p.counted
                         and (self.seconds is not None or p.name != "timescale")),
                        key=lambda p: -p.factor)
        if ranked:
            dom = ranked[0]
            nxt = "".join(f", then {p.name.replace('_', ' ')} x{p.factor:.3g}"
                          for p in ranked[1:3] if p.factor > 1.001)
            out.append(f"dominant uncertainty: {dom.name.replace('_', ' ')} x{dom.factor:.3g}"
                       f"{nxt} (--explain for every part)")
            out.append(f"to pin it: {PIN.get(dom.name, '')}")
        return out


def _sig(x: float, digits: int) -> str:
    """``x`` to ``digits`` significant figures, without an exponent for 1e-3-1e7."""
    if x == 0.0 or not math.isfinite(x) or not 1e-3 <= abs(x) < 1e7:
        return f"{x:.{digits}g}"
    e = math.floor(math.log10(abs(x)))
    v = round(x, digits - 1 - e)
    return f"{v:,.{max(digits - 1 - e, 0)}f}"


# ------------------------------------------------------------------ the parts
def _truth_parts(unc: Any) -> dict[str, Any]:
    """An answer's uncertainty by name, its parts ``dosing.truth.Part`` (an
    :class:`Uncertainty`'s fields, or the mapping a population's or a protocol's answer
    holds)."""
    if unc is None:
        return {}
    return unc.by_name() if isinstance(unc, Uncertainty) else dict(unc)


def error_parts(ans: Any) -> list[Part]:
    """reduction / numerical / interfacial_length from an answer's stated error and its
    truth's parts (``error_estimate`` keeps its meaning: numerical + reduction)."""
    out: list[Part] = []
    model = str(getattr(ans, "model", ""))
    reduced = model.startswith("front") and "+full" not in model
    est = getattr(ans, "error_estimate", None)
    unc = _truth_parts(getattr(ans, "uncertainty", None))
    numerical: TruthPart | None = unc.get("numerical")
    num = None if numerical is None else numerical.relative
    if est is not None and math.isfinite(float(est)):
        text = str(getattr(ans, "error_explanation", "") or "")
        if reduced:
            out.append(symmetric("reduction", est, "reduction: the reduced model's gap to "
                                 f"its truth, {100 * est:.2g}% (error_estimate, its "
                                 f"numerical part included). {text}".strip()))
            if num is not None:
                out.append(symmetric("numerical", num, numerical.text, counted=False))
        else:
            out.append(symmetric("numerical", est if num is None else max(est, num),
                                 f"numerical: {100 * est:.2g}% (error_estimate). {text}"))
    elif num is not None:
        out.append(symmetric("numerical", num, numerical.text))
    ell: TruthPart | None = unc.get("interfacial_length_range")
    if ell is not None and ell.relative is not None:
        out.append(symmetric("interfacial_length", ell.relative, ell.text))
    return out


def _seconds_of(result: Any) -> tuple[float, ...] | None:
    secs = (getattr(result, "actuation_seconds", None) if hasattr(result, "actuation_times")
            else result.seconds)
    if secs is None:
        return None
    secs = tuple(secs) if isinstance(secs, (list, tuple)) else (secs,)
    return secs if secs and all(s is not None for s in secs) else None


def _points(result: Any) -> tuple[float, ...]:
    if hasattr(result, "actuation_times"):
        return tuple(result.actuation_times)
    return (result.time,)


def timescale_part(planner: Any, request: Any, result: Any) -> Part | None:
    """The timescale constants' part: rescaled where the cell's dimensionless answer is free
    of tau, else rerun at each candidate effective diffusivity (``cell.now``; a candidate
    whose rerun needs new full-solver runs is rescaled, and the part says so)."""
    secs = _seconds_of(result)
    planned = request.planned
    constants = getattr(planned, "constants", None)
    t_end = getattr(planned, "t_end", None)
    if secs is None or constants is None or t_end is None:
        return None
    tu = getattr(result.answer, "timescale_uncertainty", None) if result.answer else None
    if tu is None:
        tu = timescale_uncertainty(planned.gel.omega, t_end, constants, secs[0])
    d_used = tu["diffusivity_cm2_s"]
    lo_d, hi_d = tu["diffusivity_range_cm2_s"]
    free = all(getattr(ax, "tau_free", True) for ax in
               (request.payload, request.population, request.heating, request.question))
    details = {"factor_rescaled": hi_d / lo_d, "source": tu.get("source"),
               "calibrated": bool(tu.get("calibrated")),
               "diffusivity_range_cm2_s": [lo_d, hi_d]}
    if free or tu.get("calibrated"):
        how = "rescaled (exact: the dimensionless answer does not depend on tau)" if free \
            else "rescaled over the fit's interval"
        return Part("timescale", d_used / hi_d, d_used / lo_d,
                    f"timescale constants: x{hi_d / lo_d:.3g}, {how}. {tu.get('note', '')}",
                    details=details)
    ratios, rescaled = [], []
    for d in sorted({lo_d, hi_d, *tu.get("candidates_cm2_s", {}).values()}):
        r = _rerun_ratio(planner, request, result, constants, t_end, d, secs)
        if r is None:
            rescaled.append(d)
            r = d_used / d
        ratios.append(r)
    low, high = min(min(ratios), 1.0), max(max(ratios), 1.0)
    how = ("rerun at each candidate diffusivity (a ramp's rate in K/tau and a drug's "
           "D0 / D_gel move with tau: not a rescale)")
    if rescaled:
        how += (f"; rescaled at D = {', '.join(f'{d:.2g}' for d in rescaled)} cm^2/s, whose "
                "rerun needs full-solver runs (a rescale overstates the spread)")
    details.update(rerun=True, rescaled_at_cm2_s=rescaled)
    return Part("timescale", low, high,
                f"timescale constants: x{high / low:.3g} in seconds, {how}. "
                f"{tu.get('note', '')}", details=details)


class _NeedsRuns(Exception):
    """A rerun of the envelope would queue new full-solver runs."""


class _StoredJobs:
    """The planner's job runner that queues nothing (state and results pass through)."""

    def __init__(self, jobs: Any) -> None:
        self._jobs = jobs

    def __getattr__(self, name: str) -> Any:
        if name.startswith("submit"):
            raise _NeedsRuns(name)
        return getattr(self._jobs, name)


class StoredOnly:
    """The planner answering from what it holds: whatever would queue a new full-solver run
    raises instead (an envelope's reruns never load the pool behind the user's back)."""

    def __init__(self, planner: Any) -> None:
        self._planner = planner
        self.jobs = _StoredJobs(planner.jobs)

    def __getattr__(self, name: str) -> Any:
        if name in ("submit", "submit_validation", "_advance", "trajectory", "run_here",
                    "_trajectories"):
            raise _NeedsRuns(name)
        method = getattr(type(self._planner), name, None)
        if callable(method):  # the planner's own method, its self this proxy
            return method.__get__(self)
        return getattr(self._planner, name)


def _rerun_ratio(planner: Any, request: Any, result: Any, constants: Any, t_end: float,
                 d_cm2_s: float, secs: tuple[float, ...]) -> float | None:
    """The cell's seconds at effective diffusivity ``d_cm2_s`` over the answer's, or None
    when the rerun is not available now."""
    if math.isclose(d_cm2_s, constants.diffusivity(t_end) * 1e4, rel_tol=1e-9):
        return 1.0
    return _memo(_RERUNS, _store_key(planner, request, d_cm2_s),
                 lambda: _rerun(planner, request, constants, t_end, d_cm2_s, secs))


def _rerun(planner: Any, request: Any, constants: Any, t_end: float, d_cm2_s: float,
           secs: tuple[float, ...]) -> float | None:
    """:func:`_rerun_ratio` without the memo."""
    alt = dataclasses.replace(constants, diffusivity_m2_s=d_cm2_s * 1e-4,
                              diffusivity_t_k=t_end,
                              diffusivity_source=f"the envelope's candidate {d_cm2_s:.3g}")
    try:
        req = dataclasses.replace(request, constants=alt, validate=False)
        out = req.cell.now(StoredOnly(planner), req)
    except (ParameterError, NotApplicableError, SolverError, ValueError, _NeedsRuns):
        return None
    if out is None or isinstance(out, Pending):
        return None
    got = _seconds_of(out)
    if got is None or len(got) != len(secs) or secs[0] <= 0.0:
        return None
    return max(g / s for g, s in zip(got, secs, strict=True))


def _law_ratio(planner: Any, request: Any, result: Any) -> tuple[float, float, float, int]:
    """(delayed / Maxwell, the delayed time, the Maxwell time, the lattice's N) of one
    answer: the ell = 0 lattice under the answer's own heating to the same radius."""
    target, point = _front_target(result, result.answer, request.planned)
    settings = delayed_settings(_truth())[0]
    sc = request.heating.lattice(request.planned, settings, target)
    t_d = lattice_time(planner, sc, target)
    return (t_d / point if point > 0.0 else 1.0), t_d, point, settings.n


def _law_over_timescale(planner: Any, request: Any, result: Any) -> dict[str, float]:
    """The front law's ratio at each timescale candidate (D in cm^2/s -> ratio) where the
    heating's dimensionless problem depends on tau (a ramp's K/tau, a bath's tau): the
    candidate's answer from what is stored (``StoredOnly``) and its own lattice run; a
    candidate whose answer needs new full-solver runs is left out."""
    if request.heating.tau_free:
        return {}
    return dict(_memo(_RERUNS, _store_key(planner, request, "law"),
                      lambda: _law_candidates(planner, request)))


def _law_candidates(planner: Any, request: Any) -> dict[str, float]:
    """:func:`_law_over_timescale` without the memo."""
    planned = request.planned
    constants, t_end = getattr(planned, "constants", None), getattr(planned, "t_end", None)
    if constants is None or t_end is None or constants.calibrated:
        return {}
    tu = timescale_uncertainty(planned.gel.omega, t_end, constants)
    d_used = tu["diffusivity_cm2_s"]
    out: dict[str, float] = {}
    for d in sorted(set(tu.get("candidates_cm2_s", {}).values())):
        if math.isclose(d, d_used, rel_tol=1e-9):
            continue
        alt = dataclasses.replace(constants, diffusivity_m2_s=d * 1e-4, diffusivity_t_k=t_end,
                                  diffusivity_source=f"the envelope's candidate {d:.3g}")
        try:
            req = dataclasses.replace(request, constants=alt, validate=False)
            got = req.cell.now(StoredOnly(planner), req)
            if got is None or isinstance(got, Pending):
                continue
            out[f"{d:.3g}"] = _law_ratio(planner, req, got)[0]
        except (ParameterError, NotApplicableError, SolverError, ValueError, AssertionError,
                AttributeError, TypeError, _NeedsRuns):
            continue
    return out


def front_law_part(planner: Any, request: Any, result: Any) -> Part:
    """The delayed front law against this answer's Maxwell one: the ell = 0 lattice
    (N = 200) under the same heating to the same radius, stored once per heating.  Under a
    heating whose dimensionless problem moves with tau, the ratio is also taken at each
    timescale candidate, and the part's bracket spans them (``ratio`` stays this answer's;
    the envelope, a product of parts, then overstates rather than misses)."""
    planned = request.planned
    try:
        ratio, t_d, point, n = _law_ratio(planner, request, result)
    except (ParameterError, NotApplicableError, SolverError, ValueError, AssertionError,
            AttributeError, TypeError) as exc:
        lo, hi = FRONT_LAW_PRIOR
        return Part("front_law", lo, hi, (
            f"front law: the lattice run is not available ({str(exc)[:120]}); the delayed / "
            f"Maxwell ratios measured so far span "
            f"1.05-2.65, so the bracket x{lo:g}-{hi:g} is stated"), measured=False,
            details={"ratio": None})
    cal = calibration_ratio(planned)
    calibrated = ""
    if cal is not None:  # tau absorbed the law on the calibration jump
        ratio, calibrated = ratio / cal, (
            f"; over {cal:.3g}, the laws' ratio on the kinetics fit's own curve (its tau "
            "absorbed the law there: the seconds are right on that jump under either law)")
    over = _law_over_timescale(planner, request, result) if cal is None else {}
    where = ("at the mean bead (the batch's beads share its dimensionless curve)"
             if getattr(result, "batch", None) is not None else "")
    first = ("measured on the first heating's dose, the same factor stated for the "
             "later ones" if hasattr(result, "actuation_times") else "")
    note = "; ".join(x for x in (where, first) if x)
    ratios = [ratio, *over.values()]
    spread = ("" if not over else
              f" At the other timescale candidates (the heating is in K/tau there) the ratio "
              f"is {', '.join(f'x{r:.3g} (D {d} cm^2/s)' for d, r in over.items())}; the "
              f"part spans x{min(ratios):.3g}-x{max(ratios):.3g}.")
    return Part("front_law", min(min(ratios), 1.0), max(max(ratios), 1.0), (
        f"front law: x{ratio:.3g}. This answer is the local-equilibrium (Maxwell) front; the "
        f"other consistent law, a delayed (hysteretic) transition, reaches the same radius "
        f"at t = {t_d:.5g} against {point:.5g} tau (the ell = 0 Lagrangian lattice, N = "
        f"{n}, under the same heating{'; ' + note if note else ''}{calibrated})."
        f"{spread} Which law "
        "holds is for experiment to decide (docs/interfacial.md sec. 10)"),
        details={"ratio": ratio, "delayed_time": t_d, "maxwell_time": point,
                 "ratio_over_timescale": over})


_LATTICE_TIMES: OrderedDict[tuple[str, str, float], float] = OrderedDict()
_RERUNS: OrderedDict[tuple[Any, ...], Any] = OrderedDict()  # ratios, law spreads
_LATTICE_LOCK = threading.Lock()


def lattice_time(planner: Any, sc: Any, target: float) -> float:
    """The lattice run's time to ``target`` (run once and stored: ``Planner.run_here``);
    the number kept per process, not the run (a trace's program can be large)."""
    def run() -> float:
        try:
            traj = planner.run_here(sc, need_radius=target, budget=LATTICE_BUDGET_S)
        except BudgetExceeded:  # a process's first run also compiles the solver's kernels
            # (tens of seconds, cold numba cache) inside its budget: once more, compiled
            traj = planner.run_here(sc, need_radius=target, budget=LATTICE_BUDGET_S)
        return float(traj.time_to_radius(target))

    return _memo(_LATTICE_TIMES, (str(getattr(planner.cache, "path", "")), sc.key(),
                                  float(target)), run)


def _store_key(planner: Any, request: Any, *extra: Any) -> tuple[Any, ...] | None:
    """A memo key for what ``request`` gives under the planner's run store as it is now
    (its file and generation: a new run stored makes a new key); None: not memoised."""
    try:
        return (str(planner.cache.path), planner.cache.generation(),
                json.dumps(request.to_dict(), sort_keys=True, default=str), *extra)
    except (AttributeError, TypeError):
        return None


def _memo(table: OrderedDict[Any, Any], key: Any, compute: Callable[[], Any]) -> Any:
    """``compute()`` once per ``key`` in ``table`` (least recently used out past 4096
    entries; a None key computes afresh)."""
    if key is not None:
        with _LATTICE_LOCK:
            if key in table:
                table.move_to_end(key)
                return table[key]
    got = compute()
    if key is not None:
        with _LATTICE_LOCK:
            table[key] = got
            while len(table) > 4096:
                table.popitem(last=False)
    return got


def calibration_ratio(planned: Any) -> float | None:
    """delayed / Maxwell time on a calibrated gel's own kinetics curve (the Maxwell fit's
    tau over the delayed fit's, both stored by ``dosing.fits.gel.kinetics_report``), or None."""
    constants = getattr(planned, "constants", None)
    if constants is None or not getattr(constants, "calibrated", False):
        return None
    from ..fits.gel_store import record_for

    try:
        rec = record_for(planned.gel) or {}
    except (ParameterError, OSError, ValueError):
        return None
    laws = (((rec.get("kinetics") or {}).get("fit") or {}).get("front_laws") or {})
    taus = {k: (v or {}).get("tau_s") for k, v in (laws.get("laws") or {}).items()}
    if not taus.get("maxwell") or not taus.get("delayed"):
        return None
    return float(taus["maxwell"]) / float(taus["delayed"])


def _truth() -> Any:
    from ..runs.scenario import TRUTH

    return TRUTH


def _front_target(result: Any, ans: Any, planned: Any) -> tuple[float, float]:
    """(the radius the dose leaves, the answer's own time to it), dimensionless."""
    if hasattr(result, "actuation_times"):  # a schedule: its first heating's dose
        doses = list(getattr(ans, "doses", []) or [])
        return radius_after_dose(planned.start_radius, float(doses[0])), \
            float(result.actuation_times[0])
    bead = ans if ans is not None else result.batch
    radius = getattr(bead, "final_radius", None)
    if radius is None:  # a drug's dose: the fluid out by then
        radius = radius_after_dose(planned.start_radius, float(bead.fluid_fraction))
    return float(radius), float(bead.time)


def batch_parts(result: Any) -> list[Part]:
    """The batch's quadrature error (relative to its time)."""
    batch = getattr(result, "batch", None)
    quad = getattr(batch, "quadrature", None) if batch is not None else None
    if not quad:
        return []
    err = quad.get("error") if isinstance(quad, dict) else getattr(quad, "error", None)
    if err is None:
        return []
    t = result.time or 1.0
    rel = float(err) / t if t > 0 else float(err)
    return [symmetric("quadrature", rel, f"quadrature: {100 * rel:.2g}% ({quad.get('rule', '')}"
                      f", {quad.get('nodes', '')} nodes)" if isinstance(quad, dict)
                      else f"quadrature: {100 * rel:.2g}%")]


def mesh_part(planner: Any, request: Any, result: Any, blocking: bool) -> list[Part]:
    """A sieved drug's mesh part: the cell rerun at xi_dry / 2 and 2 xi_dry and with the
    other stretch bound (the bead's mechanics cached: solute marches only; blocking only
    where the answer itself was, else from what is stored)."""
    variants = request.payload.mesh_variants(request.planned)
    if not variants:
        return []
    point = _points(result)
    times, missing = [], []
    for label, payload in variants:
        try:
            req = dataclasses.replace(request, payload=payload, validate=False)
            out = (req.cell.run(planner, req) if blocking
                   else req.cell.now(StoredOnly(planner), req))
        except _NeedsRuns:
            out = None
        except (ParameterError, NotApplicableError, SolverError, ValueError) as exc:
            missing.append(f"{label} ({str(exc)[:100]})")
            continue
        if out is None or isinstance(out, Pending) or not point[0] > 0.0:
            missing.append(f"{label} (its runs are not stored)")
            continue
        got = _points(out)
        if len(got) != len(point):  # a schedule the variant meets in another number of heatings
            missing.append(f"{label} (its schedule has {len(got)} heatings, not {len(point)})")
            continue
        times.append((label, max(t / p for t, p in zip(got, point, strict=True))))
    if not times:
        return [Part("mesh", 1.0, 1.0, (
            "mesh: not measured in this answer (its reruns need solute runs not stored: "
            f"{', '.join(missing)}); a solute near the gel's mesh size can move its release "
            "by 1-78 % over xi_dry 2-8 nm and the stretch bound"), counted=False,
            measured=False)]
    ratios = [r for _, r in times]
    low, high = min(min(ratios), 1.0), max(max(ratios), 1.0)
    listing = ", ".join(f"{label}: x{r:.3g}" for label, r in times)
    drug = getattr(request.planned, "drug", None)
    micro = ("" if getattr(drug, "fiber_radius_nm", None) is not None else
             "; the microstructure (pore transmission with free-volume diffusion against a "
             "fibre matrix) is not bounded: give the drug a fibre radius to rerun it")
    return [Part("mesh", low, high, (
        f"mesh: x{high / low:.3g}, the sieving rerun over the mesh's plausible range, "
        f"both stretch bounds and, with a fibre radius, the other microstructure ({listing}"
        + (f"; not run: {', '.join(missing)}" if missing else "") + ")" + micro),
        details={"variants": dict(times)})]


def parameter_parts(ans: Any) -> list[Part]:
    """A fitted gel's swelling-parameter interval on the time (``parameter_interval``:
    its relative half-width; the kinetics fit's part is the timescale's)."""
    pi = getattr(ans, "parameter_interval", None) if ans is not None else None
    rel = (pi or {}).get("relative_half_width")
    if rel is None or not math.isfinite(float(rel)):
        return []
    return [Part("parameters", math.exp(-rel), math.exp(rel),
                 f"parameters: the fitted gel's swelling parameters move the time by "
                 f"+-{100 * rel:.2g}% ({pi.get('method', 'delta')}). {pi.get('note', '')}"
                 .strip())]


def k0_temperature_part(request: Any) -> list[Part]:
    """k0's temperature law, when the constants ask for one (``k0_law``): the answer keeps
    k0 as given (at ``k0_reference_t_k``, or at a kinetics fit's temperature), the part the
    time's factor k0(T_ref) / k0(T_hot) at the heating's hottest temperature (a bracket: a
    ramp passes cooler temperatures on its way)."""
    planned = request.planned
    constants, t_hot = getattr(planned, "constants", None), getattr(planned, "t_end", None)
    law = getattr(constants, "k0_law", "constant")
    if constants is None or t_hot is None or law == "constant":
        return []
    t_ref = (constants.diffusivity_t_k if constants.calibrated
             else constants.k0_reference_t_k)
    f = k0_temperature_factor(law, float(t_hot), float(t_ref))
    where = ("the kinetics fit's temperature" if constants.calibrated
             else "where k0 is given")
    return [Part("k0_temperature", min(1.0, 1.0 / f), max(1.0, 1.0 / f), (
        f"k0's temperature law '{law}': k0 at {float(t_hot):g} K is x{f:.3g} its value at "
        f"{float(t_ref):g} K ({where}), so the time x{1.0 / f:.3g} (Tokita & Tanaka, Science "
        "253, 1121, 1991: the network-water friction falls by three decades approaching the "
        "transition; the law is a log-linear stand-in over 20-34 degC, not a fit)"),
        details={"law": law, "k0_ratio": f, "t_hot": float(t_hot), "t_ref": float(t_ref)})]


def envelope(planner: Any, request: Any, result: Any, blocking: bool = False) -> Envelope:
    """The envelope of ``result`` (the answer to ``request`` on ``planner``; ``blocking``:
    the answer itself waited on runs, so may its mesh reruns)."""
    ans = result.answer if result.answer is not None else getattr(result, "batch", None)
    parts: list[Part] = error_parts(ans)
    ts = timescale_part(planner, request, result)
    if ts is not None:
        parts.append(ts)
    parts.append(front_law_part(planner, request, result))
    parts += (batch_parts(result) + mesh_part(planner, request, result, blocking)
              + parameter_parts(result.answer) + k0_temperature_part(request))
    return Envelope(_points(result), _seconds_of(result), tuple(parts))
