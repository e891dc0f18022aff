"""A validated batch answer: the truth per interfacial-length band (issue 26).

The truth runs each bead at its own interfacial length ell = xi_dry / a_d (module
``truth``), so beads of different sizes follow different dimensionless trajectories.  The
batch's sizes are cut into a few bands in ln R (BANDS, evenly over the volume-weighted law's
central 99 %: the outer bands reach out to the tails); each band is run once, dimensionless,
at the ell of its geometric-centre radius, with the direct truth's runs (module ``truth``:
n and n / 2 cells, ell at xi_lo and xi_hi, the model-form lattice shared by every band).
The batch's dose time solves

    V(T) = sum_k v_k F_b(k)(T / rho_k) = f

on Gauss-Legendre panels split at the band edges (F jumps there) and at the front model's
kink, with 32 and 64 nodes per panel (their gap is the quadrature error).  Each part of the
uncertainty is the same sum on the other runs: numerical (the n / 2 runs), interfacial
length (the xi_lo and xi_hi runs), model form (the delayed-transition lattice for every
bead); by default only the central band runs the check and interfacial-length runs and the
other bands take its relative change (their truth curves stretched in time by it: the
parts vary little with the band), ``every_band=True`` runs them in every band.  A bead's
ell differs from its band's by at most the band's half-width in ln R (a factor ~1.3 at
CV 0.3 with 3 bands), inside the mesh length's range (a factor 2 either way), so the band's
approximation is bounded by the interfacial-length part.  Beads past the end of their
band's run (the smallest: their own time is shorter than the run's need) take the run's
last release, which they have all but reached.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import numpy as np

from ..request import DoseRequest, _clamp_length
from ..runs.scenario import SolverSettings
from ..truth import Part, delayed_settings, role
from ..units import radius_after_dose, released_fraction
from .front import BatchAnswer, BatchRelease, batch_answer, batch_sizes
from .sizes import DrySizes

BANDS = 3
CENTRAL = (0.005, 0.995)  # the volume-weighted quantiles the bands split evenly (ln R)
PANEL_NODES = (32, 64)  # Gauss-Legendre nodes per panel: the answer's and its check
REACH = 1.3  # a band's run must cover its smallest central bead's time x this


def _volume_quantiles(sizes: DrySizes, p: tuple[float, ...]) -> np.ndarray:
    r, v = sizes.nodes(128)
    order = np.argsort(r)
    c = np.cumsum(v[order])
    return np.interp(p, c / c[-1], r[order])


def band_edges(sizes: DrySizes, n_bands: int = BANDS) -> tuple[np.ndarray, np.ndarray]:
    """(inner edges, representative radii) in um: ``n_bands`` bands even in ln R over the
    volume-weighted central 99 %, each represented by its geometric centre."""
    if sizes.exact and len(sizes.nodes(0)[0]) == 1:
        return np.array([]), np.array([sizes.mean_um])
    lo, hi = _volume_quantiles(sizes, CENTRAL)
    e = np.geomspace(lo, hi, n_bands + 1)
    return e[1:-1], np.sqrt(e[:-1] * e[1:])


def size_settings(settings: SolverSettings, constants: Any, ref_um: float,
                  radius_um: float) -> SolverSettings:
    """The truth's settings for a bead of ``radius_um`` in a batch whose reference bead
    (``ref_um``) runs at ``settings``: its own interfacial length ell = xi_dry / a_d (kept in
    the direct runs' range) when the reference runs at its own, else ``settings`` (an ell
    given by hand, a ladder, the paper's model)."""
    if not settings.direct:
        return settings
    own = _clamp_length(constants.interfacial_lengths(ref_um)[0])
    if not math.isclose(settings.interfacial_length, own, rel_tol=1e-9):
        return settings
    return settings.with_length(_clamp_length(constants.interfacial_lengths(radius_um)[0]))


def band_request(req: DoseRequest, dry_radius_um: float) -> DoseRequest:
    """The single-bead request of a band: the batch's jump, dose and settings at a bead of
    ``dry_radius_um`` (its own ell = xi_dry / a_d)."""
    d = req.settings.request_dict()
    own = _clamp_length(req.constants.interfacial_lengths(req.bead_dry_radius_um)[0])
    if math.isclose(d["interfacial_length"] or own, own, rel_tol=1e-9):
        d["interfacial_length"] = None  # the bead's own ell: set per band
    settings = SolverSettings(**d)
    return DoseRequest(req.gel, req.t_start, req.t_end, dose_fraction=req.fraction,
                       dry_radius_um=dry_radius_um, constants=req.constants,
                       branch=req.branch, settings=settings)


def _release(traj: Any, a0: float) -> tuple[np.ndarray, np.ndarray]:
    """(s, F(s)) of a full-solver run: the released fraction on its dense steps (eq.
    FluidVolExpelled), made non-decreasing."""
    t, a = (traj.step_t, traj.step_radius) if len(traj.step_t) else (traj.t, traj.radius)
    f = released_fraction(a0, np.asarray(a, dtype=float))
    return np.asarray(t, dtype=float), np.maximum.accumulate(f)


def validated_batch(planner: Any, req: DoseRequest, n_bands: int = BANDS,
                    every_band: bool = False, lean: bool = True) -> BatchAnswer:
    """The batch's answer from the truth per interfacial-length band, with the three-part
    uncertainty and the quadrature error (blocking: runs what the cache lacks).
    ``every_band``: the check and interfacial-length runs in every band (else in the
    central band, its relative change carried to the others: fewer runs).  ``lean``
    (default): a run whose need lies past its dose is not stopped at the dose (a stopped
    run is run again to its need), and the model-form lattice runs its finest rung alone
    (the batch uses no other); ``lean=False`` is the former way (benchmarks/batch_validation.py
    compares them)."""
    ans = batch_answer(req)
    sizes = batch_sizes(req)
    edges, reps = band_edges(sizes, n_bands)
    if not req.settings.direct:  # the ladder's and the paper's truth: one ell for all
        edges, reps = np.array([]), reps[:1]
    a0 = req.start_radius
    target = radius_after_dose(a0, req.fraction)
    lower = np.concatenate([[_volume_quantiles(sizes, CENTRAL[:1])[0]], edges])
    rho_lower = (lower / sizes.mean_um) ** 2
    breqs = [band_request(req, float(rep)) if req.settings.direct else req for rep in reps]
    band_info = [{"dry_radius_um": float(rep),
                  "interfacial_length": br.settings.interfacial_length}
                 for rep, br in zip(reps, breqs, strict=True)]
    kink = _kink_time(req)
    guess = ans.time
    needs = REACH * guess / rho_lower
    for _ in range(4):  # until every band's run covers its smallest central bead
        runs, delayed = _band_runs(planner, breqs, target, needs, a0, every_band,
                                   req.fraction, lean)
        t_of = {k: [BatchRelease(sizes, n, curves, kink, edges).dose_time(
                        req.fraction, _own(curves, edges, sizes.mean_um, req.fraction), guess)
                    for n in PANEL_NODES] for k, curves in runs.items()}
        guess = t_of["truth"][-1]
        short = [max(t_of[k][-1] for k in t_of) / rho_lower[b] > min(
                 runs[k][b][0][-1] for k in runs) for b in range(len(reps))]
        if not any(short):
            break
        needs = REACH * max(max(v) for v in t_of.values()) / rho_lower
    t_truth = t_of["truth"][-1]
    quad = abs(t_of["truth"][1] - t_of["truth"][0]) / t_truth
    num = abs(t_of["check"][-1] - t_truth) / t_truth
    ell_times = [t_of["ell_lo"][-1], t_of["ell_hi"][-1]]
    ell = max(abs(x - t_truth) / t_truth for x in ell_times)
    where = ("" if every_band or len(reps) == 1 else
             " (run in the central band, its relative change carried to the others)")
    unc: dict[str, Part | list[dict[str, float]]] = {
        "numerical": Part(num, (
            f"numerical: {num:.2g}, the batch's time on the n / 2 runs{where} "
            f"({t_of['check'][-1]:.5g}) against n ({t_truth:.5g})")),
        "interfacial_length_range": Part(ell, (
            f"interfacial length: {ell:.2g}, the batch's time at xi_lo and xi_hi{where} "
            f"({ell_times[0]:.5g}, {ell_times[1]:.5g}); it also bounds the bands' "
            "approximation of each bead's own ell")),
        "quadrature": Part(quad, (
            f"quadrature: {quad:.2g}, {PANEL_NODES[0]} against {PANEL_NODES[1]} Gauss-Legendre "
            "nodes per panel (panels split at the band edges and the front model's kink)")),
        "bands": band_info,
    }
    if delayed is not None:
        curve = [_release(delayed, a0)]
        t_d = BatchRelease(sizes, PANEL_NODES[-1], curve, kink).dose_time(
            req.fraction, _own(curve, np.array([]), sizes.mean_um, req.fraction), ans.time)
        covered = t_d / rho_lower[0] <= _release(delayed, a0)[0][-1]
        unc["model_form"] = Part(abs(t_d / t_truth - 1.0), (
            f"model form: {t_d / t_truth:.3g}x, the batch's time ({t_d:.5g}) if every bead "
            "followed the delayed-transition front law (the ell = 0 lattice; not part of the "
            "error estimate, docs/interfacial.md sec. 10)"
            + ("" if covered else "; its run ends before the smallest beads' time, which take "
               "its last release, so this time is an upper bound")))
    else:
        unc["model_form"] = Part(None, "model form: not run (not a direct truth)")
    # each band's own dose time (its curve reaching f), for the mean and percentile beads
    own = np.array([float(np.interp(req.fraction, f, s_)) for s_, f in runs["truth"]])
    ref = sizes.mean_um

    def own_time(r: float) -> float:
        return (r / ref) ** 2 * own[int(np.searchsorted(edges, r))]

    mean_t = own_time(ref)
    pt = np.array([own_time(float(r)) for r in ans.percentile_radii_um])
    bounds = np.concatenate([[0.0], edges, [np.inf]])
    delivered = 0.0
    for b in range(len(own)):
        top = min(bounds[b + 1], ref * math.sqrt(t_truth / own[b]))
        if top > bounds[b]:
            delivered += float(sizes.cdf(top)) - float(sizes.cdf(bounds[b]))
    tau = ans.timescale_seconds
    note = (ans.note + f" Validated: the truth per interfacial-length band ({len(reps)} "
            f"band(s)) gives {t_truth:.5g} ({t_truth / ans.time - 1.0:+.2%} against the "
            "front model; the mean and percentile beads' own times at their band's ell).")
    return replace(ans, time=t_truth, seconds=None if tau is None else t_truth * tau,
                   mean_bead_time=mean_t, mean_bead_seconds=None if tau is None else mean_t * tau,
                   delay=t_truth / mean_t - 1.0, fraction_delivered=delivered,
                   percentile_times=pt.tolist(),
                   percentile_seconds=None if tau is None else (pt * tau).tolist(),
                   note=note, uncertainty=unc, model="truth-bands")


def _own(curves: list[tuple[np.ndarray, np.ndarray]], edges: np.ndarray, radius_um: float,
         fraction: float) -> float:
    """The own dose time of the bead of ``radius_um`` (dimensionless in its band's run)."""
    s, f = curves[int(np.searchsorted(edges, radius_um))]
    return float(np.interp(fraction, f, s))


def _roles(breq: DoseRequest, scs: list[Any], trajs: list[Any]) -> tuple[dict[str, Any], Any]:
    """The runs of one band by role ('truth', 'check', 'ell_lo', 'ell_hi'), and its finest
    model-form run (None when not among them)."""
    by: dict[str, Any] = {}
    delayed = None
    for sc, t in zip(scs, trajs, strict=True):
        if isinstance(t, BaseException):
            raise t
        k = role(breq.settings, sc.settings)
        if k == "ell_range":
            k = ("ell_lo" if sc.settings.interfacial_length
                 < breq.settings.interfacial_length else "ell_hi")
        if k == "model_form":
            if sc.settings == delayed_settings(breq.settings)[-1]:
                delayed = t
            continue
        by[k] = t
    return by, delayed


def _band_runs(planner: Any, breqs: list[DoseRequest], target: float, needs: np.ndarray,
               a0: float, every_band: bool, fraction: float,
               lean: bool = True) -> tuple[dict[str, list[Any]], Any]:
    """Per role, every band's release curve; and the finest model-form run (shared, run to
    the smallest beads' need).  Without ``every_band`` only the central band runs the check
    and interfacial-length runs; the other bands take its relative change of the dose time
    (their truth curve stretched in time by it)."""
    roles = ("truth", "check", "ell_lo", "ell_hi")
    c = len(breqs) // 2
    curves: list[dict[str, Any]] = []
    delayed: Any = None
    for b, (breq, need) in enumerate(zip(breqs, needs, strict=True)):
        scs = planner.scenarios(breq)
        mf = [sc for sc in scs if not sc.settings.regularized]
        own = [sc for sc in scs if sc.settings.regularized]
        if not (every_band or b == c):
            own = own[:1]  # the truth run alone
        by, _ = _roles(breq, own, _runs(planner, own, target, float(need), a0, fraction,
                                        lean and need >= PAST_DOSE * _front_time(breq)))
        if b == c and mf:
            if lean:
                mf = mf[-1:]  # the finest lattice: the only one the batch uses
            _, delayed = _roles(breq, mf, planner._trajectories(mf, target,
                                                               float(max(needs))))
        curves.append({k: _release(t, a0) for k, t in by.items()})
    central = curves[c]

    def own_time(curve: tuple[np.ndarray, np.ndarray]) -> float:
        return float(np.interp(fraction, curve[1], curve[0]))

    runs: dict[str, list[Any]] = {k: [] for k in roles}
    for cur in curves:
        for k in roles:
            if k in cur:
                runs[k].append(cur[k])
            else:
                ratio = own_time(central.get(k, central["truth"])) / own_time(central["truth"])
                s_, f_ = cur["truth"]
                runs[k].append((s_ * ratio, f_))
    return runs, delayed


PAST_DOSE = 1.2  # a run whose need is this far past the front model's dose is not stopped


def _front_time(req: DoseRequest) -> float:
    from ..model_choice import model_answer

    t = model_answer(req).front_time
    return math.inf if t is None else float(t)


def _runs(planner: Any, scs: list[Any], target: float, need: float, a0: float,
          fraction: float, past: bool) -> list[Any]:
    """The band's runs to ``need``.  ``past`` (the need lies past the dose): run without
    the stop at the dose radius, which would end the run there and run it again from the
    start to its need; a run that still falls short of the dose is then extended to it."""
    if not past:
        return planner._trajectories(scs, target, need)
    out = planner._trajectories(scs, None, need)
    short = [i for i, t in enumerate(out) if not isinstance(t, BaseException)
             and _release(t, a0)[1][-1] < fraction]
    if short:
        again = planner._trajectories([scs[i] for i in short], target, need)
        for i, t in zip(short, again, strict=True):
            out[i] = t
    return out


def _kink_time(req: DoseRequest) -> float:
    from ..model_choice import front_run

    return float(front_run(req.gel, req.t_start, req.t_end, req.branch,
                           req.settings.regularized).t_stop)
