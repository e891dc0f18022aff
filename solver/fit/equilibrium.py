"""Fit a gel to an equilibrium swelling curve: Omega, A0, B0, A1, B1 and the size scale.

Eq. EqlEqn is affine in T (module ``solver.equilibrium``): g(lambda; T) = c(lambda) + T d(lambda),
so T(lambda) = -c/d is explicit and the fit is on temperatures given sizes, as in the paper
(sec. Eql, eq. Params_Fitted): residuals in kelvin, no root finding, and folds and both
branches need no special care.  A measured size y (radius or diameter in any unit, or a
volume ratio) gives lambda = (y / scale)^(1/m) with m = 1 or 3.

Noise in both coordinates is weighted by the effective variance
sigma_i^2 = sigma_T^2 + (dT/dlambda sigma_lambda,i)^2 (re-weighted twice at the estimate).

Global search: for fixed (Omega, scale) the algebraic form
T_i (db + 2 b1 x_i) + da + 2 a1 x_i = F(x_i) - G(lambda_i)/Omega (x = lambda^-3, da = A0 - A1,
db = B0 - B1) is linear in the chi coefficients, so a grid over (log Omega, log scale) with a
linear solve at each node gives every start; the best few are polished by
``scipy.optimize.least_squares`` on the kelvin residuals.

Internally chi_k is centred at the data's mean temperature T_ref, C_k = A_k + B_k T_ref, so
the A-B correlation that comes only from T = 0 being far from the data does not hide the
real identifiability problems; warnings are judged in that parametrisation.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from scipy.optimize import least_squares

from ..equilibrium import _parts, folds
from ..errors import ParameterError
from ..gel import T_MAX, T_MIN, Gel
from ..thermo import osmotic_p
from .data import SIZE_POWER, SizeSeries, checked_series
from .result import (
    CONFIDENCE,
    RELATIVE_WARN,
    FitResult,
    correlation,
    correlation_warnings,
    covariance_from_jacobian,
    finite_or_none,
    t_quantile,
)

PARAMS = ("omega", "a0", "b0", "a1", "b1", "scale")
INTERNAL = ("log_omega", "chi0_ref", "b0", "chi1_ref", "b1", "log_scale")
OMEGA_RANGE = (1.0, 1.0e5)
LAMBDA_CAP = 30.0  # largest stretch a fitted scale may imply
BAD = 1.0e4  # residual (in sigmas) of a point where the model has no finite temperature
OBJECTIVES = ("orthogonal", "temperature")
BELOW_DRY_SIGMAS = 2.0  # no point more than this many size-noise widths below the dry size


class _Coeffs(NamedTuple):
    """The gel coefficients ``solver.equilibrium._parts`` reads (no validation)."""

    omega: float
    a0: float
    b0: float
    a1: float
    b1: float


@dataclass(frozen=True)
class SwellingData(SizeSeries):
    """Equilibrium points: temperature (K), size (``kind``: radius, diameter, volume_ratio)
    and optional relative weights."""

    temperature: np.ndarray
    size: np.ndarray
    kind: str = "radius"
    weight: np.ndarray | None = None

    def __post_init__(self) -> None:
        t, y, w = checked_series(self.temperature, self.size, self.kind, self.weight,
                                 "temperature_K", "temperature")
        out = np.nonzero((t < T_MIN) | (t > T_MAX))[0]
        if out.size:
            raise ParameterError("temperature_K", float(t[out[0]]), f"{T_MIN}-{T_MAX} K",
                                 f"row(s) {', '.join(str(i + 1) for i in out[:5])}")
        object.__setattr__(self, "temperature", t)
        object.__setattr__(self, "size", y)
        object.__setattr__(self, "weight", w)


# ---------------------------------------------------------------- the model
def _physical(q: np.ndarray, t_ref: float) -> tuple[_Coeffs, float]:
    """(gel coefficients, scale) from the internal vector (module doc)."""
    lo, c0, b0, c1, b1, ls = q
    return _Coeffs(math.exp(lo), c0 - b0 * t_ref, b0, c1 - b1 * t_ref, b1), math.exp(ls)


def stretch_of(size: np.ndarray, scale: float, power: int) -> np.ndarray:
    """lambda = (size / scale)^(1/m)."""
    return (np.asarray(size, dtype=float) / scale) ** (1.0 / power)


def model_temperature(gel: Gel | _Coeffs, stretch: np.ndarray) -> np.ndarray:
    """T(lambda) = -c/d of eq. EqlEqn (inf where d = 0)."""
    c, d, _, _ = _parts(gel, stretch)
    with np.errstate(divide="ignore", invalid="ignore"):
        return -c / d


def model_slope(gel: Gel | _Coeffs, stretch: np.ndarray) -> np.ndarray:
    """dT/dlambda = -(c' d - c d') / d^2 along the equilibrium curve."""
    c, d, dc, dd = _parts(gel, stretch)
    with np.errstate(divide="ignore", invalid="ignore"):
        return -(dc * d - c * dd) / (d * d)


def _temperature_and_slope(gel: Gel | _Coeffs, stretch: np.ndarray) -> tuple[np.ndarray, ...]:
    """T(lambda) and dT/dlambda from one evaluation of c, d and their derivatives."""
    c, d, dc, dd = _parts(gel, stretch)
    with np.errstate(divide="ignore", invalid="ignore"):
        return -c / d, -(dc * d - c * dd) / (d * d)


def stretch_grid(n: int = 1500) -> np.ndarray:
    """Stretches on which the curve is tabulated before each point's nearest point is refined."""
    return 1.0 + np.geomspace(1e-7, LAMBDA_CAP - 1.0, n)


