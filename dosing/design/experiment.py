"""The experiment that best pins an answer's dominant parts (issue 39).

An answer (gel, T_start -> T_end, a dose, a bead) leads with its envelope
(``dosing.question.envelope``); uncalibrated, its widest parts are the timescale (the
constants of eq. timescale, x26-100) and the front law (Maxwell or delayed, x1.3-2.6).
Both are pinned by one shrinking curve after a jump, fitted with ``thermogel fit kinetics``
(tau and the size scale; its law comparison between the two front laws).  This module
chooses that curve: the jump T_e, the bead size (from the lab's sizes) and the sampling
times, and predicts what the fit will give.

Method (Fisher information, not simulated fits): the measured radius is
y_i = s a(t_i / tau)(1 + S e_i), e_i standard normal, S the relative size noise; the
Maxwell curve a(.) is the front-sharp model's (the model ``fit kinetics`` uses for a front
jump), so the fit's information on (log tau, log s) is F = sum_i g_i g_i^T with
g_i = (-s a'(t_i/tau) t_i/tau, s a(t_i/tau)) / (S y_i).  The 95 % interval of tau is
exp(+-t_q sqrt((F^-1)_00)) (Student t on n - 2, as the fit states it).  tau is not known
before the measurement (the timescale part spans a factor 26-100), so the design is robust:
its criterion is taken over a log-uniform grid of tau across the timescale part's bracket
(``TAU_GRID`` values): D-optimal (the mean of log det F) or the dose-time interval (the
largest var(log tau) over the grid), and the predicted interval is the widest over the grid.
The times are chosen greedily (sequential D-optimal design on a log-spaced candidate grid,
distinct, at least ``min_interval_s`` apart, the first at the jump).

The fitted D = R^2 / tau at T_e carries to the answer's T_end through eq. timescale's own
temperature dependence (D ~ T / eta(T)): a relative interval of tau is the same relative
interval of the answer's seconds.  The predicted envelope after is the answer's envelope
with its timescale part replaced by that interval (the other parts held: the front law's
ratio, the reduction, the batch's quadrature do not depend on tau).

The front laws: the delayed law's curve is the ell = 0 Lagrangian lattice at N = 200 (the
envelope's own run, ``Planner.run_here``, stored).  ``law_separation_sigma`` is the distance
between the two laws' curve families in noise widths: sqrt(min chi^2) of the other law
fitted (tau and scale free) to one law's noise-free curve at the design's times, the smaller
of the two directions and the worst over the tau grid.  The expected Delta AIC of the fit's
law comparison is about its square.  When the front law dominates the envelope after the
timescale is pinned, the design maximises this separation among the candidates whose
predicted envelope is within ``ENVELOPE_SLACK`` of the narrowest.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from solver.errors import ParameterError

TAU_GRID = 7  # log-uniform tau values over the timescale part's bracket
CANDIDATE_TIMES = 240
ENVELOPE_SLACK = 1.05  # designs within 5 % of the narrowest predicted envelope compete on
# the law separation when the front law dominates
MAX_DURATION_S = 3600.0
N_POINTS = 20
MIN_INTERVAL_S = 1.0
CRITERIA = ("d-optimal", "interval")
JUMP_STEP_K = 0.5
N_JUMPS = 4  # default candidate jumps in the front model's region (plus the answer's own)
LATTICE_BUDGET_S = 60.0


@dataclass(frozen=True)
class ExperimentAsk:
    """The answer to pin (``gel``, ``t_start`` -> ``t_end``, dose ``fraction``, bead
    ``dry_radius_um``) and what the lab can do: ``size_noise`` (relative, per radius),
    ``max_duration_s``, ``n_points``, ``min_interval_s`` between samples, ``sizes_um`` (the
    bead sizes it can make; default the answer's), ``jumps`` (candidate T_e in K; default a
    few in the front model's region from T_start, the answer's own T_end among them),
    ``criterion`` 'd-optimal' (robust D-optimal for tau) or 'interval' (the widest
    predicted dose-time interval, minimised)."""

    gel: Any
    t_start: float
    t_end: float
    fraction: float
    dry_radius_um: float
    size_noise: float = 0.01
    max_duration_s: float = MAX_DURATION_S
    n_points: int = N_POINTS
    min_interval_s: float = MIN_INTERVAL_S
    sizes_um: tuple[float, ...] | None = None
    jumps: tuple[float, ...] | None = None
    criterion: str = "d-optimal"
    simulate: int = 0  # also check the Fisher interval with this many simulated fits
    constants: Any = None
    branch: str | None = None

    def __post_init__(self) -> None:
        s = self.size_noise
        if not (isinstance(s, (int, float)) and math.isfinite(s) and 1e-5 <= s <= 0.3):
            raise ParameterError("size_noise", s, "a relative size noise 1e-5-0.3")
        if not (math.isfinite(self.max_duration_s) and 1.0 <= self.max_duration_s <= 1e6):
            raise ParameterError("max_duration", self.max_duration_s, "1 s-1e6 s")
        if not 4 <= int(self.n_points) <= 200:
            raise ParameterError("n_points", self.n_points, "4-200 samples")
        if not (math.isfinite(self.min_interval_s) and 0.0 <= self.min_interval_s):
            raise ParameterError("min_interval", self.min_interval_s, ">= 0 s")
        if self.min_interval_s * (int(self.n_points) - 1) > self.max_duration_s:
            raise ParameterError("n_points", self.n_points, f"at most "
                                 f"{int(self.max_duration_s / max(self.min_interval_s, 1e-9)) + 1}"
                                 f" samples {self.min_interval_s:g} s apart within "
                                 f"{self.max_duration_s:g} s (max_duration)")
        if not 0 <= int(self.simulate) <= 500:
            raise ParameterError("simulate", self.simulate, "0-500 simulated fits")
        if self.criterion not in CRITERIA:
            raise ParameterError("criterion", self.criterion, " | ".join(CRITERIA))
        for r in self.sizes_um or ():
            if not (math.isfinite(r) and 0.01 <= r <= 1e5):
                raise ParameterError("sizes_um", r, "dry radii 0.01-1e5 um")
        for t in self.jumps or ():
            if not (math.isfinite(t) and t > float(self.t_start)):
                raise ParameterError("jumps", t, f"temperatures above t_start = "
                                     f"{self.t_start} K")

    def request(self) -> Any:
        """The answer's request (one bead, a jump, a fluid dose)."""
        from ..question import Dose, Jump, Request

        return Request(self.gel, self.t_start, Jump(self.t_end), Dose(self.fraction),
                       dry_radius_um=self.dry_radius_um, constants=self.constants,
                       branch=self.branch)

    def to_dict(self) -> dict[str, Any]:
        g = self.gel
        name = getattr(g, "name", None)
        return {"gel": name if isinstance(name, str) and name != "custom" else
                (g.to_dict() if hasattr(g, "to_dict") else g),
                "t_start": self.t_start, "t_end": self.t_end, "fraction": self.fraction,
                "dry_radius_um": self.dry_radius_um, "size_noise": self.size_noise,
                "max_duration_s": self.max_duration_s, "n_points": self.n_points,
                "min_interval_s": self.min_interval_s,
                "sizes_um": None if self.sizes_um is None else list(self.sizes_um),
                "jumps": None if self.jumps is None else list(self.jumps),
                "criterion": self.criterion, "simulate": self.simulate}


