"""The empirical release models of a pharmaceutics lab, fitted to a release profile.

One registry, :data:`MODELS` (name -> :class:`EmpiricalModel`: formula, parameters with
units, the model function, whether it takes a lag time, the window it is fitted on),
after DDSolver (Zhang et al. 2010, AAPS J 12:263) and Costa & Sousa Lobo 2001 (Eur J Pharm
Sci 13:123).  F is the cumulative release in percent of the load, t the time in the
profile's unit (the parameters' units say it), s = max(t - tlag, 0) with a lag:

* zero-order        F = k0 s
* first-order       F = 100 (1 - exp(-k1 s))
* Higuchi           F = kH s^(1/2)
* Korsmeyer-Peppas  F = kKP s^n, on the points up to 60 % released (Korsmeyer et al. 1983;
  Ritger & Peppas 1987: for a sphere n <= 0.43 Fickian, 0.43 < n < 0.85 anomalous, n >= 0.85
  case II transport)
* Hixson-Crowell    F = 100 (1 - (1 - kHC s)^3)
* Weibull           F = 100 (1 - exp(-((t - Ti) / Td)^b)) (Td: time to 63.2 %)
* Peppas-Sahlin     F = k1 t^m + k2 t^(2m), m = 0.43 for a sphere (Peppas & Sahlin 1989),
  on the points up to 60 %

Fitted by bounded least squares (scipy's trust-region reflective ``least_squares``; the
covariance from the Jacobian, ``solver.fit.result``) on the mean profile, weighted by 1/SD
of the units when replicates are given (relative weights: the covariance is scaled by the
reduced chi-square).  Not lmfit: importing it imports matplotlib and pandas (3.6 s here),
which ``dosing`` must not.  Per model: parameters, 95 % intervals (linearised, Student t),
R^2 adjusted, AIC = n ln(WSSR/n) + 2p, MSC = ln(SS_tot/WSSR) - 2p/n (the MicroMath model
selection criterion), residuals.  ``best`` is the lowest AIC among the models fitted on the
same points as the whole curve (a model on its 60 % window is ranked only against the
others there).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from solver.errors import ParameterError

from .profiles import Profile

INF = math.inf
KP_WINDOW = 60.0  # percent: Korsmeyer-Peppas and Peppas-Sahlin are fitted up to it
SPHERE_N = (0.43, 0.85)  # Ritger & Peppas 1987, sphere: Fickian <= 0.43, case II >= 0.85
CONFIDENCE = 0.95


@dataclass(frozen=True)
class Param:
    """A model parameter: its literature name, unit ('{t}' is the time unit), bounds."""

    name: str
    unit: str
    meaning: str
    lower: float = 0.0
    upper: float = INF


@dataclass(frozen=True)
class EmpiricalModel:
    """One empirical release model (module doc)."""

    name: str
    title: str
    formula: str
    params: tuple[Param, ...]
    function: Callable[..., np.ndarray]
    start: Callable[[np.ndarray, np.ndarray], dict[str, float]]
    lag: str | None = "tlag"  # the lag (or location) parameter's name, None: no lag
    window: float | None = None  # percent released it is fitted up to (None: all)
    fixed: tuple[tuple[str, float], ...] = ()
    reference: str = ""


def _s(t: np.ndarray, lag: float) -> np.ndarray:
    return np.maximum(t - lag, 0.0)


def zero_order(t: np.ndarray, k0: float, tlag: float = 0.0) -> np.ndarray:
    """F = k0 (t - tlag)."""
    return k0 * _s(t, tlag)


def first_order(t: np.ndarray, k1: float, tlag: float = 0.0) -> np.ndarray:
    """F = 100 (1 - exp(-k1 (t - tlag)))."""
    return 100.0 * -np.expm1(-k1 * _s(t, tlag))


def higuchi(t: np.ndarray, kH: float, tlag: float = 0.0) -> np.ndarray:
    """F = kH (t - tlag)^(1/2) (Higuchi 1963)."""
    return kH * np.sqrt(_s(t, tlag))


def korsmeyer_peppas(t: np.ndarray, kKP: float, n: float,
                     tlag: float = 0.0) -> np.ndarray:
    """F = kKP (t - tlag)^n (Korsmeyer et al. 1983)."""
    return kKP * _s(t, tlag) ** n


def hixson_crowell(t: np.ndarray, kHC: float, tlag: float = 0.0) -> np.ndarray:
    """F = 100 (1 - (1 - kHC (t - tlag))^3) (Hixson & Crowell 1931), 100 once dissolved."""
    return 100.0 * (1.0 - (1.0 - np.minimum(kHC * _s(t, tlag), 1.0)) ** 3)


def weibull(t: np.ndarray, Td: float, b: float, Ti: float = 0.0) -> np.ndarray:
    """F = 100 (1 - exp(-((t - Ti) / Td)^b)) (Langenbucher 1972)."""
    return 100.0 * -np.expm1(-((_s(t, Ti) / Td) ** b))


def peppas_sahlin(t: np.ndarray, k1: float, k2: float, m: float = SPHERE_N[0]) -> np.ndarray:
    """F = k1 t^m + k2 t^(2m) (Peppas & Sahlin 1989)."""
    tm = np.maximum(t, 0.0) ** m
    return k1 * tm + k2 * tm * tm


# ------------------------------------------------------------------ starting values
def _slope(x: np.ndarray, y: np.ndarray) -> float:
    """Least squares through the origin."""
    d = float(np.dot(x, x))
    return float(np.dot(x, y)) / d if d > 0 else 1.0


def _t_at(t: np.ndarray, f: np.ndarray, level: float) -> float:
    """The time the profile first reaches ``level`` % (or an extrapolation)."""
    above = np.nonzero(f >= level)[0]
    if above.size and above[0] > 0:
        i = above[0]
        return float(np.interp(level, [f[i - 1], f[i]], [t[i - 1], t[i]]))
    if above.size:
        return float(t[above[0]])
    pos = t > 0
    k = _slope(t[pos], f[pos]) if pos.any() else 1.0
    return level / max(k, 1e-12)


def _loglog(t: np.ndarray, f: np.ndarray) -> tuple[float, float]:
    ok = (t > 0) & (f > 0)
    if ok.sum() < 2:
        return 0.5, max(float(f.max()), 1.0) / max(float(t.max()), 1e-12) ** 0.5
    n, c = np.polyfit(np.log(t[ok]), np.log(f[ok]), 1)
    return float(np.clip(n, 0.05, 1.5)), float(math.exp(c))


def _weibull_start(t: np.ndarray, f: np.ndarray) -> dict[str, float]:
    ok = (t > 0) & (f > 0.5) & (f < 99.5)
    if ok.sum() >= 2:
        b, c = np.polyfit(np.log(t[ok]), np.log(-np.log1p(-f[ok] / 100.0)), 1)
        if b > 0.05:
            return {"Td": float(math.exp(-c / b)), "b": float(min(b, 5.0))}
    return {"Td": _t_at(t, f, 63.2), "b": 1.0}


def _ps_start(t: np.ndarray, f: np.ndarray) -> dict[str, float]:
    tm = np.maximum(t, 0.0) ** SPHERE_N[0]
    a = np.column_stack([tm, tm * tm])
    k, *_ = np.linalg.lstsq(a, f, rcond=None)
    return {"k1": float(k[0]), "k2": float(k[1])}


def _hc_start(t: np.ndarray, f: np.ndarray) -> dict[str, float]:
    g = 1.0 - np.cbrt(np.clip(1.0 - f / 100.0, 0.0, 1.0))
    return {"kHC": max(_slope(t, g), 1e-12)}


def _first_start(t: np.ndarray, f: np.ndarray) -> dict[str, float]:
    return {"k1": 1.0 / max(_t_at(t, f, 63.2), 1e-12)}


def _kp_start(t: np.ndarray, f: np.ndarray) -> dict[str, float]:
    n, k = _loglog(t, f)
    return {"kKP": k, "n": n}


LAG = Param("tlag", "{t}", "lag time")
MODELS: dict[str, EmpiricalModel] = {m.name: m for m in (
    EmpiricalModel("zero_order", "zero-order", "F = k0 (t - tlag)",
                   (Param("k0", "%/{t}", "zero-order release rate"),), zero_order,
                   lambda t, f: {"k0": _slope(t, f)}, reference="Costa & Sousa Lobo 2001"),
    EmpiricalModel("first_order", "first-order", "F = 100 (1 - exp(-k1 (t - tlag)))",
                   (Param("k1", "1/{t}", "first-order rate constant"),), first_order,
                   _first_start, reference="Gibaldi & Feldman 1967"),
    EmpiricalModel("higuchi", "Higuchi", "F = kH (t - tlag)^(1/2)",
                   (Param("kH", "%/{t}^0.5", "Higuchi release constant"),), higuchi,
                   lambda t, f: {"kH": _slope(np.sqrt(t), f)}, reference="Higuchi 1963"),
    EmpiricalModel("korsmeyer_peppas", "Korsmeyer-Peppas", "F = kKP (t - tlag)^n",
                   (Param("kKP", "%/{t}^n", "release constant"),
                    Param("n", "1", "release exponent", 0.01, 2.0)), korsmeyer_peppas,
                   _kp_start, window=KP_WINDOW,
                   reference="Korsmeyer et al. 1983; Ritger & Peppas 1987"),
    EmpiricalModel("hixson_crowell", "Hixson-Crowell",
                   "F = 100 (1 - (1 - kHC (t - tlag))^3)",
                   (Param("kHC", "1/{t}", "Hixson-Crowell rate constant (cube root law)"),),
                   hixson_crowell, _hc_start, reference="Hixson & Crowell 1931"),
    EmpiricalModel("weibull", "Weibull", "F = 100 (1 - exp(-((t - Ti) / Td)^b))",
                   (Param("Td", "{t}", "time to 63.2 % released", 1e-12),
                    Param("b", "1", "shape parameter", 0.05, 5.0)), weibull,
                   _weibull_start, lag="Ti", reference="Langenbucher 1972"),
    EmpiricalModel("peppas_sahlin", "Peppas-Sahlin", "F = k1 t^m + k2 t^(2m), m = 0.43",
                   (Param("k1", "%/{t}^m", "Fickian (diffusion) constant", -INF),
                    Param("k2", "%/{t}^(2m)", "relaxation (case II) constant", -INF)),
                   peppas_sahlin, _ps_start, lag=None, window=KP_WINDOW,
                   fixed=(("m", SPHERE_N[0]),), reference="Peppas & Sahlin 1989"),
)}


def kp_mechanism(n: float, interval: list[float] | None = None) -> dict[str, Any]:
    """The release mechanism a Korsmeyer-Peppas exponent indicates for a sphere (Ritger &
    Peppas 1987: 0.43 Fickian, 0.85 case II); a bound inside n's 95 % interval counts as
    reached (n = 0.44 +- 0.02 is Fickian)."""
    lo, hi = SPHERE_N
    iv = interval if interval is not None else [n, n]
    if n <= lo or iv[0] <= lo:
        words = "Fickian diffusion"
    elif n >= hi or iv[1] >= hi:
        words = "case II transport (relaxation-controlled)" + (
            "; super case II (n above 0.85)" if iv[0] > hi else "")
    else:
        words = "anomalous (non-Fickian) transport: diffusion and swelling/relaxation"
    out: dict[str, Any] = {"geometry": "sphere", "bounds": [lo, hi], "mechanism": words,
                           "reference": "Ritger & Peppas 1987, J Control Release 5:23"}
    if iv[0] <= lo and iv[1] >= hi:
        out["note"] = (f"the 95 % interval of n ({iv[0]:.3g}-{iv[1]:.3g}) spans both bounds: "
                       "the data do not tell the mechanisms apart")
    elif iv[0] < lo < iv[1] or iv[0] < hi < iv[1]:
        out["note"] = (f"the 95 % interval of n ({iv[0]:.3g}-{iv[1]:.3g}) contains a bound")
    return out


@dataclass
class ModelFit:
    """One model's fit (module doc)."""

    model: str
    title: str
    formula: str
    parameters: dict[str, float]
    units: dict[str, str]
    stderr: dict[str, float | None]
    intervals: dict[str, list[float] | None]
    fixed: dict[str, float]
    n_points: int
    n_parameters: int
    window_percent: float | None
    time: list[float]
    observed: list[float]
    fitted: list[float]
    residuals: list[float]
    wssr: float
    r2: float
    r2_adjusted: float
    aic: float
    bic: float
    msc: float
    success: bool
    reference: str
    warnings: list[str] = field(default_factory=list)
    interpretation: dict[str, Any] | None = None
    delta_aic: float | None = None

    def to_dict(self) -> dict[str, Any]:
        """Plain data (JSON-ready)."""
        return asdict(self)