class Distances(NamedTuple):
    """Each point's nearest point on the fitted curve in noise units (orthogonal distance)."""

    signed: np.ndarray  # signed distance in units of the noise
    stretch: np.ndarray  # lambda of the nearest curve point
    temperature: np.ndarray  # its temperature T(lambda)
    size: np.ndarray  # its size scale lambda^m


def distances(coef: Gel | _Coeffs, scale: float, data: SwellingData, sigma_t: float,
              sigma_y: np.ndarray, grid: np.ndarray) -> Distances:
    """Orthogonal distance of each point (T_i, y_i) to the curve (T(lambda), scale lambda^m):
    the nearest tabulated point, refined by Gauss-Newton steps in lambda (module doc)."""
    m = data.power
    t, y = data.temperature, data.size
    tg = model_temperature(coef, grid)
    yg = scale * grid**m
    ok = np.isfinite(tg)
    du = (tg[None, :] - t[:, None]) / sigma_t
    dv = (yg[None, :] - y[:, None]) / sigma_y[:, None]
    dist = np.where(ok[None, :], du * du + dv * dv, np.inf)
    j = np.argmin(dist, axis=1)
    lam = grid[j]
    lo = grid[np.maximum(j - 1, 0)]
    hi = grid[np.minimum(j + 1, grid.size - 1)]
    for _ in range(4):
        tm, dt = _temperature_and_slope(coef, lam)
        ru, rv = (tm - t) / sigma_t, (scale * lam**m - y) / sigma_y
        ju, jv = dt / sigma_t, m * scale * lam ** (m - 1) / sigma_y
        step = (ru * ju + rv * jv) / (ju * ju + jv * jv)
        step = np.where(np.isfinite(step), step, 0.0)
        lam = np.clip(lam - step, lo, hi)
    tm, dt = _temperature_and_slope(coef, lam)
    ru, rv = (tm - t) / sigma_t, (scale * lam**m - y) / sigma_y
    ju, jv = dt / sigma_t, m * scale * lam ** (m - 1) / sigma_y
    d = np.sqrt(ru * ru + rv * rv)
    sign = np.where(jv * ru - ju * rv >= 0.0, 1.0, -1.0)
    return Distances(np.where(np.isfinite(d), sign * d, BAD), lam, tm, lam**m)