# ------------------------------------------------------------------ the curves
@dataclass(frozen=True)
class Curves:
    """One jump's dimensionless curves: the Maxwell law's (front-sharp) and the delayed
    law's (the ell = 0 lattice), radius in dry radii against t / tau."""

    t_end: float
    maxwell: Any
    delayed_t: np.ndarray
    delayed_a: np.ndarray
    a0: float
    a_end: float
    t_stop: float  # the Maxwell front reaches the centre

    def delayed(self, s: np.ndarray) -> np.ndarray:
        return np.interp(np.asarray(s, float), self.delayed_t, self.delayed_a)

    def law(self, name: str, s: np.ndarray) -> np.ndarray:
        return self.maxwell(s) if name == "maxwell" else self.delayed(s)


def jump_curves(planner: Any, gel: Any, t_start: float, t_end: float, branch: str) -> Curves:
    """The two laws' curves after the jump (the lattice run on the planner, stored)."""
    from scipy.interpolate import PchipInterpolator

    from ..model_choice import front_run
    from ..runs.scenario import TRUTH, Scenario
    from ..truth import delayed_settings

    fr = front_run(gel, t_start, t_end, branch, True)
    c = fr.curve
    # the front model's curve tabulated once (PCHIP in log t: its own inversion costs ~8 ms
    # a call in Python, and the design evaluates it thousands of times)
    t0 = max(float(c.t_start), 0.0)
    grid = np.geomspace(max(float(fr.t_stop) * 1e-9, 1e-12), float(fr.t_stop), 1500)
    grid = grid[grid > t0]
    table = np.asarray(c.radius(c.front_at(grid)), dtype=float)
    spline = PchipInterpolator(np.log(grid), table, extrapolate=False)
    a_first = float(np.asarray(c.radius(c.front_at(np.array([max(t0, 0.0)]))))[0])

    def maxwell(s: np.ndarray) -> np.ndarray:
        ss = np.clip(np.asarray(s, dtype=float), grid[0], grid[-1])
        out = spline(np.log(ss))
        return np.where(np.asarray(s, float) <= grid[0], a_first, out)

    a0 = float(maxwell(np.zeros(1))[0])
    a_end = float(maxwell(np.array([fr.t_stop]))[0])
    need = a_end + 0.002 * (a0 - a_end)
    st = delayed_settings(TRUTH)[0]
    traj = planner.run_here(Scenario(gel, t_start, t_end, branch=branch, settings=st),
                            need_radius=need, budget=LATTICE_BUDGET_S)
    tt, aa = (traj.step_t, traj.step_radius) if traj.step_t.size >= 2 else (traj.t, traj.radius)
    return Curves(float(t_end), maxwell, np.asarray(tt, float), np.asarray(aa, float), a0,
                  a_end, float(fr.t_stop))


