"""Design maps of a batch: its dose time over the CV of its sizes and the dose, the largest
CV a dose tolerates, and a sweep's batch columns (the front model's batch,
``dosing.population.front``)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy.optimize import brentq

from solver.errors import ParameterError

from ..population.front import batch_answer, batch_sizes
from ..request import DoseRequest
from ..runs.scenario import SolverSettings
from ..units import timescale


def with_cv(req: DoseRequest, cv: float, fraction: float | None = None) -> DoseRequest:
    """The request with its batch's CV (and dose) replaced: the same law and number-weighted
    mean dry radius (a number-weighted spread of dry radii)."""
    d = req.size_distribution.to_dict() if req.size_distribution is not None else {}
    kind = d.get("kind", "lognormal")
    if kind == "table":
        raise ParameterError("size_distribution.kind", "table", "a lognormal or normal "
                             "(a measured table has no CV to vary)")
    spec = {"kind": kind, "cv": cv, "mean_um": batch_sizes(req).mean_um
            if req.size_distribution is not None else req.bead_dry_radius_um}
    return DoseRequest(req.gel, req.t_start, req.t_end,
                       dose_fraction=req.fraction if fraction is None else fraction,
                       constants=req.constants, branch=req.branch,
                       settings=SolverSettings(**req.settings.request_dict()),
                       size_distribution=spec)


def design_map(req: DoseRequest, cvs: Any, fractions: Any) -> dict[str, Any]:
    """A design map with the CV as an axis: the batch's dose time (in the reference bead's
    tau and in seconds) and its delay against the mean bead, for every CV x dose."""
    cv = np.asarray(cvs, dtype=float)
    fr = np.asarray(fractions, dtype=float)
    time = np.empty((fr.size, cv.size))
    delay = np.empty_like(time)
    for i, f in enumerate(fr):
        for j, c in enumerate(cv):
            b = batch_answer(with_cv(req, float(c), float(f)))
            time[i, j], delay[i, j] = b.time, b.delay
    tau = timescale(req.bead_dry_radius_um, req.t_end, req.constants).seconds
    return {"cv": cv.tolist(), "dose_fraction": fr.tolist(), "time": time.tolist(),
            "seconds": (time * tau).tolist(), "delay": delay.tolist()}


def tolerated_cv(req: DoseRequest, tolerance: float, cv_max: float = 1.0) -> float:
    """The largest CV whose batch dose comes at most ``tolerance`` (relative) after the mean
    bead's (the delay grows with the CV): how much spread the dose tolerates."""
    tol = float(tolerance)
    if not (math.isfinite(tol) and tol > 0.0):
        raise ParameterError("tolerance", tolerance, "a finite number > 0")

    def excess(c: float) -> float:
        return batch_answer(with_cv(req, c)).delay - tol

    if excess(cv_max) <= 0.0:
        return cv_max
    return float(brentq(excess, 0.0, cv_max, xtol=1e-6))


def check_cvs(values: Any) -> tuple[float, ...]:
    """A sweep's CV axis: a non-empty list of CVs 0-2 (ParameterError names the entry)."""
    from ..population.sizes import _cv

    out = []
    for i, v in enumerate(values):
        try:
            out.append(_cv("cv", v))
        except ParameterError as exc:
            raise ParameterError(f"size_cvs[{i}]", v, exc.valid) from None
    if not out:
        raise ParameterError("size_cvs", list(values), "a non-empty list of CVs 0-2")
    return tuple(out)


def batch_row(req: DoseRequest, cv: float) -> dict[str, Any]:
    """A sweep row's batch columns for the single-bead request ``req`` as the mean of a
    number-weighted lognormal of CV ``cv`` (CV 0: the bead's own answer exactly)."""
    b = batch_answer(with_cv(req, cv))
    return {"time": b.time, "seconds": b.seconds, "size_cv": cv, "batch_delay": b.delay,
            "fraction_delivered": b.fraction_delivered}