# ---------------------------------------------------------------- global search
def _linear_start(data: SwellingData, omega: float, scale: float,
                  t_ref: float) -> np.ndarray | None:
    """The chi coefficients for fixed (Omega, scale) by the algebraic linear fit (module doc),
    as an internal vector, from the points that scale puts above lambda = 1.001; or None."""
    lam = stretch_of(data.size, scale, data.power)
    use = lam > 1.001
    if np.count_nonzero(use) < 5:
        return None
    lam = lam[use]
    x = lam**-3.0
    t = data.temperature[use]
    f = osmotic_p(1.0 - x, 0.0, 0.0) / (x * x)
    g = (lam * lam - 1.0) / lam**3 / (x * x)
    rhs = f - g / omega
    mat = np.column_stack([np.ones_like(x), 2.0 * x, t, 2.0 * t * x])
    w = np.ones_like(x)
    sol = None
    for _ in range(2):  # second pass divides by the model's denominator: ~ kelvin residuals
        sol, *_ = np.linalg.lstsq(mat * w[:, None], rhs * w, rcond=None)
        den = sol[2] + 2.0 * sol[3] * x
        if not np.all(np.isfinite(den)) or np.any(den == 0.0):
            return None
        w = 1.0 / np.abs(den)
    da, a1, db, b1 = sol
    a0, b0 = da + a1, db + b1
    return np.array([math.log(omega), a0 + b0 * t_ref, b0, a1 + b1 * t_ref, b1,
                     math.log(scale)])


def _scale_bounds(data: SwellingData, objective: str = "orthogonal",
                  size_rel_sigma: float = 0.01,
                  below_sigmas: float = BELOW_DRY_SIGMAS) -> tuple[float, float]:
    """(lowest, highest) log scale: the largest point below LAMBDA_CAP; the dry size bounded
    by the data: no point more than ``below_sigmas`` noise widths below it (orthogonal
    objective: y_min >= scale (1 - k sigma_rel)), every point above it (temperature
    objective, where T(lambda <= 1) does not exist)."""
    y = data.size
    if objective == "temperature":
        hi = math.log(float(y.min())) - 1e-9
    else:
        k = below_sigmas * size_rel_sigma
        hi = math.log(float(y.min())) + (-math.log1p(-k) if k < 0.2 else 0.25)
    lo = math.log(float(y.max())) - data.power * math.log(LAMBDA_CAP)
    if not lo < hi:
        raise ParameterError(data.kind, f"max/min = {y.max() / y.min():.4g}",
                             f"a size range below {LAMBDA_CAP ** data.power:.4g}x")
    return lo, hi


def global_starts(data: SwellingData, t_ref: float, sigma_t: float, sigma_y: np.ndarray,
                  n_omega: int = 12, n_scale: int = 20,
                  objective: str = "orthogonal") -> list[tuple[float, np.ndarray]]:
    """Every grid node's linear start as (cost under ``objective``, internal vector), best
    first."""
    lo, _ = _scale_bounds(data)
    ymin = float(data.size.min())
    # the smallest point's stretch (y_min / scale)^(1/m): dense near 1, where dry states sit
    top = max((ymin / math.exp(lo)) ** (1.0 / data.power) - 1.0, 4e-3)
    lam_min = 1.0 + np.geomspace(2e-3, top, n_scale)
    scales = ymin / lam_min**data.power
    grid = stretch_grid(300)
    out = []
    for om in np.geomspace(10.0, 1.0e4, n_omega):
        for s in scales:
            q = _linear_start(data, float(om), float(s), t_ref)
            if q is None:
                continue
            coef, scale = _physical(q, t_ref)
            if objective == "temperature":
                d = np.clip(temperature_residuals(coef, scale, data, sigma_t), -BAD, BAD)
            else:
                d = distances(coef, scale, data, sigma_t, sigma_y, grid).signed
            out.append((float(d @ d), q))
    out.sort(key=lambda p: p[0])
    return out


# ---------------------------------------------------------------- the fit
def temperature_residuals(coef: Gel | _Coeffs, scale: float, data: SwellingData,
                          sigma_t: float) -> np.ndarray:
    """The paper's residual (sec. Eql): (T(lambda_i) - T_i) / sigma_t at the measured
    stretch lambda_i = (y_i / scale)^(1/m); BAD where lambda_i <= 1 (no temperature)."""
    lam = stretch_of(data.size, scale, data.power)
    with np.errstate(invalid="ignore"):
        tm = np.where(lam > 1.0, model_temperature(coef, np.maximum(lam, 1.0 + 1e-12)), np.nan)
    r = (tm - data.temperature) / sigma_t
    return np.where(np.isfinite(r), r, BAD)