# ------------------------------------------------------------------ information
def _gradients(curve: Any, times: np.ndarray, tau: float, noise: float) -> np.ndarray:
    """g_i (2 x n): d y_i / d(log tau, log s) over the noise width S y_i (s = 1)."""
    s = times / tau
    a = curve(s)
    h = 1e-4
    da = (curve(s * math.exp(h)) - curve(s * math.exp(-h))) / (2 * h)  # d a / d log s
    return np.vstack([-da, a]) / (noise * a)


def _fisher(g: np.ndarray) -> np.ndarray:
    return g @ g.T


def tau_sd(curve: Any, times: np.ndarray, tau: float, noise: float) -> float:
    """sd of log tau from the Fisher information at ``times``."""
    f = _fisher(_gradients(curve, np.asarray(times, float), tau, noise))
    det = f[0, 0] * f[1, 1] - f[0, 1] ** 2
    return math.sqrt(f[1, 1] / det) if det > 0 else math.inf


def greedy_times(curve: Any, taus: np.ndarray, noise: float, n: int, t_max: float,
                 min_interval: float, criterion: str) -> np.ndarray:
    """n sampling times from a log-spaced candidate grid (and t = 0): each added where it
    raises the criterion most, averaged (d-optimal) or worst (interval) over ``taus``."""
    lo = max(min_interval, t_max * 1e-5, 1e-3)
    cand = np.unique(np.concatenate([[0.0], np.geomspace(lo, t_max, CANDIDATE_TIMES)]))
    g = np.stack([_gradients(curve, cand, tau, noise) for tau in taus])  # (k, 2, m)
    ridge = 1e-9 * np.eye(2)
    f = np.broadcast_to(ridge, (len(taus), 2, 2)).copy()
    free = np.ones(cand.size, bool)
    chosen: list[float] = []
    for _ in range(n):
        # F + g g^T for every candidate and tau: det and (F^-1)_00
        f00 = f[:, 0, 0][:, None] + g[:, 0, :] ** 2
        f11 = f[:, 1, 1][:, None] + g[:, 1, :] ** 2
        f01 = f[:, 0, 1][:, None] + g[:, 0, :] * g[:, 1, :]
        det = f00 * f11 - f01**2
        if criterion == "d-optimal":
            score = np.mean(np.log(np.maximum(det, 1e-300)), axis=0)
        else:
            score = -np.max(f11 / np.maximum(det, 1e-300), axis=0)
        score = np.where(free, score, -np.inf)
        j = int(np.argmax(score))
        if not np.isfinite(score[j]):
            break
        chosen.append(float(cand[j]))
        f[:, 0, 0] = f00[:, j]
        f[:, 1, 1] = f11[:, j]
        f[:, 0, 1] = f[:, 1, 0] = f01[:, j]
        free &= np.abs(cand - cand[j]) >= max(min_interval, 1e-9)
        free[j] = False
    return np.sort(np.array(chosen))


