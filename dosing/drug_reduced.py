"""Drug doses from the reduced drug model, where its measured error holds (issue 23).

The model (``solver.front.solute``): the drug's advection, hindered diffusion, sieving and
partition, exactly as the full solver's drug (docs/drug.md), on the step-function front
model's bead (the sharp-interface front model of the fluid answers) instead of the full
solver's mechanics; a few milliseconds a dose.  Its error is measured against the full
solver's drug runs (a 50 um bead of ANB 302 -> 308 K and HHT 304 -> 308 K, D0 1e-9 to 1e-5
cm^2/s, four hindrance laws, doses 10-90 %: ``benchmarks/drug_reduced.py --table``,
docs/drug_reduced.md), and :data:`MEASURED` keeps the largest |error| of both gels at each
measured (law, D0 / D_gel, dose).

Where it answers (:func:`applies`, :func:`stated_error`): a dose at once after the heating
starts (no wait at T_start), into a perfect sink, from a bead of 25-100 um dry radius
(``BEAD_UM``) on a jump the fluid answer gives to the front model (the direct truth: the
regularized model at the bead's own ell), with a law measured here for a drug
at least as hindered (r_s / xi_dry and r_s / r_f no smaller, Y <= ``Y_MAX``), D0 / D_gel and
the dose inside the measured range, and every corner of its cell (two D0, two doses, both
gels, that drug's row and the unhindered row) within ``STATED_LIMIT``.  The answer states
that largest corner as its model-form error.  Elsewhere the full solver answers, as it
does when asked to validate.
"""

from __future__ import annotations

import bisect
import math
from typing import Any

from solver.front.solute import CELLS, HORIZON, front_release, time_to_release

STATED_LIMIT = 0.05  # the reduced model answers where its measured error is at most this
Y_MAX = 1.0  # the free-volume law's Y of the measured drugs
# dry bead radii it answers for (um): the table's 50 um within a factor 2 either way, so the
# truth's ell = xi_dry / a_d (8e-5 at 50 um) stays within a factor 2 of the measured one
BEAD_UM = (25.0, 100.0)
FIRST_REACH = 1.25  # the first run's end, over the fluid's time for the same fraction
DOSES = (0.1, 0.3, 0.5, 0.7, 0.9)
MODEL = "front-solute"
MODEL_NAME = ("the reduced drug model (the drug's advection, hindered diffusion, sieving and "
              "partition on the sharp-interface front model's bead; docs/drug_reduced.md)")