def _residual_fn(data: SwellingData, t_ref: float, free: np.ndarray, q_fixed: np.ndarray,
                 sigma_t: float, sigma_y: np.ndarray, root_w: np.ndarray,
                 objective: str = "orthogonal"):
    grid = stretch_grid()

    def fun(p: np.ndarray) -> np.ndarray:
        q = q_fixed.copy()
        q[free] = p
        coef, scale = _physical(q, t_ref)
        if objective == "temperature":
            r = root_w * temperature_residuals(coef, scale, data, sigma_t)
        else:
            r = root_w * distances(coef, scale, data, sigma_t, sigma_y, grid).signed
        return np.where(np.isfinite(r), np.clip(r, -BAD, BAD), BAD)
    return fun


def _fixed_internal(fixed: Mapping[str, float], t_ref: float) -> dict[int, float]:
    """Fixed reported parameters as internal entries (a0 fixed needs b0 fixed too)."""
    unknown = set(fixed) - set(PARAMS)
    if unknown:
        raise ParameterError("fixed", sorted(unknown), "keys among " + ", ".join(PARAMS))
    out: dict[int, float] = {}
    v = {k: float(x) for k, x in fixed.items()}
    for k, x in v.items():
        if not math.isfinite(x):
            raise ParameterError(f"fixed.{k}", x, "a finite number")
    for k in ("omega", "scale"):
        if k in v:
            if v[k] <= 0.0:
                raise ParameterError(f"fixed.{k}", v[k], "a finite number > 0")
            out[0 if k == "omega" else 5] = math.log(v[k])
    for a, b, i in (("a0", "b0", 1), ("a1", "b1", 3)):
        if b in v:
            out[i + 1] = v[b]
        if a in v:
            if b not in v:
                raise ParameterError("fixed", sorted(v), f"{b} fixed too when {a} is fixed "
                                     f"(chi is fitted as chi(T_ref) and a slope)")
            out[i] = v[a] + v[b] * t_ref
    return out