def separation(curves: Curves, times: np.ndarray, tau: float, noise: float) -> float:
    """The two laws apart in noise widths at ``times``: sqrt(min chi^2) of the other law
    fitted (tau, scale) to one law's noise-free curve, the smaller direction."""
    out = []
    for data_law, fit_law in (("maxwell", "delayed"), ("delayed", "maxwell")):
        y = curves.law(data_law, times / tau)
        sig = noise * y

        def res(x: np.ndarray, fit_law: str = fit_law, y: np.ndarray = y,
                sig: np.ndarray = sig) -> np.ndarray:
            return (math.exp(x[1]) * curves.law(fit_law, times / math.exp(x[0])) - y) / sig

        best = math.inf
        lt = math.log(tau)
        for shift in (0.0, 0.5, -0.5, 1.0):
            r = least_squares(res, [lt + shift, 0.0], method="trf", xtol=1e-10, ftol=1e-10,
                              bounds=([lt - 8.0, -3.0], [lt + 8.0, 3.0]), max_nfev=400)
            best = min(best, float(np.sum(r.fun**2)))
        out.append(math.sqrt(best))
    return min(out)


# ------------------------------------------------------------------ the design
@dataclass
class Candidate:
    """One experiment: the jump, the bead, the times, and what they predict."""

    t_end: float
    dry_radius_um: float
    tau_nominal_s: float
    times_s: np.ndarray
    tau_half_width: float  # the widest 95 % relative half-width of log tau over the grid
    separation: float
    separations: list[float]
    score: float

    def to_dict(self) -> dict[str, Any]:
        return {"t_end": self.t_end, "dry_radius_um": self.dry_radius_um,
                "tau_nominal_s": self.tau_nominal_s,
                "timescale_factor_after": math.exp(2 * self.tau_half_width),
                "law_separation_sigma": self.separation,
                "n_points": int(self.times_s.size)}


