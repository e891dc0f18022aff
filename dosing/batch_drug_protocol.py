"""A batch's drug dose under a heating protocol (issue 26 x issue 24): the time from the
protocol's start at which the batch has released the dose of its load.

A protocol in seconds is a different dimensionless program for every size (tau_k ~ R_k^2,
eq. timescale), so no one trajectory serves the batch: each size node k runs the full
solver's mechanics of the protocol at its own bead size and interfacial length
(``fit_release_protocol.protocol_mechanics``, the single bead's drug dose under a protocol
uses the same, module ``drug_protocol``), and the coupled solve of ``batch_medium`` takes
one mechanics per node (the node its own band), each in its own time t / rho_k,
rho_k = (R_k / R_ref)^2, so the beads share one medium (or a perfect sink).  The nodes are
the few-node rule of the batch schedules (``batch_schedule.rule``: Gauss-Hermite in ln R
for a lognormal, 3 nodes, checked on 5; a table's sizes exactly), the load shares their
volume weights.  Every node's run reaches ``horizon`` seconds from the protocol's start,
grown x ``drug_protocol.GROWTH`` until the batch reaches its dose.

The answer's parts: numerical (the coupled solve's steps halved; the mechanics' n / 2 check
is the single bead's, not run per node), the quadrature error (3 against 5 nodes), and, as
for a single bead under a protocol, the interfacial length not measured and the model form
of holding D0 at the hottest temperature not run per node (the single bead's drug dose
under the protocol states both).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from solver.errors import ParameterError

from .batch_medium import MediumRelease, coupled_release
from .batch_schedule import ladder, rule
from .batch_truth import size_settings
from .drug import drug_settings
from .drug_protocol import GROWTH, MAX_HORIZON, check_protocol
from .fit_release_protocol import protocol_mechanics
from .size_distribution import DrySizes
from .units import timescale

POINTS = 400  # outputs of the coupled solve, even in ln t from START x the horizon
START = 1e-5
FIRST_HORIZON = 0.05  # tau_ref past the protocol's end: the first runs' horizon


def _solve(req: Any, sizes: DrySizes, n: int, horizon_s: float, v0: float | None,
           sub: int) -> tuple[MediumRelease, np.ndarray, list[Any]]:
    """The coupled release of the n-node rule's classes, each on its own mechanics run of
    the protocol to ``horizon_s`` seconds; (release, the nodes' radii, their runs)."""
    from solver.solute import node_volumes

    prot = check_protocol(req)
    ref = sizes.mean_um
    settings = drug_settings(req.settings)
    r, v, _ = rule(sizes, n)
    runs = [protocol_mechanics(req.gel, prot, float(x), horizon_s, req.constants,
                               size_settings(settings, req.constants, ref, float(x)))
            for x in r]
    tau_ref = timescale(ref, req.t_end, req.constants).seconds
    t_max = horizon_s / tau_ref
    times = np.concatenate(([0.0], np.geomspace(t_max * START, t_max, POINTS)))
    mr = coupled_release([np.asarray(m.result.t, dtype=float) for m in runs],
                         [node_volumes(m.result) for m in runs], req.solute,
                         (r / ref) ** 2, v, v0, times, sub=sub, points=0,
                         band=np.arange(len(r)))
    return mr, r, runs


def protocol_batch_time(req: Any, sizes: DrySizes, v0: float | None) -> dict[str, Any]:
    """The batch's dose time (tau_ref) under ``req.heating`` and its checks (module doc)."""
    prot = check_protocol(req)
    tau_ref = timescale(sizes.mean_um, req.t_end, req.constants).seconds
    total = sum(p.duration or 0.0 for p in prot.program(tau_ref)
                if math.isfinite(p.duration or 0.0))
    rungs = ladder(sizes)
    n, fine = rungs[0], (rungs[1] if len(rungs) > 1 else None)
    horizon = total + FIRST_HORIZON
    while True:
        best, radii, runs = _solve(req, sizes, n, horizon * tau_ref, v0, 2)
        try:
            t = best.time_to_release(req.fraction)
            break
        except ValueError:
            if horizon >= total + MAX_HORIZON:
                raise ParameterError(
                    "dose_fraction", req.fraction, f"below {best.released.max():.4f} of the "
                    "batch's load", f"the protocol and {MAX_HORIZON:g} tau at its last "
                    "temperature release at most that (the collapsed shells hold the rest)"
                ) from None
            horizon = min(GROWTH * horizon, total + MAX_HORIZON)
    half, _, _ = _solve(req, sizes, n, horizon * tau_ref, v0, 1)
    t_half = half.time_to_release(req.fraction)
    quad = 0.0
    if fine is not None:
        check, _, _ = _solve(req, sizes, fine, horizon * tau_ref, v0, 2)
        quad = abs(check.time_to_release(req.fraction) / t - 1.0)
    return {"time": t, "release": best, "radii": radii, "runs": runs,
            "numerical": abs(t_half / t - 1.0), "quadrature": quad,
            "nodes": len(radii), "check_nodes": None if fine is None else fine,
            "horizon": horizon, "texts": prot.texts}


def protocol_parts(res: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """The answer's parts under a protocol (module doc), in numbers and words."""
    return {
        "numerical": {"relative": res["numerical"], "text": (
            f"numerical: {res['numerical']:.1e} (the coupled solve's steps halved); the "
            "mechanics' n / 2 check is not run per node (the single bead's drug dose under "
            "the protocol gives it)")},
        "interfacial_length_range": {"relative": None, "text": (
            "interfacial length: not measured under a protocol (each node runs at its own "
            "ell = xi_dry / a_d)")},
        "model_form": {"relative": None, "text": (
            "model form: D0 is held at the protocol's hottest temperature; what that costs "
            "is not run per node (the single bead's drug dose under the protocol bounds "
            "it)")},
    }


__all__ = ["protocol_batch_time", "protocol_parts"]