def fit_equilibrium(data: SwellingData, *, sigma_t: float = 0.05, size_rel_sigma: float = 0.01,
                    fixed: Mapping[str, float] | None = None, n_starts: int = 6,
                    absolute_sigma: bool = False, max_nfev: int = 400,
                    objective: str = "orthogonal",
                    below_dry_sigmas: float = BELOW_DRY_SIGMAS,
                    start: Mapping[str, float] | None = None) -> FitResult:
    """Fit eq. EqlEqn to equilibrium swelling data (module doc).

    ``start`` (all six reported parameters): a warm start, one local fit from there in
    place of the global search (e.g. refits of similar data in a coverage study).

    ``objective``: 'orthogonal' (default; errors in both variables, judged by chi-square
    under the stated noise) or 'temperature' (the paper's residual T(lambda_i) - T_i at the
    measured sizes; every point above the dry size).  The dry size (``scale``) is bounded by
    the data: no point more than ``below_dry_sigmas`` size-noise widths below it; or fix it
    (``fixed={"scale": dry size in the data's unit}``).

    Each point's residual is its orthogonal distance to the curve (T(lambda), scale lambda^m)
    in units of the noise, ``sigma_t`` in K and ``size_rel_sigma`` times the size; with
    ``absolute_sigma=False`` (default) only their ratio matters and the covariance is scaled
    by the residual variance.  ``fixed`` holds reported parameters to keep (omega, a0 with
    b0, b0, a1 with b1, b1, scale).  Raises ParameterError for data that cannot determine
    the fit (too few points; all on one side of the transition).
    """
    if objective not in OBJECTIVES:
        raise ParameterError("objective", objective, " or ".join(OBJECTIVES))
    sigma_t = float(sigma_t)
    size_rel_sigma = float(size_rel_sigma)
    if not (math.isfinite(sigma_t) and sigma_t > 0):
        raise ParameterError("sigma_t", sigma_t, "a finite number > 0 (K)")
    if not (math.isfinite(size_rel_sigma) and size_rel_sigma > 0):
        raise ParameterError("size_rel_sigma", size_rel_sigma, "a finite number > 0")
    t_ref = float(np.mean(data.temperature))
    fixed = dict(fixed or {})
    fix = _fixed_internal(fixed, t_ref)
    free = np.array([i for i in range(6) if i not in fix], dtype=int)
    n, p = len(data), free.size
    if n <= p:
        raise ParameterError("data", f"{n} points", f"at least {p + 1} points (more than the "
                             f"{p} fitted parameters {', '.join(PARAMS[i] for i in free)})")
    if np.unique(np.round(data.temperature, 6)).size < min(p, 4):
        raise ParameterError("temperature_K", "too few distinct values",
                             f"at least {min(p, 4)} distinct temperatures")
    root_w = np.sqrt(data.weight) if data.weight is not None else np.ones(n)
    sigma_y = size_rel_sigma * data.size
    lo_s, hi_s = _scale_bounds(data, objective, size_rel_sigma, below_dry_sigmas)
    lb = np.array([math.log(OMEGA_RANGE[0]), -np.inf, -np.inf, -np.inf, -np.inf, lo_s])
    ub = np.array([math.log(OMEGA_RANGE[1]), np.inf, np.inf, np.inf, np.inf, hi_s])
    for i, val in fix.items():
        if i in (0, 5) and not (lb[i] <= val <= ub[i]):
            raise ParameterError(f"fixed.{PARAMS[i]}", math.exp(val),
                                 f"{math.exp(lb[i]):.4g}-{math.exp(ub[i]):.4g}")
    if start is not None:
        if set(start) != set(PARAMS):
            raise ParameterError("start", sorted(start), "all of " + ", ".join(PARAMS))
        warm = _fixed_internal(start, t_ref)
        starts = [(0.0, np.array([warm[i] for i in range(6)]))]
    else:
        starts = [(c, q) for c, q in global_starts(data, t_ref, sigma_t, sigma_y,
                                                   objective=objective)
                  if lo_s <= q[5] <= hi_s]
    if not starts:
        raise ParameterError("data", "no start", "data for which some gel has a finite "
                             "equilibrium temperature at every point")
    chosen: list[np.ndarray] = []
    for _, q in starts:  # the best distinct nodes
        q = q.copy()
        for i, val in fix.items():
            q[i] = val
        if all(np.max(np.abs(q - c) / (np.abs(c) + 1e-3)) > 0.05 for c in chosen):
            chosen.append(q)
        if len(chosen) >= n_starts:
            break
    best = None
    nfev = 0
    for q0 in chosen:
        fun = _residual_fn(data, t_ref, free, q0, sigma_t, sigma_y, root_w, objective)
        x0 = np.clip(q0[free], lb[free] + 1e-12, ub[free] - 1e-12)
        res = least_squares(fun, x0, bounds=(lb[free], ub[free]), x_scale="jac",
                            method="trf", max_nfev=max_nfev, xtol=1e-10, ftol=1e-10)
        nfev += int(res.nfev)
        if best is None or res.cost < best[1].cost:
            q = q0.copy()
            q[free] = res.x
            best = (q, res)
    assert best is not None
    q, res = best
    out = _report(data, q, res, free, t_ref, fixed, nfev, len(chosen), absolute_sigma,
                  sigma_t, size_rel_sigma, objective)
    out.extra["dry_size_bound"] = {
        "upper": math.exp(hi_s), "rule": "every point above the dry size" if objective ==
        "temperature" else f"no point more than {below_dry_sigmas:g} size-noise widths "
        f"({below_dry_sigmas * size_rel_sigma:.1%}) below the dry size",
        "at_bound": bool(5 in free and q[5] >= hi_s - 1e-6)}
    return out


# ---------------------------------------------------------------- the report
def _to_reported(q: np.ndarray, t_ref: float) -> tuple[np.ndarray, np.ndarray]:
    """Reported (omega, a0, b0, a1, b1, scale) and d(reported)/d(internal)."""
    coef, scale = _physical(q, t_ref)
    vals = np.array([coef.omega, coef.a0, coef.b0, coef.a1, coef.b1, scale])
    m = np.zeros((6, 6))
    m[0, 0] = coef.omega
    m[1, 1], m[1, 2] = 1.0, -t_ref
    m[2, 2] = 1.0
    m[3, 3], m[3, 4] = 1.0, -t_ref
    m[4, 4] = 1.0
    m[5, 5] = scale
    return vals, m


