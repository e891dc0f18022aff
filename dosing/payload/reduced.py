"""Drug doses from the reduced drug model, where its measured error holds (issue 23).

The model (``solver.front.solute``): the full solver's drug physics on the sharp front model's
bead, a few milliseconds a dose; :data:`MEASURED` keeps its largest |error| (both gels) per
measured (law, D0 / D_gel, dose).  Where it answers (:func:`applies`, :func:`stated_error`)
and why: docs/drug_reduced.md secs. 4, 5 and 7."""

from __future__ import annotations

import bisect
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from solver.front.solute import CELLS, HORIZON, front_release, time_to_release

from ..answers import Verdict

STATED_LIMIT = 0.05  # the reduced model answers where its measured error is at most this
Y_MAX = 1.0  # the free-volume law's Y of the measured drugs
# dry bead radii it answers for (um): the table's 50 um within a factor 2 either way, so the
# truth's ell = xi_dry / a_d (8e-5 at 50 um) stays within a factor 2 of the measured one
BEAD_UM = (25.0, 100.0)
FIRST_REACH = 1.25  # the first run's end, over the fluid's time for the same fraction
STAGE_CENTRE = 2.0  # the next run's end, over the front's time to the centre
# the reduced model's own error (unsieved, sieved drugs): 48 cells against 384, the largest
# over ANB and HHT (docs/drug_reduced.md sec. 3)
NUMERICAL = (0.01, 0.043)
TWIN_RTOL = 1e-2  # the squeezed split only (not the dose time): a coarser twin
SIEVED = 0.1  # r_s / xi_dry above which the first run is skipped (a sieved drug lags the fluid)
DOSES = (0.1, 0.3, 0.5, 0.7, 0.9)
MODEL = "front-solute"
MODEL_NAME = ("the reduced drug model (the drug's advection, hindered diffusion, sieving and "
              "partition on the sharp-interface front model's bead; docs/drug_reduced.md)")
Row = tuple[tuple[float, float], tuple[float, ...], tuple[tuple[float | None, ...], ...]]
# law -> measured drugs: ((r_s / xi_dry, r_s / r_f), D0 / D_gel of the measured rows, the
# largest |relative error| of the dose time over ANB and HHT at each of DOSES; None: a dose
# not reached), written to dosing/data/drug_reduced_errors.json by
# `python -m benchmarks.drug_reduced --emit` from benchmarks/drug_reduced_table.json
MEASURED: dict[str, list[Row]] = json.loads(
    (Path(__file__).parents[1] / "data" / "drug_reduced_errors.json").read_text())


def _bracket(values: tuple[float, ...], x: float) -> tuple[int, ...] | None:
    """Indices of the measured values around x: one where x is a measured value (to 1e-9),
    else the two on either side (None outside their range)."""
    tol = 1e-9
    if not values or not values[0] * (1 - tol) <= x <= values[-1] * (1 + tol):
        return None
    for i, v in enumerate(values):
        if abs(x - v) <= tol * v:
            return (i,)
    j = bisect.bisect_right(values, x) - 1
    return (j, j + 1)


def _corners(row: Row, d: float, dose: float) -> float | None:
    """The largest error at the corners of the measured cell around (d, dose)."""
    _, ds, errs = row
    jd, jf = _bracket(ds, d), _bracket(DOSES, dose)
    if jd is None or jf is None:
        return None
    out = 0.0
    for i in set(jd):
        for k in set(jf):
            e = errs[i][k]
            if e is None or not math.isfinite(e):
                return None
            out = max(out, e)
    return out


def _near(a: float, b: float) -> bool:
    return abs(a - b) <= 1e-9 * max(abs(a), abs(b), 1e-300)


def stated_error(solute: Any, dose: float,
                 measured: dict[str, list[Row]] | None = None) -> float | None:
    """The reduced model's stated error for ``solute`` (a ``solver.solute.Solute``) at ``dose`` of
    the load, or None where it does not answer: the largest error at the corners of its measured
    cell in D0 / D_gel, dose and size (r_s / xi_dry, r_s / r_f; below the smallest measured size
    the unhindered drug).  ``measured``: the error table (default :data:`MEASURED`)."""
    table = MEASURED if measured is None else measured
    h = solute.hindrance
    d = solute.diffusivity
    if d <= 0.0 or solute.release_volume is not None or not table.get("none"):
        return None
    rows = [table["none"][0]]
    if h.law != "none":
        if h.law == "free-volume" and h.y > Y_MAX:
            return None
        mesh = h.mesh_ratio if (h.convective or h.law != "ogston") else 0.0
        fiber = h.fiber_ratio
        own = table.get(h.law, [])
        above = [r for r in own if r[0][0] >= mesh * (1 - 1e-9)
                 and r[0][1] >= fiber * (1 - 1e-9)]
        if not above:
            return None
        up = min(above, key=lambda r: sum(r[0]))
        below = [r for r in own if r[0][0] <= mesh * (1 + 1e-9)
                 and r[0][1] <= fiber * (1 + 1e-9)]
        if _near(up[0][0], mesh) and _near(up[0][1], fiber):
            rows = [up]
        else:
            rows = [up, max(below, key=lambda r: sum(r[0])) if below else rows[0]]
    errs = [_corners(r, d, dose) for r in rows]
    if any(e is None for e in errs):
        return None
    err = max(errs)
    return err if err <= STATED_LIMIT else None


