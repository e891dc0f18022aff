"""One fit result (scipy ``OptimizeResult``-like): estimates, 95% intervals, covariance.

Intervals come from the linearised covariance s^2 (J^T J)^-1 of the weighted least-squares
problem (s^2 the residual variance, unless the noise is declared absolute), with the
Student-t quantile on n - p degrees of freedom.  A parameter fitted in log form (omega,
scale, tau, ...) gets the interval exp(q +- t sigma_q), which keeps it positive.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import stats

from ..presenters import html_or_none, presenter

CONFIDENCE = 0.95
CORRELATION_WARN = 0.995  # |r| above this: the two parameters are not separately identifiable
RELATIVE_WARN = 1.0  # 95% half-width above 100% of the value: not identifiable


@dataclass
class FitResult:
    """A least-squares fit: ``parameters``, ``intervals`` (95%), ``stderr``, ``covariance``
    and ``correlation`` (of the reported parameters, named by ``names``), ``warnings``,
    ``success``/``status``/``message``/``nfev`` as in ``scipy.optimize.OptimizeResult``,
    and ``extra`` for model-specific results (transition temperatures, tau, ...)."""

    names: list[str]
    parameters: dict[str, float]
    intervals: dict[str, list[float] | None]
    stderr: dict[str, float | None]
    covariance: list[list[float]]
    correlation: list[list[float]]
    fixed: dict[str, float]
    success: bool
    status: int
    message: str
    nfev: int
    n_points: int
    rms_residual: float
    chi2_reduced: float
    warnings: list[str] = field(default_factory=list)
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def x(self) -> np.ndarray:
        """The fitted values in ``names`` order (as OptimizeResult.x)."""
        return np.array([self.parameters[n] for n in self.names])

    def interval(self, name: str) -> tuple[float, float] | None:
        """The 95% interval of one parameter (None for a fixed one)."""
        iv = self.intervals.get(name)
        return None if iv is None else (float(iv[0]), float(iv[1]))

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready data."""
        return {"names": list(self.names), "parameters": dict(self.parameters),
                "intervals": dict(self.intervals), "stderr": dict(self.stderr),
                "covariance": self.covariance, "correlation": self.correlation,
                "fixed": dict(self.fixed), "success": self.success, "status": self.status,
                "message": self.message, "nfev": self.nfev, "n_points": self.n_points,
                "rms_residual": self.rms_residual, "chi2_reduced": self.chi2_reduced,
                "confidence": CONFIDENCE, "warnings": list(self.warnings), **self.extra}

    def to_xarray(self, request: Any = None) -> Any:
        """This fit as an xarray Dataset (:func:`dosing.export.fit_dataset`)."""
        return presenter("fit_dataset")(self, request)

    def to_dataframe(self) -> Any:
        """One row per parameter: estimate, 95% interval, stderr, unit (pandas)."""
        return presenter("fit_frame")(self)

    def _repr_html_(self) -> str | None:
        return html_or_none("fit_html", self)


def t_quantile(dof: int, confidence: float = CONFIDENCE) -> float:
    """Two-sided Student-t quantile for ``dof`` degrees of freedom."""
    return float(stats.t.ppf(0.5 + confidence / 2.0, max(int(dof), 1)))


def covariance_from_jacobian(jac: np.ndarray, residual: np.ndarray, n_params: int,
                             absolute_sigma: bool = False) -> tuple[np.ndarray, float]:
    """(covariance, reduced chi^2) of a weighted least-squares fit at its optimum.

    The pseudo-inverse (SVD, singular values below eps * largest dropped) keeps a
    rank-deficient Jacobian finite: the dropped directions get an infinite variance.
    """
    n = residual.size
    dof = max(n - n_params, 1)
    chi2 = float(residual @ residual) / dof
    _, s, vt = np.linalg.svd(jac, full_matrices=False)
    tol = np.finfo(float).eps * max(jac.shape) * (s[0] if s.size else 0.0)
    keep = s > tol
    cov = (vt[keep].T / s[keep] ** 2) @ vt[keep]
    if not np.all(keep):
        lost = vt[~keep]
        cov = cov + 1e300 * (lost.T @ lost)  # unidentifiable directions
    return (cov if absolute_sigma else cov * chi2), chi2


def correlation(cov: np.ndarray) -> np.ndarray:
    """The correlation matrix of a covariance (zero variance gives zero correlation)."""
    sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    with np.errstate(divide="ignore", invalid="ignore"):
        r = cov / np.outer(sd, sd)
    r = np.where(np.isfinite(r), r, 0.0)
    np.fill_diagonal(r, 1.0)
    return np.clip(r, -1.0, 1.0)


def correlation_warnings(names: Sequence[str], corr: np.ndarray,
                         threshold: float = CORRELATION_WARN, what: str = "") -> list[str]:
    """Warnings for pairs with |r| > threshold (``what`` names the parametrisation): one per
    pair when there are few, else one naming the least determined combination."""
    pairs = [(names[i], names[j], float(corr[i, j])) for i in range(len(names))
             for j in range(i + 1, len(names)) if abs(corr[i, j]) > threshold]
    if len(pairs) <= 3:
        return [f"{a} and {b} are strongly correlated (r = {r:+.4f}{what}): this data pins "
                "down a combination of them, not each one; consider fixing one"
                for a, b, r in pairs]
    w, v = np.linalg.eigh(corr)
    weak = v[:, 0]
    order = np.argsort(-np.abs(weak))
    combo = " ".join(f"{weak[i]:+.2f} {names[i]}" for i in order if abs(weak[i]) > 0.1)
    first = [names[i].removeprefix("log_") for i in order[:2]]
    return [f"{len(pairs)} parameter pairs are strongly correlated (|r| > {threshold}{what}): "
            f"the data do not determine the combination {combo} (standardised; correlation "
            f"eigenvalue {w[0]:.1e}); consider fixing {' or '.join(first)}"]


def finite_or_none(x: float) -> float | None:
    """x if finite, else None (strict JSON; an unbounded interval end)."""
    return float(x) if math.isfinite(x) else None