def fit_gel(result: FitResult, name: str = "fitted") -> Gel:
    """The fitted gel (constant permeability; set it with ``Gel.with_permeability``)."""
    p = result.parameters
    return Gel(omega=p["omega"], a0=p["a0"], b0=p["b0"], a1=p["a1"], b1=p["b1"], name=name)


def transitions(gel: Gel, stretch_range: tuple[float, float]) -> list[dict[str, float | str]]:
    """The folds of the fitted curve (kind shrink/swell) in the data's stretch range, or,
    without a fold there, the steepest point of lambda(T) (kind ``continuous``)."""
    lo, hi = stretch_range
    out = [{"kind": f.kind, "temperature": f.temperature, "stretch": f.stretch}
           for f in folds(gel) if lo <= f.stretch <= hi]
    if out:
        return out
    lam = np.geomspace(lo, hi, 2001)
    slope = np.abs(model_slope(gel, lam))
    t = model_temperature(gel, lam)
    ok = np.isfinite(slope) & np.isfinite(t)
    if not np.any(ok):
        return []
    i = int(np.argmin(np.where(ok, slope, np.inf)))
    return [{"kind": "continuous", "temperature": float(t[i]), "stretch": float(lam[i])}]


def gel_from_internal(q: np.ndarray, t_ref: float, name: str = "custom") -> Gel:
    """The gel of an internal parameter vector (log omega, chi0(T_ref), b0, chi1(T_ref), b1,
    log scale), as stored in a fit report's ``internal`` block."""
    coef, _ = _physical(np.asarray(q, dtype=float), t_ref)
    return Gel(omega=coef.omega, a0=coef.a0, b0=coef.b0, a1=coef.a1, b1=coef.b1, name=name)


_gel_of = gel_from_internal


def _transition_intervals(q: np.ndarray, cov_q: np.ndarray, t_ref: float,
                          found: list[dict], rng: tuple[float, float],
                          tq: float) -> list[str]:
    """Delta-method intervals of the transition temperatures (central differences)."""
    warns: list[str] = []
    sd = np.sqrt(np.clip(np.diag(cov_q), 0.0, None))
    grads = np.zeros((len(found), q.size))
    for j in range(q.size):
        h = min(0.05 * sd[j], 1e-3 * max(abs(q[j]), 1e-2)) if sd[j] > 0.0 else 0.0
        if h == 0.0:
            continue
        vals = []
        for sgn in (1.0, -1.0):
            qq = q.copy()
            qq[j] += sgn * h
            try:
                tr = transitions(_gel_of(qq, t_ref), (rng[0] * 0.9, rng[1] * 1.1))
            except ParameterError:
                tr = []
            vals.append(tr)
        for k, f in enumerate(found):
            pair = []
            for tr in vals:
                same = [x for x in tr if x["kind"] == f["kind"]]
                pair.append(min(same, key=lambda x: abs(x["temperature"] - f["temperature"]))
                            ["temperature"] if same else math.nan)
            grads[k, j] = (pair[0] - pair[1]) / (2.0 * h)
    for k, f in enumerate(found):
        g = grads[k]
        if not np.all(np.isfinite(g)):
            f["interval"] = None
            f["stderr"] = None
            warns.append(f"the {f['kind']} transition at {f['temperature']:.3f} K disappears "
                         "under small parameter changes: no interval")
            continue
        se = float(math.sqrt(max(g @ cov_q @ g, 0.0)))
        f["stderr"] = finite_or_none(se)
        f["interval"] = [f["temperature"] - tq * se, f["temperature"] + tq * se] \
            if math.isfinite(se) and se < 1e3 else None
    return warns