Row = tuple[tuple[float, float], tuple[float, ...], tuple[tuple[float | None, ...], ...]]
# law -> measured drugs: ((r_s / xi_dry, r_s / r_f), D0 / D_gel of the measured rows, the
# largest |relative error| of the dose time over ANB and HHT at each of DOSES; None: a dose
# not reached), written by `python -m benchmarks.drug_reduced --emit` from
# benchmarks/drug_reduced_table.json
MEASURED: dict[str, list[Row]] = (
    {'amsden': [((0.25, 1.0),
                 (0.112558959519, 1.12558959519, 11.2558959519, 33.7676878557, 112.558959519,
                  337.676878557, 1125.58959519),
                 ((0.5725, 0.5669, 0.849, None, None), (0.1123, 0.0914, 0.0506, 0.0406, 0.0312),
                  (1.1756, 0.1205, 0.0134, 0.0391, 0.0353),
                  (5.2843, 0.2746, 0.0775, 0.0166, 0.0361),
                  (3.5133, 0.6179, 0.1891, 0.0748, 0.0512),
                  (1.769, 1.684, 0.3818, 0.1536, 0.0651),
                  (0.744, 1.0386, 0.9192, 0.3223, 0.1303))),
                ((0.0625, 0.25),
                 (0.112558959519, 1.12558959519, 11.2558959519, 112.558959519, 1125.58959519),
                 ((0.2215, 0.0465, 0.0354, 0.0501, 0.0578),
                  (0.2432, 0.0979, 0.084, 0.084, 0.0964), (0.1822, 0.0557, 0.0418, 0.0373, 0.036),
                  (0.0798, 0.0364, 0.0221, 0.018, 0.0159),
                  (0.032, 0.0171, 0.0115, 0.0108, 0.0075)))],
     'free-volume': [((0.25, 0.0),
                      (0.112558959519, 1.12558959519, 11.2558959519, 33.7676878557, 112.558959519,
                       337.676878557, 1125.58959519),
                      ((0.0904, 0.1054, 0.213, 0.2919, None),
                       (0.3355, 0.4236, 0.7609, None, None),
                       (2.0465, 0.3271, 0.258, 0.2079, 0.1655),
                       (21.5916, 0.3732, 0.3156, 0.2595, 0.2114),
                       (2020.1948, 0.5427, 0.4004, 0.3585, 0.2953),
                       (5826.3709, 1.8099, 0.5396, 0.4277, 0.3897),
                       (18968.4926, 1928.2657, 0.7326, 0.591, 0.4635))),
                     ((0.0625, 0.0),
                      (0.112558959519, 1.12558959519, 11.2558959519, 112.558959519,
                       1125.58959519),
                      ((0.2197, 0.025, 0.0169, 0.0248, 0.0284),
                       (0.2193, 0.0333, 0.0236, 0.0278, 0.0359),
                       (0.1069, 0.0312, 0.025, 0.0238, 0.025),
                       (0.1545, 0.1172, 0.1293, 0.1472, 0.1848),
                       (0.1811, 0.0627, 0.0562, 0.0582, 0.0729)))],
     'none': [((0.0, 0.0),
               (0.112558959519, 0.337676878557, 1.12558959519, 3.37676878557, 11.2558959519,
                33.7676878557, 112.558959519, 337.676878557, 1125.58959519),
               ((0.2457, 0.04, 0.0269, 0.0264, 0.0289), (0.2475, 0.0405, 0.0271, 0.0265, 0.0289),
                (0.257, 0.0427, 0.0279, 0.0266, 0.0283), (0.2856, 0.0458, 0.0254, 0.0224, 0.0227),
                (0.3392, 0.0582, 0.025, 0.0167, 0.0143), (0.3859, 0.0784, 0.0299, 0.0163, 0.0112),
                (0.2404, 0.1084, 0.0416, 0.02, 0.0108), (0.1496, 0.14, 0.0565, 0.0271, 0.0129),
                (0.0877, 0.0826, 0.0781, 0.0396, 0.0206)))],
     'ogston': [((0.25, 1.0),
                 (0.112558959519, 1.12558959519, 11.2558959519, 33.7676878557, 112.558959519,
                  337.676878557, 1125.58959519),
                 ((0.5644, 0.5636, None, None, None), (0.1119, 0.2107, 0.0793, 0.0571, 0.039),
                  (0.6812, 0.0942, 0.0344, 0.0321, 0.028),
                  (1.9526, 0.2011, 0.0705, 0.0197, 0.0326),
                  (2.7001, 0.383, 0.1359, 0.0953, 0.009), (1.446, 0.8249, 0.2379, 0.1012, 0.0955),
                  (0.6515, 0.8844, 0.4914, 0.1954, 0.0797))),
                ((0.0625, 0.25),
                 (0.112558959519, 1.12558959519, 11.2558959519, 112.558959519, 1125.58959519),
                 ((0.2211, 0.0418, 0.0311, 0.0476, 0.056),
                  (0.2508, 0.1072, 0.1042, 0.108, 0.1344),
                  (0.1637, 0.0601, 0.0492, 0.0473, 0.0462),
                  (0.0523, 0.0216, 0.0171, 0.0159, 0.0143),
                  (0.0194, 0.0035, 0.0056, 0.0063, 0.0063)))]}
)


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


def stated_error(solute: Any, dose: float) -> float | None:
    """The reduced model's stated error for ``solute`` (a ``solver.solute.Solute``) at
    ``dose`` of the load, or None where it does not answer (module docstring): the
    measured drug of the same law that is least hindering among those at least as
    hindering as this one (r_s / xi_dry and r_s / r_f no smaller), and the unhindered
    drug, both within STATED_LIMIT at every corner of the cell around (D0 / D_gel, dose)."""
    h = solute.hindrance
    d = solute.diffusivity
    if d <= 0.0 or solute.release_volume is not None:
        return None
    none = MEASURED.get("none")
    if not none:
        return None
    errs = [_corners(none[0], d, dose)]
    if h.law != "none":
        if h.law == "free-volume" and h.y > Y_MAX:
            return None
        mesh = h.mesh_ratio if (h.convective or h.law != "ogston") else 0.0
        rows = sorted((r for r in MEASURED.get(h.law, ()) if r[0][0] >= mesh * (1 - 1e-9)
                       and r[0][1] >= h.fiber_ratio * (1 - 1e-9)), key=lambda r: sum(r[0]))
        if not rows:
            return None
        errs.append(_corners(rows[0], d, dose))
    if any(e is None for e in errs):
        return None
    err = max(errs)
    return err if err <= STATED_LIMIT else None