@dataclass
class EmpiricalResult:
    """Every model's fit to one profile, and the best by AIC."""

    fits: dict[str, ModelFit]
    errors: dict[str, str]
    best: str | None
    ranked: list[str]
    time_unit: str
    weighted: bool
    profile: Profile
    lag: bool = False
    notes: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """The report: per model parameters (with units), intervals, r2_adjusted, aic, msc,
        residuals; ``best`` by AIC."""
        return {"best": self.best, "ranked_by_aic": list(self.ranked),
                "models": {k: v.to_dict() for k, v in self.fits.items()},
                "errors": dict(self.errors), "time_unit": self.time_unit,
                "weighted": self.weighted, "lag": self.lag, "confidence": CONFIDENCE,
                "criteria": {
                    "aic": "n ln(WSSR/n) + 2p (lower is better; compared on the same points)",
                    "msc": "ln(sum w^2 (y - ybar)^2 / WSSR) - 2p/n (MicroMath; higher is "
                           "better)",
                    "r2_adjusted": "1 - (1 - R^2)(n - 1)/(n - p)"},
                "profile": self.profile.to_dict(), "notes": list(self.notes)}

    def report(self, curve_points: int = 200) -> dict[str, Any]:
        """``to_dict`` with each model's curve on ``curve_points`` times from 0 to the last
        (``curve_time``, ``curve``: for plots and the page)."""
        rep = self.to_dict()
        tt = np.linspace(0.0, float(self.profile.times.max()), curve_points)
        for name, fit in self.fits.items():
            rep["models"][name]["curve_time"] = tt.tolist()
            rep["models"][name]["curve"] = curve(fit, tt).tolist()
        return rep

    def to_dataframe(self) -> Any:
        """One row per model and parameter (pandas, imported here)."""
        import pandas as pd

        rows = []
        for f in self.fits.values():
            for name, value in f.parameters.items():
                iv = f.intervals.get(name)
                rows.append({"model": f.model, "parameter": name, "value": value,
                             "unit": f.units.get(name, ""), "stderr": f.stderr.get(name),
                             "lower": None if iv is None else iv[0],
                             "upper": None if iv is None else iv[1],
                             "fixed": name in f.fixed, "aic": f.aic, "msc": f.msc,
                             "r2_adjusted": f.r2_adjusted, "n_points": f.n_points,
                             "best": f.model == self.best})
        return pd.DataFrame(rows)


