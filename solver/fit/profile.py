"""Profile-likelihood intervals of a swelling fit (our own, not lmfit's conf_interval).

For a parameter theta_j the profile is chi2_p(v) = min over the other parameters of the fit's
chi-square with theta_j = v; the 95% interval is where chi2_p(v) - chi2_min <= Delta s^2,
Delta = 3.841 (chi-square, 1 dof) and s^2 the residual variance (1 with the noise declared
absolute, else chi2_min / (n - p), the same scaling as the linearised intervals).  Each
profile point is a warm-started ``least_squares`` polish of the remaining parameters; the
edges are bracketed by steps of the linearised standard deviation and found by the secant
method on sqrt(chi2_p - chi2_min) (linear in v for a quadratic profile).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy import stats
from scipy.optimize import least_squares

from .equilibrium import INTERNAL, PARAMS, SwellingData, _residual_fn

DELTA_95 = float(stats.chi2.ppf(0.95, 1))


def profile_interval(data: SwellingData, report: dict[str, Any], name: str = "scale",
                     max_steps: int = 6, max_nfev: int = 60) -> dict[str, Any]:
    """The 95% profile-likelihood interval of one reported parameter of a swelling fit
    (``FitResult.to_dict()`` of ``solver.fit.fit_equilibrium``).  Omega and scale are
    profiled in log form (their internal coordinates); a0/a1 through chi at T_ref."""
    internal = report["internal"]
    q = np.array(internal["values"], dtype=float)
    t_ref = float(internal["t_ref"])
    free_names = list(internal["free"])
    j = PARAMS.index(name)
    if name in ("a0", "a1"):
        raise ValueError("profile omega, b0, b1 or scale (a0, a1 are fitted as chi at T_ref)")
    if INTERNAL[j] not in free_names:
        return {"parameter": name, "method": "profile", "interval": None, "note": "fixed"}
    w = report["weighting"]
    sigma_t, rel = float(w["sigma_t_K"]), float(w["size_rel_sigma"])
    objective = report.get("objective", "orthogonal")
    free = np.array([INTERNAL.index(k) for k in free_names if k != INTERNAL[j]], dtype=int)
    sigma_y = rel * data.size
    root_w = np.sqrt(data.weight) if data.weight is not None else np.ones(len(data))
    n, p = len(data), len(free_names)
    cov = np.array(internal["covariance"], dtype=float)
    sd = math.sqrt(max(cov[j, j], 0.0))
    if not (0.0 < sd < 1e3):
        return {"parameter": name, "method": "profile", "interval": None,
                "note": "not identifiable (linearised variance unbounded)"}

    def chi2_at(v: float, start: np.ndarray) -> tuple[float, np.ndarray]:
        qq = q.copy()
        qq[j] = v
        fun = _residual_fn(data, t_ref, free, qq, sigma_t, sigma_y, root_w, objective)
        r = least_squares(fun, start, method="trf", x_scale="jac", max_nfev=max_nfev,
                          xtol=1e-8, ftol=1e-8)
        return float(r.fun @ r.fun), r.x

    chi_min, _ = chi2_at(q[j], q[free])
    s2 = 1.0 if w.get("absolute_sigma") else chi_min / max(n - p, 1)
    target = DELTA_95 * s2
    ends: list[float | None] = []
    evals = 0
    for sign in (-1.0, 1.0):
        start = q[free].copy()
        prev_v, prev_g = q[j], 0.0
        found = None
        step = sd
        for _ in range(max_steps):
            v = prev_v + sign * step
            c, start = chi2_at(v, start)
            evals += 1
            g = math.sqrt(max(c - chi_min, 0.0) / target)
            if g >= 1.0:  # bracketed: secant on g(v) = 1
                found = prev_v + (1.0 - prev_g) / (g - prev_g) * (v - prev_v)
                break
            prev_v, prev_g = v, g
            step *= 1.6
        ends.append(found)
    lo, hi = ends
    conv = (lambda x: math.exp(x)) if INTERNAL[j].startswith("log_") else (lambda x: x)
    return {"parameter": name, "method": "profile likelihood (own implementation: refit "
            "of the other parameters at each value, Delta chi2 = 3.84 s^2)",
            "interval": [None if lo is None else conv(lo), None if hi is None else conv(hi)],
            "delta_chi2": target, "evaluations": evals,
            "note": "an open end (null) is beyond "
                    f"{sum(1.6 ** k for k in range(max_steps)):.0f} linearised sd: the data "
                    "do not bound it on that side"}