@dataclass
class ExperimentDesign:
    """The recommended experiment and its predictions (``to_dict`` for JSON)."""

    ask: ExperimentAsk
    best: Candidate
    candidates: list[Candidate]
    before: Any  # the answer's Envelope
    after_parts: list[Any]
    tau_grid_s: list[float]
    law_focus: bool
    point_seconds: float
    t_start: float
    expected: dict[str, Any] = field(default_factory=dict)
    simulated: dict[str, Any] | None = None

    @property
    def envelope_before_factor(self) -> float:
        return self.before.high / self.before.low

    @property
    def envelope_after_factor(self) -> float:
        lo = math.prod(p.low for p in self.after_parts if p.counted)
        hi = math.prod(p.high for p in self.after_parts if p.counted)
        return hi / lo

    def _factor_without(self, name: str) -> float:
        """The predicted envelope's width without one part (the front law's, were the
        envelope to drop it once a fit has decided the law)."""
        ps = [p for p in self.after_parts if p.counted and p.name != name]
        return math.prod(p.high for p in ps) / math.prod(p.low for p in ps)

    def steps(self) -> list[str]:
        b = self.best
        dur = float(b.times_s.max()) if b.times_s.size else self.ask.max_duration_s
        return [f"Rest at {self.t_start:g} K for 30 min",
                f"Hold at {b.t_end:.6g} K for {max(dur, 1.0):.6g} s"]

    def table(self) -> list[dict[str, Any]]:
        """The sampling table: one row per sample, the expected radius under both laws at
        the nominal tau (for the lab's sanity, not a target)."""
        b, e = self.best, self.expected
        rows = []
        for i, t in enumerate(b.times_s):
            rows.append({"sample": i + 1, "time_s": float(t),
                         "expected_radius_um_maxwell": e["maxwell"][i],
                         "expected_radius_um_delayed": e["delayed"][i]})
        return rows

    def to_dict(self) -> dict[str, Any]:
        from ..question.envelope import Envelope

        b = self.best
        after = Envelope((0.0,), (self.point_seconds,), tuple(self.after_parts))
        bef = self.before.to_dict()
        aft = after.to_dict()
        return {
            "question": "design experiment",
            "experiment": {"jump": {"t_start": self.t_start, "t_end": b.t_end},
                           "dry_radius_um": b.dry_radius_um,
                           "steps": self.steps(), "protocol": "; ".join(self.steps()),
                           "sampling_times_s": [float(t) for t in b.times_s],
                           "size_noise": self.ask.size_noise,
                           "fit": (f"thermogel fit kinetics FILE.csv --gel "
                                   f"{self.ask.to_dict()['gel']} --t-start {self.t_start:g} "
                                   f"--t-end {b.t_end:.6g} --dry-radius-um "
                                   f"{b.dry_radius_um:g} --size-rel-sigma "
                                   f"{self.ask.size_noise:g} --compare-laws --save NAME")},
            "sampling_table": self.table(),
            "envelope_before_seconds": bef["seconds"][0] if bef["seconds"] else None,
            "envelope_before_factor": self.envelope_before_factor,
            "envelope_after_seconds": aft["seconds"][0] if aft["seconds"] else None,
            "envelope_after_factor": self.envelope_after_factor,
            "envelope_after_method": (
                "Fisher information of the kinetics fit (tau, size scale) at the design, "
                "relative size noise, the widest 95 % interval of tau over a log-uniform "
                f"grid of {len(self.tau_grid_s)} tau values across the timescale part's "
                "bracket; the other parts of the answer's envelope held"),
            "timescale_factor_after": math.exp(2 * b.tau_half_width),
            "envelope_after_factor_law_pinned": self._factor_without("front_law"),
            "simulated_fits": self.simulated,
            "law_separation_sigma": b.separation,
            "law_separation_by_tau": [{"tau_s": t, "sigma": s} for t, s in
                                      zip(self.tau_grid_s, b.separations, strict=True)],
            "expected_delta_aic": b.separation ** 2,
            "law_decided": bool(b.separation >= 3.0),
            "chosen_for": ("the law separation (the front law dominates once the timescale "
                           "is pinned), among designs within 5 % of the narrowest predicted "
                           "envelope" if self.law_focus else
                           f"the predicted envelope ({self.ask.criterion})"),
            "dominant_before": self.before.dominant_dict(),
            "dominant_after": after.dominant_dict(),
            "parts_after": {p.name: p.to_dict() for p in self.after_parts},
            "point_seconds": self.point_seconds,
            "tau_grid_s": self.tau_grid_s,
            "candidates": [c.to_dict() for c in self.candidates],
            "ask": self.ask.to_dict(),
            "assumptions": ASSUMPTIONS,
        }

    def lines(self) -> list[str]:
        d = self.to_dict()
        b = self.best
        bl, bh = d["envelope_before_seconds"] or (math.nan, math.nan)
        al, ah = d["envelope_after_seconds"] or (math.nan, math.nan)
        out = [f"measure: {d['experiment']['protocol']} (a {b.dry_radius_um:g} um dry bead), "
               f"{b.times_s.size} radii at the times below",
               f"envelope now {bl:.2g}-{bh:.3g} s (x{d['envelope_before_factor']:.3g}); "
               f"predicted after the fit {al:.3g}-{ah:.3g} s "
               f"(x{d['envelope_after_factor']:.3g}; Fisher information)",
               f"the two front laws apart by {b.separation:.3g} noise widths (expected "
               f"Delta AIC ~{b.separation ** 2:.3g}: "
               f"{'decided' if d['law_decided'] else 'NOT decided'} by the fit)",
               f"then: {d['experiment']['fit']}",
               "sample  time_s      radius_um (Maxwell / delayed, at the nominal tau)"]
        for r in d["sampling_table"]:
            out.append(f"{r['sample']:6d}  {r['time_s']:<10.4g}  "
                       f"{r['expected_radius_um_maxwell']:.4g} / "
                       f"{r['expected_radius_um_delayed']:.4g}")
        return out

    def csv(self) -> str:
        """The sampling table a lab fills in (time_s, radius_um), '#' lines describing the
        experiment and the expected radii; ``fit kinetics`` reads it as it is once the radii
        are written."""
        d = self.to_dict()
        table = self.table()
        head = [f"# thermogel design experiment: {d['experiment']['protocol']}",
                f"# bead: {self.best.dry_radius_um:g} um dry radius; size noise "
                f"{self.ask.size_noise:g} (relative); write each measured radius (um)",
                f"# then: {d['experiment']['fit']}",
                "# expected radius (um) at the nominal tau, sample: Maxwell law / delayed law",
                *(f"#   {r['sample']:3d} at {r['time_s']:.6g} s: "
                  f"{r['expected_radius_um_maxwell']:.5g} / "
                  f"{r['expected_radius_um_delayed']:.5g}" for r in table),
                "time_s,radius_um"]
        rows = [f"{r['time_s']:.6g}," for r in table]
        return "\n".join(head + rows) + "\n"