def applies(req: Any, settings: Any) -> float | None:
    """The stated error if the reduced model answers drug dose ``req`` (a
    ``DrugDoseRequest``) on the truth ``settings``, else None."""
    from .model_choice import choose_model

    dry = req.bead_dry_radius_um
    if (req.lead > 0.0 or not settings.direct or dry is None
            or not BEAD_UM[0] <= dry <= BEAD_UM[1]):
        return None
    own = req.constants.interfacial_lengths(dry)[0]  # the bead's own ell: the measured truth
    if abs(settings.interfacial_length / own - 1.0) > 1e-9:
        return None
    err = stated_error(req.solute, req.fraction)
    if err is None:
        return None
    model, _ = choose_model(req.gel, req.t_start, req.t_end, req.branch)
    return err if model == "front" else None


def reduced_release(req: Any) -> tuple[Any, float]:
    """The reduced model's release (``solver.solute.ReleaseResult``) for ``req``'s jump and
    the dose's time on it.  First only to a quarter past the fluid's time for the same
    fraction (a drug that diffuses leaves at least as fast as the fluid unless the shell
    hinders it), then, if the dose is not reached, to the end of the horizon; ValueError if
    it never is."""
    from .model_choice import front_run

    fr = front_run(req.gel, req.t_start, req.t_end, req.branch, True)
    first = FIRST_REACH * float(fr.time_to_fraction(req.fraction))
    for horizon in (first, HORIZON):
        rel = front_release(fr, req.solute, horizon=horizon)
        try:
            return rel, time_to_release(rel, req.fraction)
        except ValueError:
            if horizon == HORIZON:
                raise
    raise AssertionError("unreachable")


def reduced_answer(req: Any, settings: Any, common: dict[str, Any]) -> Any:
    """The drug dose from the reduced model where it answers (:func:`applies`), else None.
    ``common``: the answer fields every drug answer shares (``dosing.drug_dose``)."""
    err = applies(req, settings)
    if err is None:
        return None
    from .drug_dose import SPLIT, DrugDoseAnswer, _conc, mechanism
    from .truth import Part, Uncertainty

    try:
        rel, t = reduced_release(req)
    except ValueError:
        return None  # not reached: the full solver says how much is
    tau = common["timescale_seconds"]
    squeezed = rel.squeezed_at(t)
    a3 = float(_interp(t, rel.t, rel.radius**3))
    fluid = (float(rel.radius[0]) ** 3 - a3) / (req.start_radius**3 - 1.0)
    pe = rel.peclet(0.0, t)
    how = ("ask with validate (HTTP validate_full: true, CLI --validate, Python "
           "plan_drug_dose(..., validate=True)) for the full solver's drug run")
    unc = Uncertainty(
        Part(None, f"numerical: below 1 % unhindered, 4 % sieved ({CELLS} graded dry cells "
                   "against 384: benchmarks/drug_reduced.py --convergence)"),
        Part(None, f"interfacial length: not measured for the reduced drug model; {how}"),
        Part(err, f"model form: {err:.1%}, the largest error of the reduced drug model "
                  "against the full solver's drug runs (50 um ANB and HHT beads) at the "
                  "measured D0 and doses around this one (docs/drug_reduced.md); " + how))
    return DrugDoseAnswer(
        model=MODEL, time=t, seconds=None if tau is None else t * tau,
        leaked_before_heating=0.0, leaked_before_heating_ug=0.0 if common["load_ug"]
        is not None else None, squeezed_fraction=squeezed,
        diffused_fraction=req.fraction - squeezed,
        mechanism=mechanism(squeezed, req.fraction - squeezed), fluid_fraction=fluid,
        medium_concentration_ug_per_ul=_conc(req, req.fraction, a3 ** (1.0 / 3.0)),
        mass_balance_error=rel.mass_balance_error, fluid_answer=None, scenario_key=None,
        uncertainty=unc, peclet=pe,
        split=SPLIT + ("" if pe is None else f" Peclet number of the heating {pe:.3g}."),
        note=(f"{MODEL_NAME[0].upper()}{MODEL_NAME[1:]}: {CELLS} dry cells, the front "
              f"model's mechanics (sharp-interface front condition), within {err:.1%} of "
              f"the full solver where measured; {how}."), **common)


def _interp(x: float, xs: Any, ys: Any) -> float:
    import numpy as np

    return float(np.interp(x, xs, ys))


__all__ = ["MEASURED", "STATED_LIMIT", "applies", "reduced_answer", "reduced_release",
           "stated_error"]