def weights_of(p: Profile) -> np.ndarray | None:
    """1/SD of the units at each time (SD floored at a tenth of the median SD and 0.01 %),
    or None for a single unit."""
    sd = p.sd
    if sd is None:
        return None
    pos = sd[sd > 0]
    floor = max(0.1 * float(np.median(pos)) if pos.size else 0.0, 0.01)
    return 1.0 / np.maximum(sd, floor)


def fit_empirical(profile: Profile, models: list[str] | tuple[str, ...] | None = None, *,
                  lag: bool = False, kp_window: float = KP_WINDOW) -> EmpiricalResult:
    """Fit the zoo (or ``models``) to ``profile``'s mean; ``lag``: fit a lag time where the
    model has one; ``kp_window``: percent released Korsmeyer-Peppas and Peppas-Sahlin are
    fitted up to (60, the literature's; above it the exponent's meaning is lost: flagged)."""
    names = list(MODELS) if models is None else list(models)
    if not names:
        raise ParameterError("models", "[]", f"one or more of {', '.join(MODELS)}")
    for n in names:
        if n not in MODELS:
            raise ParameterError("models", n, ", ".join(MODELS))
    if not (0.0 < kp_window <= 105.0) or not math.isfinite(kp_window):
        raise ParameterError("kp_window", kp_window, "0 < percent <= 105 (60: the "
                             "literature's window)")
    t, f = profile.times, profile.mean
    w = weights_of(profile)
    fits: dict[str, ModelFit] = {}
    errors: dict[str, str] = {}
    for name in dict.fromkeys(names):
        model = MODELS[name]
        window = None if model.window is None else kp_window
        keep = np.ones(t.size, bool) if window is None else f <= window + 1e-9
        try:
            fits[name] = _fit_one(model, t[keep], f[keep], None if w is None else w[keep],
                                  lag, window, profile.time_unit)
        except ParameterError as exc:
            errors[name] = str(exc)
        except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
            errors[name] = f"the least squares failed on this curve ({exc})"
    best, ranked = _rank(fits, t.size)
    notes = [f"times in {profile.time_unit}; F in % of the load"]
    if w is not None:
        notes.append(f"weighted by 1/SD of {profile.n_units} units (relative weights)")
    return EmpiricalResult(fits, errors, best, ranked, profile.time_unit, w is not None,
                           profile, lag, notes)


