"""Fit the timescale tau (hence the permeability scale k0) to a shrinking curve after a jump.

After a jump T_start -> T_end the dimensionless radius a(t/tau) is fixed by the gel and the
permeability law (eq. timescale: one dimensionless run serves every tau), so a measured size
y(t) = scale a(t/tau)^m (m = 1 for a radius or diameter, 3 for a volume ratio) has two
parameters, tau and the size scale, and optionally the exponent beta of
k = phi/(1-phi)^beta (eq. Permeability) when the model depends on it.  ``model(beta)``
returns the curve a(t) for one beta (the caller supplies the front model or the full solver).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from ..errors import ParameterError
from ..gel import BETA_RANGE
from .data import SizeSeries, checked_series
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

RadiusCurve = Callable[[np.ndarray], np.ndarray]
RadiusModel = Callable[[float | None], RadiusCurve]


@dataclass(frozen=True)
class KineticsData(SizeSeries):
    """Sizes after a jump at time 0: ``time`` (s, or any unit: tau comes out in it), ``size``
    (``kind``: radius, diameter, volume_ratio) and optional relative weights."""

    time: np.ndarray
    size: np.ndarray
    kind: str = "radius"
    weight: np.ndarray | None = None

    def __post_init__(self) -> None:
        t, y, w = checked_series(self.time, self.size, self.kind, self.weight, "time_s",
                                 "time")
        if np.any(t < 0.0):
            raise ParameterError("time_s", float(t.min()), "times >= 0 (from the jump)")
        object.__setattr__(self, "time", t)
        object.__setattr__(self, "size", y)
        object.__setattr__(self, "weight", w)


def _half_time(t: np.ndarray, y: np.ndarray) -> float | None:
    """First time y falls half-way from its first to its last value (linear interpolation)."""
    order = np.argsort(t)
    t, y = t[order], y[order]
    mid = 0.5 * (y[0] + y[-1])
    below = np.nonzero(y <= mid)[0]
    if below.size == 0 or below[0] == 0:
        return None
    i = int(below[0])
    return float(t[i - 1] + (y[i - 1] - mid) / (y[i - 1] - y[i]) * (t[i] - t[i - 1]))


def fit_kinetics(data: KineticsData, model: RadiusModel, *, fit_beta: bool = False,
                 beta: float | None = None, size_rel_sigma: float = 0.01,
                 scale: float | None = None, absolute_sigma: bool = False,
                 max_nfev: int = 200) -> FitResult:
    """Fit tau (and the size scale, and beta with ``fit_beta``) to a shrinking curve.

    Residuals are relative size errors (y_i - scale a(t_i/tau)^m) / (size_rel_sigma y_i).
    ``beta`` is the fixed exponent (None: the gel's own law) or the start of its fit;
    ``scale`` fixes the size scale (the dry size in the data's unit) instead of fitting it.
    """
    rel = float(size_rel_sigma)
    if not (math.isfinite(rel) and rel > 0):
        raise ParameterError("size_rel_sigma", size_rel_sigma, "a finite number > 0")
    names = ["tau"] + ([] if scale is not None else ["scale"]) + (["beta"] if fit_beta else [])
    n, p = len(data), len(names)
    if n <= p:
        raise ParameterError("data", f"{n} points", f"at least {p + 1} points (more than the "
                             f"{p} fitted parameters {', '.join(names)})")
    if fit_beta:
        beta = 2.0 if beta is None else float(beta)
        if not (BETA_RANGE[0] < beta < BETA_RANGE[1]):
            raise ParameterError("beta", beta, "0 < beta < 10")
    m = data.power
    t, y = data.time, data.size
    sig = rel * y
    root_w = np.sqrt(data.weight) if data.weight is not None else np.ones(n)
    curve0 = model(beta)
    grid = np.geomspace(1e-6, 1e3, 4000)
    a_grid = curve0(grid)
    a0, a_end = float(curve0(np.zeros(1))[0]), float(a_grid[-1])
    if not (np.nanmax(y) / np.nanmin(y)) ** (1.0 / m) > 1.0 + 0.2 * (a0 / a_end - 1.0):
        raise ParameterError("data", f"sizes {y.min():.4g}-{y.max():.4g}",
                             "a shrinking curve: sizes falling by a sizeable part of the "
                             f"model's change (radius {a0:.4g} -> {a_end:.4g} dry radii)")
    s0 = scale if scale is not None else float(y[np.argmin(t)]) / a0**m
    th_data = _half_time(t, y)
    th_model = _half_time(grid, a_grid**m)
    tau0 = (th_data / th_model) if th_data and th_model else float(np.median(t[t > 0]) / 0.1)

    def unpack(x: np.ndarray) -> tuple[float, float, float | None]:
        tau = math.exp(x[0])
        sc = math.exp(x[1]) if scale is None else float(scale)
        b = float(x[-1]) if fit_beta else beta
        return tau, sc, b

    def fun(x: np.ndarray) -> np.ndarray:
        tau, sc, b = unpack(x)
        a = model(b)(t / tau)
        r = root_w * (sc * a**m - y) / sig
        return np.where(np.isfinite(r), r, 1e6)

    lb = [math.log(tau0) - 12.0] + ([] if scale is not None else [math.log(s0) - 3.0])
    ub = [math.log(tau0) + 12.0] + ([] if scale is not None else [math.log(s0) + 3.0])
    x_start = [math.log(tau0)] + ([] if scale is not None else [math.log(s0)])
    if fit_beta:
        lb.append(BETA_RANGE[0] + 1e-3)
        ub.append(BETA_RANGE[1] - 1e-3)
        x_start.append(beta)
    best, nfev = None, 0
    for shift in (0.0, math.log(3.0), -math.log(3.0)):
        x0 = np.array(x_start, dtype=float)
        x0[0] += shift
        res = least_squares(fun, x0, bounds=(lb, ub), x_scale="jac", method="trf",
                            max_nfev=max_nfev, xtol=1e-10, ftol=1e-10,
                            diff_step=1e-6 if not fit_beta else 1e-4)
        nfev += int(res.nfev)
        if best is None or res.cost < best.cost:
            best = res
    res = best
    assert res is not None
    return _report(data, names, res, unpack, scale, beta, fit_beta, nfev, absolute_sigma, rel,
                   model)


def _report(data: KineticsData, names: list[str], res, unpack, scale: float | None,
            beta: float | None, fit_beta: bool, nfev: int, absolute_sigma: bool, rel: float,
            model: RadiusModel) -> FitResult:
    n, p = len(data), len(names)
    cov_x, chi2 = covariance_from_jacobian(res.jac, res.fun, p, absolute_sigma)
    tau, sc, b = unpack(res.x)
    vals = {"tau": tau, "scale": sc, "beta": b}
    tq = t_quantile(n - p)
    sd_x = np.sqrt(np.clip(np.diag(cov_x), 0.0, None))
    jac_rep = np.diag([vals[k] if k in ("tau", "scale") else 1.0 for k in names])
    cov = jac_rep @ cov_x @ jac_rep.T
    params, intervals, stderr, warns = {}, {}, {}, []
    for i, k in enumerate(names):
        v = float(res.x[i])
        if k in ("tau", "scale"):
            iv = [math.exp(min(v - tq * sd_x[i], 700.0)), math.exp(min(v + tq * sd_x[i], 700.0))]
        else:
            iv = [v - tq * sd_x[i], v + tq * sd_x[i]]
        params[k] = float(vals[k])
        intervals[k] = [float(iv[0]), float(iv[1])] if np.all(np.isfinite(iv)) else None
        stderr[k] = finite_or_none(math.sqrt(max(cov[i, i], 0.0)))
        half = 0.5 * (iv[1] - iv[0])
        if not math.isfinite(half) or half > RELATIVE_WARN * abs(vals[k]):
            warns.append(f"{k} is not identifiable from this data: its {CONFIDENCE:.0%} "
                         f"interval is [{iv[0]:.4g}, {iv[1]:.4g}] around {vals[k]:.5g}")
    corr = correlation(cov_x)
    warns += correlation_warnings(names, corr)
    fixed = {}
    if scale is not None:
        fixed["scale"] = float(scale)
    if not fit_beta and beta is not None:
        fixed["beta"] = float(beta)
    success = bool(res.success) and res.status > 0
    msg = str(res.message)
    if not success:
        warns.insert(0, f"the fit did not converge ({msg}); the best point found is reported")
    fitted = sc * model(b)(data.time / tau) ** data.power
    rel_res = data.size / fitted - 1.0
    rms = float(np.sqrt(np.mean(rel_res**2)))
    return FitResult(
        names=names, parameters=params, intervals=intervals, stderr=stderr,
        covariance=cov.tolist(), correlation=corr.tolist(), fixed=fixed, success=success,
        status=int(res.status), message=msg, nfev=nfev, n_points=n, rms_residual=rms,
        chi2_reduced=chi2, warnings=warns,
        extra={"rms_residual_relative": rms, "residuals_relative": rel_res.tolist(),
               "fitted_size": fitted.tolist(), "beta": b, "size_kind": data.kind,
               "weighting": {"size_rel_sigma": rel, "absolute_sigma": absolute_sigma}})