ASSUMPTIONS = [
    "noise: independent Gaussian relative errors of the measured radius (size_noise), no "
    "error in time; the fit weights as thermogel fit kinetics does",
    "the fit: tau and the size scale free, the gel's swelling parameters and permeability "
    "law held fixed (the curve's shape is the model's)",
    "the two laws: Maxwell (local equilibrium at the front: the front-sharp model, the "
    "curve fit kinetics fits) and delayed (the ell = 0 Lagrangian lattice, N = 200)",
    "tau unknown before the measurement: the design is robust over a log-uniform grid "
    "across the timescale part's bracket; the prediction is the grid's widest interval",
    "D fitted at the experiment's T_e carries to the answer's T_end through eq. "
    "timescale (D ~ T / eta(T)); the answer's other parts (front law, reduction) held",
]


def front_region(gel: Any, t_start: float, branch: str) -> list[float]:
    """The jumps from ``t_start`` (every JUMP_STEP_K up to 20 K) where a front forms."""
    from ..model_choice import choose_model

    front = []
    for t in np.arange(t_start + JUMP_STEP_K, t_start + 20.0, JUMP_STEP_K):
        try:
            if choose_model(gel, t_start, float(t), branch)[0] == "front":
                front.append(float(t))
        except (ParameterError, ValueError):
            continue
    return front


