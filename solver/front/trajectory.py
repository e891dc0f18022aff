"""front_trajectory: the step-function front model from a start to the centre (sec. FrontSoln)."""

from __future__ import annotations

import numpy as np

from ..equilibrium import Branch
from ..errors import ParameterError, SolverError, require_finite_positive
from ..gel import Gel, as_gel
from .evolve import FrontCurve, leading_curve
from .levels import FrontLevels, front_applicability, front_levels
from .result import FrontResult
from .start import StartState, resolve_start

MAX_SAMPLES = 1_000_000
CORRECTION_NOT_KEPT = (
    "the O(1/Omega) shell-porosity correction was measured against the full solver and not "
    "kept: it moves dose times by +1.8% (ANB) and +0.5% (HHT), below the full solver's own "
    "30-60% grid dependence in the front regime, and in opposite directions relative to it")


def _stop(curve: FrontCurve, until: float | None,
          target_radius: float | None) -> tuple[float, float, str]:
    """(t_stop, R_f at stop, reason) for the centre, a target radius or a final time."""
    t_stop, x_stop, reason = curve.t_centre, 0.0, "centre"
    if target_radius is not None:
        lo, hi = float(curve.radius(0.0)), float(curve.radius(curve.x_start))
        a = float(target_radius) if np.isscalar(target_radius) else float("nan")
        if not (np.isfinite(a) and lo <= a <= hi):
            raise ParameterError("target_radius", target_radius,
                                 f"{lo:.6g} <= a <= {hi:.6g} (the radii the front reaches "
                                 "between the start and the centre)")
        x_stop = float(np.clip(curve.front(a), 0.0, curve.x_start))
        t_stop, reason = float(curve.time_of_front(x_stop)), "target_radius"
    if until is not None:
        u = require_finite_positive("until", until)
        if u <= curve.t_start:
            raise ParameterError("until", until, f"until > t0 = {curve.t_start:g}")
        if u < t_stop:
            t_stop, reason = u, "until"
            x_stop = float(curve.front_at(np.array([u]))[0])
    return t_stop, x_stop, reason


def _sample_times(t0: float, t_stop: float, every: float | None, n: int) -> np.ndarray:
    if every is None:
        if not (isinstance(n, (int, np.integer)) and 2 <= n <= MAX_SAMPLES):
            raise ParameterError("n", n, f"an integer 2 <= n <= {MAX_SAMPLES}")
        return np.linspace(t0, t_stop, int(n))
    dt = require_finite_positive("every", every)
    count = int(np.floor((t_stop - t0) / dt))
    if count > MAX_SAMPLES:
        raise ParameterError("every", every, f"every >= {(t_stop - t0) / MAX_SAMPLES:.3g}")
    t = t0 + dt * np.arange(count + 1)
    return t if t[-1] >= t_stop * (1 - 1e-12) else np.append(t, t_stop)


def front_trajectory(gel: Gel, t_start: float, t_end: float, *, branch: Branch | None = None,
                     start: tuple[float, float, float] | None = None,
                     until: float | None = None, target_radius: float | None = None,
                     correction: bool = False, conservative: bool = True,
                     every: float | None = None, n: int = 201) -> FrontResult:
    """The front model after a jump T_start -> T_end (eqs. SphereEvolve_Dimless, FrontEvolve).

    ``start=None`` starts from the initial equilibrium alone (a shell of zero thickness at
    t = 0); ``start=(t0, a, R_f)`` from a measured state (``conservative=False`` keeps the
    measured R_f as the paper did, else R_f follows from solid conservation).  The run stops
    when the front reaches the centre, at ``target_radius`` or at time ``until``, whichever
    comes first; samples are ``n`` equal steps or every ``every``.  ``correction=True`` is
    refused (ParameterError): the next-order correction was tried and did not help (see
    CORRECTION_NOT_KEPT).  NotApplicableError off the front regime (:func:`front_applicability`).
    """
    gel = as_gel(gel)
    if correction:
        raise ParameterError("correction", correction, "False", CORRECTION_NOT_KEPT)
    levels = front_levels(gel, t_start, t_end, branch)
    st = resolve_start(levels, start, conservative)
    curve = leading_curve(levels, st.t0, st.front, st.solid)
    return sample_curve(levels, st, curve, until, target_radius, every, n, "front-leading",
                        {"applicability": front_applicability(gel, t_start, t_end, branch)[1],
                         "t_end_temperature": levels.t_end,
                         "chebyshev_degree": curve.rate.degree(),
                         "conservative": conservative})


def sample_curve(levels: FrontLevels, st: StartState, curve: FrontCurve, until: float | None,
                 target_radius: float | None, every: float | None, n: int, model: str,
                 extra: dict) -> FrontResult:
    """Sample a front curve from its start to its stop into a :class:`FrontResult`
    (``extra``: the model's own diagnostics, with its ``applicability`` in words)."""
    t_stop, x_stop, reason = _stop(curve, until, target_radius)
    t = _sample_times(st.t0, t_stop, every, n)
    x = curve.front_at(t)
    x[0], x[-1] = st.front, x_stop
    a = curve.radius(x)
    with np.errstate(divide="ignore"):
        amp = curve.flux(x)
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(a))):
        raise SolverError(f"{model} model produced a non-finite state",
                          {"t_stop": t_stop, "front_stop": x_stop})
    diag = {"behaviour": levels.behaviour, "stop": reason,
            "t_centre": curve.t_centre, "radius_centre": float(curve.radius(0.0)),
            "solid": st.solid, "a0": levels.a0, **extra,
            **st.diagnostics}
    return FrontResult(t=t, radius=a, front=x, flux=amp, phi_minus=levels.phi_minus,
                       phi_plus=levels.phi_plus, model=model, start=st.label,
                       diagnostics=diag, curve=curve, t_stop=t_stop, front_stop=x_stop)