def _rank(fits: dict[str, ModelFit], n_all: int) -> tuple[str | None, list[str]]:
    """Rank by AIC the models fitted on the whole curve (else those on the most points)."""
    if not fits:
        return None, []
    most = max(f.n_points for f in fits.values())
    group = [k for k, f in fits.items() if f.n_points == most and f.window_percent is None]
    if not group:
        group = [k for k, f in fits.items() if f.n_points == most]
    ranked = sorted(group, key=lambda k: fits[k].aic)
    best = ranked[0]
    for k in ranked:
        fits[k].delta_aic = fits[k].aic - fits[best].aic
    return best, ranked


def _lag_starts(t: np.ndarray, f: np.ndarray) -> list[float]:
    """Lag starts: none, and midway from the last point below 1 % to the first above it."""
    above = np.nonzero(f > 1.0)[0]
    if not above.size or above[0] == 0:
        return [0.0]
    i = above[0]
    return [0.0, 0.5 * float(t[i - 1] + t[i])]


def _start_vector(model: EmpiricalModel, t: np.ndarray, f: np.ndarray, lag0: float,
                  names: list[str], bounds: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """Starts from the curve shifted by ``lag0``, inside the bounds."""
    start = {**model.start(np.maximum(t - lag0, 0.0), f), **({model.lag: lag0}
                                                           if model.lag else {})}
    x0 = np.array([float(start[n]) for n in names])
    x0[~np.isfinite(x0)] = 1.0
    lo, hi = bounds
    span = np.where(np.isfinite(hi - lo), hi - lo, np.maximum(np.abs(x0), 1.0))
    return np.clip(x0, lo + 1e-9 * span, hi - 1e-9 * span)


def _fit_one(model: EmpiricalModel, t: np.ndarray, f: np.ndarray, w: np.ndarray | None,
             lag: bool, window: float | None, time_unit: str) -> ModelFit:
    from scipy.optimize import least_squares

    from solver.fit.result import covariance_from_jacobian, t_quantile

    use_lag = lag and model.lag is not None
    names = [par.name for par in model.params] + ([model.lag] if use_lag else [])
    p_free = len(names)
    if t.size < p_free + 1:
        where = f" at or below {window:g} % released" if window is not None else ""
        raise ParameterError(model.name, f"{t.size} points{where}",
                             f"at least {p_free + 1} points for {p_free} parameters")
    fixed = {k: float(v) for k, v in model.fixed}
    lag_max = max(float(t[np.argmax(f > 1.0)] if np.any(f > 1.0) else t[-1]), 1e-12)
    lo = np.array([par.lower for par in model.params] + ([0.0] if use_lag else []))
    hi = np.array([par.upper for par in model.params] + ([lag_max] if use_lag else []))
    ww = np.ones_like(f) if w is None else w

    def predict(x: np.ndarray, tt: np.ndarray = t) -> np.ndarray:
        return model.function(tt, **dict(zip(names, x, strict=True)), **fixed)

    def fun(x: np.ndarray) -> np.ndarray:
        with np.errstate(all="ignore"):
            r = ww * (predict(x) - f)
        return np.where(np.isfinite(r), r, 1e10)

    res = None
    for lag0 in _lag_starts(t, f) if use_lag else [0.0]:
        x0 = _start_vector(model, t, f, lag0, names, (lo, hi))
        trial = least_squares(fun, x0, bounds=(lo, hi), method="trf", x_scale="jac",
                              xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=2000 * p_free)
        if res is None or trial.cost < res.cost:
            res = trial
    assert res is not None
    cov, _ = covariance_from_jacobian(res.jac, res.fun, p_free)
    with np.errstate(all="ignore"):
        fitted = predict(res.x)
    if not np.all(np.isfinite(fitted)) or not np.all(np.isfinite(res.x)):
        raise ValueError("the model is not finite at the fitted parameters")
    resid = f - fitted
    wssr = max(float(np.sum((ww * resid) ** 2)), 1e-300)
    ybar = float(np.sum(ww**2 * f) / np.sum(ww**2))
    sst = float(np.sum((ww * (f - ybar)) ** 2))
    n, p = t.size, p_free
    r2 = 1.0 - wssr / sst if sst > 0 else 1.0
    r2_adj = 1.0 - (1.0 - r2) * (n - 1) / (n - p) if n > p else r2
    aic = n * math.log(wssr / n) + 2 * p
    bic = n * math.log(wssr / n) + p * math.log(n)
    msc = (math.log(sst / wssr) if sst > 0 else INF) - 2.0 * p / n
    tq = t_quantile(n - p, CONFIDENCE)
    units = {par.name: par.unit.format(t=time_unit) for par in model.params}
    if model.lag is not None:
        units[model.lag] = time_unit
    values, errs, ivs = {}, {}, {}
    warns = []
    for k, name in enumerate(names):
        v = float(res.x[k])
        values[name] = v
        se = math.sqrt(cov[k, k]) if cov[k, k] >= 0 else math.nan
        ok = math.isfinite(se) and se < 1e100
        errs[name] = se if ok else None
        ivs[name] = [v - tq * se, v + tq * se] if ok else None
        at_top = hi[k] < INF and abs(v - hi[k]) <= 1e-6 * max(1.0, abs(hi[k]))
        at_bottom = lo[k] > 0.0 and abs(v - lo[k]) <= 1e-6 * lo[k]
        if at_top or at_bottom:
            warns.append(f"{name} at its bound [{lo[k]:g}, {hi[k]:g}]")
    if not res.success:
        warns.append(f"the fit did not converge ({res.message})")
    if not any(e is not None for e in errs.values()):
        warns.append("no intervals: the covariance could not be estimated")
    interp = None
    if model.name == "korsmeyer_peppas":
        interp = kp_mechanism(values["n"], ivs["n"])
        if window is not None and window > KP_WINDOW:
            warns.append(f"fitted beyond 60 % released (up to {window:g} %): the exponent's "
                         "mechanism bounds hold only for the first 60 % (Ritger & Peppas "
                         "1987)")
            interp["beyond_60_percent"] = True
    if model.name == "peppas_sahlin" and window is not None and window > KP_WINDOW:
        warns.append(f"fitted beyond 60 % released (up to {window:g} %)")
    return ModelFit(model.name, model.title, model.formula, values, units, errs, ivs, fixed,
                    n, p, window, t.tolist(), f.tolist(), fitted.tolist(), resid.tolist(),
                    wssr, r2, r2_adj, aic, bic, msc, bool(res.success), model.reference,
                    warns, interp)


def curve(fit: ModelFit, times: np.ndarray) -> np.ndarray:
    """A fitted model's release (percent) at ``times`` (in the fit's time unit)."""
    m = MODELS[fit.model]
    return np.asarray(m.function(np.asarray(times, float), **fit.parameters, **fit.fixed))