def _candidate_jumps(ask: ExperimentAsk, gel: Any, branch: str) -> list[float]:
    """The experiment's jumps: given, or the front model's region from T_start sampled
    (the answer's own T_end among them when the front applies there)."""
    from ..model_choice import choose_model

    if ask.jumps:
        return sorted(set(float(t) for t in ask.jumps))
    front = front_region(gel, float(ask.t_start), branch)
    if not front:
        return [float(ask.t_end)]
    pick = [front[int(round(i))] for i in np.linspace(0, len(front) - 1, min(N_JUMPS,
                                                                                len(front)))]
    try:
        if choose_model(gel, float(ask.t_start), float(ask.t_end), branch)[0] == "front":
            pick.append(float(ask.t_end))
    except (ParameterError, ValueError):
        pass
    return sorted(set(pick))


def design_experiment(ask: ExperimentAsk, planner: Any = None) -> ExperimentDesign:
    """The recommended shrinking-curve experiment and its predicted envelope (module doc)."""
    if planner is None:
        from ..planner import one_shot

        p = one_shot(None, None)
        try:
            return design_experiment(ask, p)
        finally:
            p.close()
            p.jobs.executor.shutdown(wait=True)
    from solver.fit.result import t_quantile

    from ..model_choice import choose_model
    from ..question import plan
    from ..question.envelope import Part
    from ..units import timescale

    req = ask.request()
    planned = req.planned
    gel, branch, constants = planned.gel, planned.branch, planned.constants
    res = plan(req, planner)
    env = res.envelope
    ts = next((p for p in env.parts if p.name == "timescale"), None)
    d_used = constants.diffusivity(float(ask.t_end)) * 1e4
    lo_d, hi_d = (ts.details.get("diffusivity_range_cm2_s") if ts is not None else None) \
        or (d_used, d_used)
    jumps = _candidate_jumps(ask, gel, branch)
    sizes = sorted(set(ask.sizes_um or (float(ask.dry_radius_um),)))
    tq = t_quantile(max(int(ask.n_points) - 2, 1))
    cands: list[Candidate] = []
    curves_of: dict[float, Curves] = {}
    for te in jumps:
        try:
            if choose_model(gel, float(ask.t_start), te, branch)[0] != "front":
                region = front_region(gel, float(ask.t_start), branch)
                where = (f"{region[0]:g}-{region[-1]:g} K (sampled every {JUMP_STEP_K:g} K)"
                         if region else "none within 20 K of t_start")
                raise ParameterError("jumps", te, f"a jump from {float(ask.t_start):g} K "
                                     f"where a front forms: {where}", "the curve fit "
                                     "kinetics fits there is the front model's")
            cv = curves_of[te] = jump_curves(planner, gel, float(ask.t_start), te, branch)
        except ParameterError:
            if ask.jumps:
                raise
            continue
        for r in sizes:
            tau_nom = timescale(r, te, constants).seconds
            # tau over the timescale part's bracket (D from d_used to the range's ends)
            taus = tau_nom * np.geomspace(d_used / hi_d, d_used / lo_d,
                                                        TAU_GRID)
            times = greedy_times(cv.maxwell, taus, ask.size_noise, int(ask.n_points),
                                 float(ask.max_duration_s), float(ask.min_interval_s),
                                 ask.criterion)
            sds = [tau_sd(cv.maxwell, times, tau, ask.size_noise) for tau in taus]
            half = tq * max(sds)
            seps = [separation(cv, times, tau, ask.size_noise) for tau in taus]
            score = float(np.mean(np.log(np.maximum(sds, 1e-300))))
            cands.append(Candidate(te, float(r), tau_nom, times, half, min(seps), seps,
                                   score))
    if not cands:
        raise ParameterError("jumps", list(jumps), "a jump from t_start the front model "
                             "answers (no candidate experiment could be made)")
    others = [p for p in env.parts if p.name != "timescale"]

    def after(c: Candidate) -> list[Any]:
        h = c.tau_half_width
        return others + [Part("timescale", math.exp(-h), math.exp(h), (
            f"timescale after the kinetics fit: +-{100 * (math.exp(h) - 1):.2g}% "
            "(predicted: Fisher information at the design)"), details={"predicted": True})]

    def width(c: Candidate) -> float:
        ps = after(c)
        return (math.prod(p.high for p in ps if p.counted)
                / math.prod(p.low for p in ps if p.counted))

    narrowest = min(width(c) for c in cands)
    dom_after = max((p for p in after(min(cands, key=width)) if p.counted),
                    key=lambda p: p.factor)
    law_focus = dom_after.name == "front_law"
    if law_focus:
        pool = [c for c in cands if width(c) <= ENVELOPE_SLACK * narrowest]
        best = max(pool, key=lambda c: c.separation)
    else:
        best = min(cands, key=width)
    cv = curves_of[best.t_end]
    s = best.times_s / best.tau_nominal_s
    expected = {"maxwell": (best.dry_radius_um * cv.maxwell(s)).tolist(),
                "delayed": (best.dry_radius_um * cv.delayed(s)).tolist()}
    taus_best = best.tau_nominal_s * np.geomspace(d_used / hi_d, d_used / lo_d, TAU_GRID)
    sim = None if not ask.simulate else simulated_fits(
        cv, best, taus_best, ask.size_noise, int(ask.simulate), tq)
    return ExperimentDesign(ask, best, cands, env, after(best),
                            [float(t) for t in taus_best], law_focus, float(res.seconds),
                            float(planned.t_start), expected, sim)