def applies(req: Any, settings: Any) -> Verdict:
    """Whether the reduced model answers drug dose ``req`` (a ``DrugDoseRequest``) on the
    truth ``settings``, why, and its stated error where it does (module doc)."""
    from ..model_choice import choose_model

    dry = req.bead_dry_radius_um
    if req.lead > 0.0:
        return Verdict(False, "a wait at T_start before the heating was not measured")
    if not settings.direct:
        return Verdict(False, "its error was measured against the direct truth only")
    if dry is None or not BEAD_UM[0] <= dry <= BEAD_UM[1]:
        return Verdict(False, f"its error was measured for dry beads of {BEAD_UM[0]:g}-"
                       f"{BEAD_UM[1]:g} um (the bead's size sets the truth's ell)")
    own = req.constants.interfacial_lengths(dry)[0]  # the bead's own ell: the measured truth
    if abs(settings.interfacial_length / own - 1.0) > 1e-9:
        return Verdict(False, "the truth is not at the bead's own interfacial length")
    err = stated_error(req.solute, req.fraction)
    if err is None:
        return Verdict(False, f"the drug and dose are outside the measured table, or its "
                       f"error there is above {STATED_LIMIT:.0%}")
    model, _ = choose_model(req.gel, req.t_start, req.t_end, req.branch)
    if model != "front":
        return Verdict(False, f"the jump's fluid answer is the {model} model's, not the "
                       "front model's the reduced drug model rides on")
    return Verdict(True, f"inside the measured table, its error there {err:.1%}", err)


def reduced_release(req: Any, fraction: float | None = None) -> tuple[Any, float, float]:
    """The reduced model's release (``solver.solute.ReleaseResult``) for ``req``'s jump, the dose's
    (``fraction``, default ``req.fraction``) time on it and the squeezed part by then (the D0 = 0
    twin's).  Run in stages that stop early (docs/drug_reduced.md sec. 7); ValueError if the dose
    is never reached."""
    from solver.solute import Solute

    from ..model_choice import front_run

    fr = front_run(req.gel, req.t_start, req.t_end, req.branch, True)
    dose = req.fraction if fraction is None else fraction
    sol = req.solute
    h = sol.hindrance
    sieved = h.convective and h.mesh_ratio > 0.0
    first = FIRST_REACH * float(fr.time_to_fraction(dose))
    stages = [first, max(STAGE_CENTRE * fr.curve.t_centre, first), HORIZON]
    if sieved and h.mesh_ratio > SIEVED:  # retained behind the fluid: skip the first
        stages.pop(0)
    for horizon in stages:
        rel = front_release(fr, sol, horizon=horizon, twin="none" if sieved else "exact")
        try:
            t = time_to_release(rel, dose)
        except ValueError:
            if horizon == HORIZON:
                raise
            continue
        if not sieved:
            return rel, t, rel.squeezed_at(t)
        twin = front_release(fr, Solute(0.0, h, sol.partition), horizon=t, rtol=TWIN_RTOL)
        return rel, t, float(twin.released_fraction[-1])
    raise AssertionError("unreachable")


@dataclass(frozen=True)
class ReducedDose:
    """The reduced drug model's dose (:func:`reduced_dose`): its time (tau), the squeezed
    share, the fluid fraction expelled and the bead's radius by then, the heating's Peclet
    number, the solute's mass balance, the three-part uncertainty and the answer's note;
    ``dosing.payload.release`` makes the drug answer of it."""

    time: float
    squeezed: float
    fluid_fraction: float
    radius: float
    peclet: float | None
    mass_balance_error: float
    uncertainty: Any
    note: str


def reduced_dose(req: Any, settings: Any) -> ReducedDose | None:
    """The drug dose from the reduced model where it answers (:func:`applies`), else None."""
    verdict = applies(req, settings)
    if not verdict.applies:
        return None
    err = verdict.stated_error
    from ..truth import Part, Uncertainty

    try:
        rel, t, squeezed = reduced_release(req)
    except ValueError:
        return None  # not reached: the full solver says how much is
    h = req.solute.hindrance
    sieved = h.convective and h.mesh_ratio > 0.0
    num = NUMERICAL[1] if sieved else NUMERICAL[0]
    a3 = float(_interp(t, rel.t, rel.radius**3))
    fluid = (float(rel.radius[0]) ** 3 - a3) / (req.start_radius**3 - 1.0)
    how = ("ask with validate (HTTP validate_full: true, CLI --validate, Python "
           "plan_drug_dose(..., validate=True)) for the full solver's drug run")
    unc = Uncertainty(
        Part(num, f"numerical: {num:.1%}, the largest change of the dose times of "
                  f"{'sieved' if sieved else 'unsieved'} drugs from {CELLS} graded dry cells "
                  "to 384 (benchmarks/drug_reduced.py --convergence)"),
        Part(None, f"interfacial length: not measured for the reduced drug model; {how}"),
        Part(err, f"model form: {err:.1%}, the largest error of the reduced drug model "
                  "against the full solver's drug runs (50 um ANB and HHT beads) at the "
                  "measured D0 and doses around this one (docs/drug_reduced.md); " + how))
    note = (f"{MODEL_NAME[0].upper()}{MODEL_NAME[1:]}: {CELLS} dry cells, the front "
            f"model's mechanics (sharp-interface front condition), within {err:.1%} of "
            f"the full solver where measured; {how}.")
    return ReducedDose(time=t, squeezed=squeezed, fluid_fraction=fluid,
                       radius=a3 ** (1.0 / 3.0), peclet=rel.peclet(0.0, t),
                       mass_balance_error=rel.mass_balance_error, uncertainty=unc, note=note)


def _interp(x: float, xs: Any, ys: Any) -> float:
    import numpy as np

    return float(np.interp(x, xs, ys))


__all__ = ["MEASURED", "STATED_LIMIT", "applies", "ReducedDose", "reduced_dose", "reduced_release",
           "stated_error"]