def _report(data: SwellingData, q: np.ndarray, res,
            free: np.ndarray, t_ref: float, fixed: dict, nfev: int, n_starts: int,
            absolute_sigma: bool, sigma_t: float, size_rel_sigma: float,
            objective: str = "orthogonal") -> FitResult:
    n, p = len(data), free.size
    cov_free, chi2 = covariance_from_jacobian(res.jac, res.fun, p, absolute_sigma)
    cov_q = np.zeros((6, 6))
    cov_q[np.ix_(free, free)] = cov_free
    vals, m = _to_reported(q, t_ref)
    cov = m @ cov_q @ m.T
    tq = t_quantile(n - p)
    sd_q = np.sqrt(np.clip(np.diag(cov_q), 0.0, None))
    sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    params = {k: float(v) for k, v in zip(PARAMS, vals, strict=True)}
    intervals: dict[str, list[float] | None] = {}
    stderr: dict[str, float | None] = {}
    warns: list[str] = []
    for i, k in enumerate(PARAMS):
        if i not in free:
            intervals[k], stderr[k] = None, None
            continue
        if i in (0, 5):  # fitted in log form
            lo, hi = q[i] - tq * sd_q[i], q[i] + tq * sd_q[i]
            iv = [math.exp(min(lo, 700.0)), math.exp(min(hi, 700.0))]
        else:
            iv = [vals[i] - tq * sd[i], vals[i] + tq * sd[i]]
        intervals[k] = [float(iv[0]), float(iv[1])] if np.all(np.isfinite(iv)) else None
        stderr[k] = finite_or_none(sd[i])
        half = 0.5 * (iv[1] - iv[0])
        if not math.isfinite(half) or half > RELATIVE_WARN * abs(vals[i]):
            warns.append(f"{k} is not identifiable from this data: its {CONFIDENCE:.0%} "
                         f"interval is {_fmt(iv)} around {vals[i]:.5g}")
    names_q = [INTERNAL[i] for i in free]
    corr_q = correlation(cov_free)
    warns += correlation_warnings(names_q, corr_q, what=f", with chi centred at "
                                                        f"T_ref = {t_ref:.2f} K")
    coef, scale = _physical(q, t_ref)
    near = distances(coef, scale, data, sigma_t, size_rel_sigma * data.size, stretch_grid())
    lam = near.stretch
    resid = data.temperature - near.temperature
    # the rms residual in noise units, expressed in kelvin: for the orthogonal objective the
    # temperature error that alone would explain the misfit (not a temperature residual)
    rms = float(sigma_t * np.sqrt(np.mean(res.fun**2)))
    judged = judge(data, coef_scale=_physical(q, t_ref), sigma_t=sigma_t,
                   size_rel_sigma=size_rel_sigma, n_free=p)
    size_resid = data.size / (scale * near.size) - 1.0
    rng = (float(lam.min()), float(lam.max()))
    gel = _gel_of(q, t_ref)
    found = transitions(gel, rng)
    warns += _transition_intervals(q, cov_q, t_ref, found, rng, tq)
    _check_sides(found, lam)
    success = bool(res.success) and res.status > 0
    msg = str(res.message)
    if not success:
        warns.insert(0, f"the fit did not converge ({msg}); the best point found is reported")
    return FitResult(
        names=list(PARAMS), parameters=params, intervals=intervals, stderr=stderr,
        covariance=cov.tolist(), correlation=correlation(cov).tolist(), fixed=dict(fixed),
        success=success, status=int(res.status), message=msg, nfev=nfev, n_points=n,
        rms_residual=rms, chi2_reduced=chi2, warnings=warns,
        extra={"objective": objective, **judged, "transitions": found,
               "rms_residual_size": float(np.sqrt(np.mean(size_resid**2))),
               "residuals_K": resid.tolist(), "residuals_size": size_resid.tolist(),
               "stretch": lam.tolist(),
               "model": "eq. EqlEqn, T(lambda) = -c/d; " + (
                   "each point's residual is T(lambda_i) - T_i at its measured size (the "
                   "paper's)" if objective == "temperature" else
                   "each point's residual is its orthogonal distance to the curve in noise "
                   "units, split into a temperature part (K) and a relative size part"),
               "weighting": {"sigma_t_K": sigma_t, "size_rel_sigma": size_rel_sigma,
                             "absolute_sigma": absolute_sigma},
               "n_starts": n_starts,
               "internal": {"names": list(INTERNAL), "values": q.tolist(),
                            "covariance": cov_q.tolist(), "t_ref": t_ref,
                            "correlation": corr_q.tolist(), "free": names_q},
               "size_kind": data.kind})