def simulated_fits(cv: Curves, best: Candidate, taus: np.ndarray, noise: float, seeds: int,
                   tq: float) -> dict[str, Any]:
    """The Fisher prediction checked: ``seeds`` noisy Maxwell curves at the design's times,
    at the tau of the grid where the predicted interval is widest, each fitted as ``fit
    kinetics`` fits (solver.fit.kinetics, tau and scale free): the spread of log tau, the
    fits' own 95 % half-width (median) and how often their intervals cover the truth."""
    from solver.fit.kinetics import KineticsData, fit_kinetics

    sds = [tau_sd(cv.maxwell, best.times_s, t, noise) for t in taus]
    tau = float(taus[int(np.argmax(sds))])
    rng = np.random.default_rng(39)
    y0 = best.dry_radius_um * cv.maxwell(best.times_s / tau)
    logs, halves, cover = [], [], 0
    for _ in range(seeds):
        y = y0 * (1.0 + noise * rng.standard_normal(y0.size))
        r = fit_kinetics(KineticsData(best.times_s, y, "radius"), lambda beta: cv.maxwell,
                         size_rel_sigma=noise)
        t_fit, iv = r.parameters["tau"], r.intervals["tau"]
        logs.append(math.log(t_fit / tau))
        if iv:
            halves.append(0.5 * math.log(iv[1] / iv[0]))
            cover += int(iv[0] <= tau <= iv[1])
    return {"seeds": seeds, "tau_s": tau, "fisher_sd_log_tau": max(sds),
            "fisher_half_width": tq * max(sds),
            "simulated_sd_log_tau": float(np.std(logs)),
            "simulated_bias_log_tau": float(np.mean(logs)),
            "median_fit_half_width": float(np.median(halves)) if halves else None,
            "coverage": cover / seeds,
            "method": "simulated fits over noise seeds (the Maxwell curve at the widest "
                      "tau of the grid), each fitted as fit kinetics fits"}


__all__ = ["ASSUMPTIONS", "ExperimentAsk", "ExperimentDesign", "design_experiment",
           "greedy_times", "jump_curves", "separation", "tau_sd"]