def judge(data: SwellingData, coef_scale: tuple[_Coeffs, float], sigma_t: float,
          size_rel_sigma: float, n_free: int) -> dict[str, float | int | str | None]:
    """A fitted curve judged under the stated noise, whatever objective fitted it: the
    orthogonal chi-square (errors in both variables) with its p-value, AIC and BIC (known
    noise: AIC = chi2 + 2k, BIC = chi2 + k ln n), the paper's temperature residual over the
    points above the dry size, and how many points lie below the dry size and how far."""
    from scipy import stats

    coef, scale = coef_scale
    n = len(data)
    d = distances(coef, scale, data, sigma_t, size_rel_sigma * data.size, stretch_grid())
    w = data.weight if data.weight is not None else np.ones(n)
    chi2 = float(np.sum(w * d.signed**2))
    dof = max(n - n_free, 1)
    tr = temperature_residuals(coef, scale, data, sigma_t)
    above = tr != BAD
    below = 1.0 - data.size / (scale * 1.0)  # size relative to the dry size (m-th power)
    below = np.where(data.size < scale, below, 0.0)
    return {"chi2": chi2, "dof": dof, "chi2_p_value": float(stats.chi2.sf(chi2, dof)),
            "aic": chi2 + 2.0 * n_free, "bic": chi2 + n_free * math.log(n),
            "rms_orthogonal_K": float(sigma_t * math.sqrt(chi2 / n)),
            "rms_orthogonal_meaning": "sigma_t times the rms orthogonal distance of the "
                                      "points to the curve in noise units (not a "
                                      "temperature residual)",
            "rms_temperature_residual_K": float(sigma_t * np.sqrt(np.mean(tr[above] ** 2)))
            if np.any(above) else None,
            "n_temperature_residual": int(np.sum(above)),
            "points_below_dry": int(np.sum(data.size < scale)),
            "max_below_dry_relative": float(below.max())}


def _check_sides(found: list[dict], lam: np.ndarray) -> None:
    """Refuse data that lie all on one side of the fitted transition."""
    if not found:
        raise ParameterError("data", "no transition", "points on both sides of the volume-phase "
                             "transition (the fitted curve has no fold or steep step over the "
                             "data)")
    top = max(f["stretch"] for f in found)
    bottom = min(f["stretch"] for f in found)
    n_sw, n_sh = int(np.sum(lam >= top)), int(np.sum(lam <= bottom))
    if n_sw < 2 or n_sh < 2:
        side = "swollen" if n_sh < 2 else "shrunken"
        t = found[0]["temperature"]
        raise ParameterError(
            "data", f"{len(lam)} points", "points on both sides of the volume-phase "
            "transition (at least 2 swollen and 2 shrunken)",
            f"all but {min(n_sw, n_sh)} are on the {side} side of the fitted transition near "
            f"{t:.2f} K: measure across it")


def _fmt(iv: list[float]) -> str:
    return f"[{iv[0]:.4g}, {iv[1]:.4g}]"


def curve_band(result: FitResult, n: int = 300) -> dict[str, list[float]]:
    """The fitted curve and its pointwise 95% band in temperature, on a size grid spanning
    the data: ``size``, ``temperature``, ``lower``, ``upper`` (delta method)."""
    internal = result.extra["internal"]
    q = np.array(internal["values"])
    cov_q = np.array(internal["covariance"])
    t_ref = internal["t_ref"]
    power = SIZE_POWER[result.extra["size_kind"]]
    lam = np.array(result.extra["stretch"])
    lam_grid = np.geomspace(max(lam.min(), 1.0 + 1e-6), lam.max(), n)
    coef, scale = _physical(q, t_ref)
    size = scale * lam_grid**power
    base = model_temperature(coef, lam_grid)
    sd = np.sqrt(np.clip(np.diag(cov_q), 0.0, None))
    grads = np.zeros((n, 6))
    for j in range(6):
        if not (0.0 < sd[j] < 1e6):
            continue
        h = 0.05 * sd[j]
        qq = q.copy()
        qq[j] += h
        c2, s2 = _physical(qq, t_ref)
        # the same measured size: the stretch moves with the scale
        grads[:, j] = (model_temperature(c2, stretch_of(size, s2, power)) - base) / h
    var = np.einsum("ij,jk,ik->i", grads, cov_q, grads)
    half = t_quantile(result.n_points - len(internal["free"])) * np.sqrt(np.clip(var, 0, None))
    return {"size": size.tolist(), "temperature": base.tolist(),
            "lower": (base - half).tolist(), "upper": (base + half).tolist()}
