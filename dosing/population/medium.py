"""A batch's drug dose into one shared medium (issue 26): the Python way in.

The batch (a size distribution) of drug-loaded beads releases into a well-mixed medium of
``medium_volume_ml`` shared by its ``bead_count`` beads (None: a perfect sink, the default).
Each size class follows the full-solver mechanics of its interfacial-length band in its own
time t / tau_k (module ``batch``): the sizes are cut into the fluid batch's bands
(``population.bands.band_edges``: even in ln R over the volume-weighted central 99 %), each band
run once at the ell of its geometric-centre bead (ell = xi_dry / a_d, as every truth's).
The solute of every size class and the medium are solved together (module
``solver.solute.medium``), so the beads see one concentration c_med(t) and take drug back from it.
The classes are Gauss-Legendre nodes over the volume-weighted law (a bead's load is
~ R^3), the rows of a measured table exactly.

The answer states the batch's dose time (a fraction of its load in the medium), what the
sum of perfect-sink beads would say at that time, the mass balance, the medium's
concentration, the quadrature error (classes doubled) and the three parts of the truth's
uncertainty, each the relative change of the batch's dose time when every class follows
the central band's other run instead of its own (the parts vary little with the band, as
the fluid batch's validation measures): numerical (the mechanics on n / 2 cells, with the
coupled solve's steps halved), interfacial length (the mechanics at the mesh length's
range, xi_lo and xi_hi; a bead's ell differs from its band's by less than that range) and
model form (the delayed-transition lattice, ``truth.delayed_settings``).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from solver.errors import ParameterError
from solver.limits import BEAD_COUNT_RANGE, MEDIUM_VOLUME_ML_RANGE
from solver.solute import MediumRelease, coupled_release

from ..payload.release import GROWTH, MAX_HORIZON, check_protocol
from ..quantity import micrometres, number, to_unit
from ..request import _clamp_length
from ..runs.mechanics import jump_mechanics, protocol_mechanics
from ..runs.solute import drug_settings
from ..truth import Part, delayed_settings
from ..units import UM3_PER_UL, timescale, volume_to_ul
from .bands import band_edges, size_settings
from .cycles import ladder, rule
from .sizes import DrySizes, SizeDistribution, as_distribution

CLASSES = (32, 64)  # Gauss-Legendre size classes (one panel): the answer's and its check
POINTS = 200  # steps of the coupled solve (x SUB), geometric from START x the horizon
START = 1e-5
SUB = (1, 2)  # steps per interval: the answer's and its check (their gap: numerical error)
HORIZON = 0.5  # tau of the reference bead's mechanics run (every class rests after its end)
PROTOCOL_POINTS = 400  # a protocol's coupled solve: outputs even in ln t from START x horizon
PROTOCOL_FIRST_HORIZON = 0.05  # tau_ref past the protocol's end: the first runs' horizon


def medium_volume_ml(value: Any, field: str = "medium_volume_ml") -> float | None:
    """A medium volume in mL (a number in mL, or a quantity: "250 uL"), None: a sink."""
    if value is None:
        return None
    if isinstance(value, str):
        try:
            value = float(value)  # a bare number is in mL
        except ValueError:
            pass
    ul = to_unit(value if not isinstance(value, (int, float)) or isinstance(value, bool)
                 else value * 1e3, "volume", field)
    ml = ul * 1e-3
    lo, hi = MEDIUM_VOLUME_ML_RANGE
    if not lo <= ml <= hi:
        raise ParameterError(field, value, f"{lo:g}-{hi:g} mL (None: a perfect sink)")
    return ml


def bead_count(value: Any, field: str = "bead_count") -> float:
    """The batch's number of beads."""
    x, (lo, hi) = number(value), BEAD_COUNT_RANGE
    if not (math.isfinite(x) and lo <= x <= hi):
        raise ParameterError(field, value, f"a number of beads {lo:g}-{hi:g}")
    return x


def batch_dry_volume_ul(sizes: DrySizes, count: float) -> float:
    """The batch's dry volume N E_n[4 pi R^3 / 3] in uL (E_n[R^3] = 1 / E_v[R^-3])."""
    r, v = sizes.nodes(64)
    mean_r3 = 1.0 / float(np.sum(v / r**3))
    return count * 4.0 * math.pi / 3.0 * mean_r3 / UM3_PER_UL


@dataclass
class DrugBatchAnswer:
    """A batch's drug dose into a shared medium (module doc); times in the reference
    bead's tau (and seconds)."""

    model: str
    dose_fraction: float
    time: float
    seconds: float | None
    sink_time: float
    sink_overestimate: float
    medium_volume_ml: float | None
    bead_count: float | None
    medium_over_pore_volume: float | None
    medium_concentration_ug_per_ul: float | None
    mass_balance_error: float
    numerical_error: float
    quadrature_error: float
    classes: int
    reference_dry_radius_um: float
    interfacial_length: float
    description: str
    note: str
    uncertainty: dict[str, Part] | None = None  # numerical, interfacial length, model form
    bands: list[dict[str, float]] | None = None  # each band's bead and interfacial length

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form (JSON-ready)."""
        return asdict(self)


def truth_parts(req: Any, sizes: DrySizes, bands: Bands, reps: np.ndarray,
                case: tuple[float | None, float, float, float]) -> dict[str, Part]:
    """The three parts of the truth's uncertainty (module doc): each the relative change of
    the batch's dose time (n classes, 2 steps per interval) when every class follows one of
    the central band's other runs instead of that band's own; ``case`` is (v0, the dose,
    the coupled solve's step-halving gap, the answer's time)."""
    v0, f, steps_gap, t_bands = case
    c = len(bands.settings) // 2
    s = bands.settings[c]

    def time_on(b: Bands) -> float:
        return coupled(b, req.solute, sizes, CLASSES[0], v0, SUB[1]).time_to_release(f)

    def change(other: Any) -> float | str:
        try:
            return abs(time_on(run_bands(req, sizes, np.array([]), [other])) / t0 - 1.0)
        except ValueError as exc:  # the other run does not reach the dose in its horizon
            return str(exc)

    t0 = time_on(bands.only(c))
    where = (f"every class on the central band's ({reps[c]:.4g} um, ell = "
             f"{s.interfacial_length:.3g}) runs")
    chk = s.check()
    gap = change(chk)
    num = (None if isinstance(gap, str) else gap + steps_gap)
    out = {"numerical": Part(num, (
        f"numerical: {num:.2%}" if num is not None else "numerical: not measured") +
        f" (the mechanics on {chk.n} cells against {s.n}, {where}: "
        + (f"{gap:.2%}" if not isinstance(gap, str) else f"the check fails: {gap}")
        + f"; the coupled solve's steps halved: {steps_gap:.1e})")}
    if s.direct:
        own, lo, hi = req.constants.interfacial_lengths(float(reps[c]))
        ell = s.interfacial_length
        both = [change(s.with_length(_clamp_length(ell * x / own))) for x in (lo, hi)]
        nums = [x for x in both if not isinstance(x, str)]
        rel = max(nums) if len(nums) == 2 else None
        xr = req.constants.mesh_length_range_nm
        out["interfacial_length_range"] = Part(rel, (
            f"interfacial length: {rel:.2%}" if rel is not None else
            "interfacial length: not measured (" + "; ".join(
                x for x in both if isinstance(x, str)) + ")") +
            f" (the mechanics at xi_dry {xr[0]:g}-{xr[1]:g} nm, {where}; each class runs at "
            "its band's ell, which differs from the bead's own by less than that range; the "
            f"bands' own ells moved the batch's time by {t_bands / t0 - 1.0:+.1e} "
            "(relative) against every class at the central band's)")
        dl = delayed_settings(s)[-1]
        mf = change(dl)
        out["model_form"] = Part(None if isinstance(mf, str) else mf, (
            f"model form: {mf:.2%}" if not isinstance(mf, str) else
            f"model form: not measured ({mf})") + (
            f" (the delayed-transition law: the ell = 0 Lagrangian lattice, N = {dl.n}, "
            f"{where})"))
    else:
        why = ("the paper's model (no interfacial energy)" if not s.regularized else
               "a ladder's coarsest rung")
        for k in ("interfacial_length_range", "model_form"):
            out[k] = Part(None, (
                f"{k.replace('_range', '').replace('_', ' ')}: not measured for {why}; "
                "the direct truth (the default) states it"))
    return out


def reference_bead(req: Any, size_distribution: Any) -> tuple[Any, SizeDistribution]:
    """(the request at the batch's number-weighted mean bead, the spec with its mean): a
    spread without a size takes the request's bead size as its mean (as ``DoseRequest``)."""
    from dataclasses import replace

    d = as_distribution(size_distribution)
    own = "dry_radius_um" if d.state == "dry" else "swollen_radius_um"
    other = "swollen_radius_um" if d.state == "dry" else "dry_radius_um"
    if getattr(req, other) is not None:
        raise ParameterError(other, getattr(req, other), f"None with a {d.state} "
                             f"size_distribution (its number-weighted mean goes in {own})")
    size = getattr(req, own)
    if not d.has_size:
        if size is None:
            raise ParameterError("size_distribution.mean_um", None, f"a size > 0 (um), or "
                                 f"{own} as the batch's number-weighted mean")
        return req, d.with_mean(micrometres(size, own))
    mean = d.number_mean_um()
    if size is None:
        return replace(req, **{own: mean}), d
    if not math.isclose(micrometres(size, own), mean, rel_tol=1e-9):
        raise ParameterError(own, size, f"None or the size_distribution's number-weighted "
                             f"mean {mean:.6g} um")
    return req, d


def batch_classes(sizes: DrySizes, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(rho_k = (R_k / R_ref)^2, load shares nu_k) of ``n`` classes (a table: its rows)."""
    r, v = sizes.nodes(0 if sizes.exact else n)
    return (r / sizes.mean_um) ** 2, v


@dataclass(frozen=True)
class Bands:
    """The batch's interfacial-length bands: inner edges (um), each band's mechanics
    samples ``s`` and node volumes ``s3`` (``solver.solute.node_volumes``), its settings."""

    edges: np.ndarray
    s: list[np.ndarray]
    s3: list[np.ndarray]
    settings: list[Any]

    def of(self, sizes: DrySizes, rho: np.ndarray) -> np.ndarray:
        """Each class's band (its dry radius R_ref sqrt(rho) against the edges)."""
        return np.searchsorted(self.edges, sizes.mean_um * np.sqrt(rho))

    def only(self, b: int) -> Bands:
        """Every class on band ``b``'s mechanics."""
        return Bands(np.array([]), [self.s[b]], [self.s3[b]], [self.settings[b]])


def run_bands(req: Any, sizes: DrySizes, edges: np.ndarray, settings: list[Any]) -> Bands:
    """Each band's mechanics (memoised full-solver runs to HORIZON)."""
    from solver.solute import node_volumes

    runs = [jump_mechanics(req.gel, req.t_start, req.t_end, req.branch, x, HORIZON)
            for x in settings]
    return Bands(edges, [np.asarray(r.t, dtype=float) for r in runs],
                 [node_volumes(r) for r in runs], list(settings))


def coupled(bands: Bands, solute: Any, sizes: DrySizes, n: int, v0: float | None,
            sub: int) -> MediumRelease:
    """The coupled release of ``n`` classes, each on its band's mechanics, up to the
    largest class's horizon (of the finest quadrature: every run on the same outputs), on
    steps even in ln t (a release is fast at first: the outputs are the steps)."""
    rho, nu = batch_classes(sizes, n)
    end = min(float(x[-1]) for x in bands.s)
    t_max = end * float(batch_classes(sizes, CLASSES[-1])[0].max())
    times = np.concatenate(([0.0], np.geomspace(t_max * START, t_max, POINTS)))
    return coupled_release(bands.s, bands.s3, solute, rho, nu, v0, times, sub=sub, points=0,
                           band=bands.of(sizes, rho))


def drug_batch_dose(req: Any, size_distribution: Any, medium_volume: Any = None,
                    count: Any = None) -> DrugBatchAnswer:
    """The batch's drug dose (module doc).  ``req`` is a DrugDoseRequest of the reference
    bead (its drug's own release_volume_ul must be None: the batch's medium is
    ``medium_volume``, mL, shared by ``count`` beads); ``size_distribution`` a spec."""
    from ..runs.solute import drug_settings

    if req.drug.release_volume_ul is not None:
        raise ParameterError("drug.release_volume_ul", req.drug.release_volume_ul,
                             "None for a batch (give medium_volume_ml and bead_count)")
    if req.drug_mass_ug is not None:
        raise ParameterError("drug_mass_ug", req.drug_mass_ug,
                             "None for a batch (give dose_fraction of the batch's load)")
    if req.lead > 0.0:
        raise ParameterError("wait", req.wait if req.wait is not None else req.wait_seconds,
                             "0 or None for a batch (a wait at T_start is not planned for "
                             "batches yet)")
    req, spec = reference_bead(req, size_distribution)
    sizes = spec.resolve(req.start_radius, req.t_start)
    ml = medium_volume_ml(medium_volume)
    v0 = None
    n_beads = None
    if ml is not None:
        if count is None:
            raise ParameterError("bead_count", None, "the batch's number of beads (with "
                                 "medium_volume_ml)")
        n_beads = bead_count(count)
        v0 = ml * 1e3 / batch_dry_volume_ul(sizes, n_beads)
    if req.heating is not None:  # under a protocol: a run per size node
        return _protocol_answer(req, sizes, (ml, n_beads, v0))
    settings = drug_settings(req.settings)
    edges, reps = band_edges(sizes)
    bands = run_bands(req, sizes, edges, [size_settings(settings, req.constants, sizes.mean_um,
                                                        float(r)) for r in reps])
    solute = req.solute
    f = req.fraction
    # the answer (n classes, 2 steps per interval), its numerical check (1 step) and its
    # quadrature check (2n classes, 1 step: against the n-class 1-step run)
    cases = ((CLASSES[0], SUB[0]), (CLASSES[0], SUB[1]), (CLASSES[1], SUB[0]))
    runs = {c: coupled(bands, solute, sizes, c[0], v0, c[1])
            for c in (cases[:2] if sizes.exact else cases)}
    if sizes.exact:
        runs[cases[2]] = runs[cases[0]]
    best = runs[cases[1]]
    try:
        t = best.time_to_release(f)
        t_num = runs[cases[0]].time_to_release(f)
        t_quad = runs[cases[2]].time_to_release(f) * t / t_num
    except ValueError as exc:
        raise ParameterError("dose_fraction", f, f"below {best.released.max():.4f} (the "
                             "batch's release into this medium by the largest bead's "
                             f"{HORIZON:g} tau)", str(exc)) from None
    sink = best if v0 is None else coupled(bands, solute, sizes, CLASSES[0], None, SUB[1])
    steps_gap = abs(t_num - t) / t
    unc = truth_parts(req, sizes, bands, reps, (v0, f, steps_gap, t))
    ells = ", ".join(f"{x.interfacial_length:.3g}" for x in bands.settings)
    return _answer(
        req, sizes, (ml, n_beads, v0), t, best, sink, lambda medium, tau, t_sink, over: (
            f"Full-solver mechanics ({settings.grid} grid, N = {settings.n}) of "
            f"{len(reps)} interfacial-length band(s) of the batch (beads of "
            f"{', '.join(f'{r:.4g}' for r in reps)} um dry at ell = {ells}; each size in its "
            f"own tau ~ R^2, the reference bead {sizes.mean_um:.4g} um dry) with the drug of "
            f"{best.rho.size} size classes ({sizes.spec.describe()}) released into {medium}: "
            f"the batch releases {f:.0%} of its load at {t:.4g} tau_ref = {t * tau:.4g} s"
            + ("" if v0 is None else
               f"; the sum of perfect-sink beads says {t_sink:.4g} tau_ref and overstates "
               f"the released drug at that time by {over:.1%} (re-absorption from the shared "
               "medium)") + ". " + " ".join(p.text for p in unc.values())),
        model="full+batch-medium", unc=unc,
        mass_balance_error=max(r.mass_balance_error for r in runs.values()),
        numerical_error=steps_gap,
        quadrature_error=0.0 if sizes.exact else abs(t_quad - t) / t,
        classes=int(best.rho.size),
        interfacial_length=float(settings.interfacial_length or 0.0),
        bands=list(zip(reps, bands.settings, strict=True)))


def _answer(req: Any, sizes: DrySizes, medium: tuple[float | None, float | None, float | None],
            t: float, best: MediumRelease, sink: MediumRelease, note: Any, unc: dict[str, Part],
            bands: list[tuple[float, Any]], **fields: Any) -> DrugBatchAnswer:
    """The answer of a batch releasing into ``medium`` (mL, beads, v0) at ``t`` (tau_ref) on
    ``best``; ``sink`` the perfect-sink beads' release; ``note(medium text, tau, sink time,
    overstatement)``; ``bands`` (dry radius, settings) of its mechanics."""
    ml, n_beads, v0 = medium
    f = req.fraction
    t_sink = sink.time_to_release(f) if sink is not best else t
    over = sink.released_at(t) / best.released_at(t) - 1.0 if sink is not best else 0.0
    tau = timescale(sizes.mean_um, req.t_end, req.constants).seconds
    pore = _pore(req, v0)
    conc = None
    if v0 is not None and req.load_ug is not None:  # per load and batch dry volume -> ug/uL
        ref_ul = volume_to_ul(4.0 * math.pi / 3.0, sizes.mean_um)
        conc = float(np.interp(t, best.t, best.concentration)) * req.load_ug / ref_ul
    text = ("a perfect sink" if v0 is None else
            f"one well-mixed medium of {ml:.4g} mL shared by {n_beads:.4g} beads "
            f"({pore:.3g}x their partition-weighted pore volume)")
    return DrugBatchAnswer(
        dose_fraction=f, time=t, seconds=t * tau, sink_time=t_sink, sink_overestimate=over,
        medium_volume_ml=ml, bead_count=n_beads, medium_over_pore_volume=pore,
        medium_concentration_ug_per_ul=conc, reference_dry_radius_um=sizes.mean_um,
        description=sizes.spec.describe(), note=note(text, tau, t_sink, over),
        uncertainty=unc, bands=[{"dry_radius_um": float(r), "interfacial_length": float(
            x.interfacial_length)} for r, x in bands], **fields)


def _pore(req: Any, v0: float | None) -> float | None:
    """The medium over the batch's partition-weighted pore volume."""
    if v0 is None:
        return None
    k = float(req.solute.partition_at(1.0 - 1.0 / req.start_radius**3))
    return v0 / (k * (req.start_radius**3 - 1.0))


def _protocol_answer(req: Any, sizes: DrySizes,
                     medium: tuple[float | None, float | None, float | None]
                     ) -> DrugBatchAnswer:
    """The batch's drug dose under ``req.heating`` (:func:`protocol_batch_time`)."""
    v0 = medium[2]
    res = protocol_batch_time(req, sizes, v0)
    t, best, f = res["time"], res["release"], req.fraction
    sink = best if v0 is None else protocol_batch_time(req, sizes, None)["release"]
    unc = protocol_parts(res)
    return _answer(
        req, sizes, medium, t, best, sink, lambda text, tau, t_sink, over: (
            f"Under the protocol {'; '.join(res['texts'])}: each of {res['nodes']} size "
            f"nodes ({', '.join(f'{r:.4g}' for r in res['radii'])} um dry) runs the full "
            f"solver's mechanics of the protocol at its own size and interfacial length (its "
            f"own program: tau ~ R^2), the drug of every node released into "
            f"{text}; the batch ({sizes.spec.describe()}) releases {f:.0%} of "
            f"its load at {t * tau:.4g} s from the protocol's start. Quadrature: "
            f"{res['quadrature']:.1e} ({res['nodes']} against {res['check_nodes']} nodes). "
            + " ".join(p.text for p in unc.values())),
        model="full+batch-medium under a protocol", unc=unc,
        mass_balance_error=best.mass_balance_error, numerical_error=res["numerical"],
        quadrature_error=res["quadrature"], classes=res["nodes"],
        interfacial_length=float(req.settings.interfacial_length or 0.0),
        bands=[(r, m.settings) for r, m in zip(res["radii"], res["runs"], strict=True)])


def _protocol_solve(req: Any, sizes: DrySizes, n: int, horizon_s: float, v0: float | None,
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
    times = np.concatenate(([0.0], np.geomspace(t_max * START, t_max, PROTOCOL_POINTS)))
    mr = coupled_release([np.asarray(m.result.t, dtype=float) for m in runs],
                         [node_volumes(m.result) for m in runs], req.solute,
                         (r / ref) ** 2, v, v0, times, sub=sub, points=0,
                         band=np.arange(len(r)))
    return mr, r, runs


def protocol_batch_time(req: Any, sizes: DrySizes, v0: float | None) -> dict[str, Any]:
    """The batch's dose time (tau_ref) under ``req.heating`` and its checks: every size
    node runs the protocol's mechanics at its own size and ell (a protocol in seconds is
    a different dimensionless program per size, tau ~ R^2, eq. timescale), the coupled
    solve takes one mechanics per node in its own time t / rho_k; the nodes are the batch
    schedule's few-node rule (3 checked on 5), grown x GROWTH until the dose is in."""
    prot = check_protocol(req)
    tau_ref = timescale(sizes.mean_um, req.t_end, req.constants).seconds
    total = sum(p.duration or 0.0 for p in prot.program(tau_ref)
                if math.isfinite(p.duration or 0.0))
    rungs = ladder(sizes)
    n, fine = rungs[0], (rungs[1] if len(rungs) > 1 else None)
    horizon = total + PROTOCOL_FIRST_HORIZON
    while True:
        best, radii, runs = _protocol_solve(req, sizes, n, horizon * tau_ref, v0, 2)
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
    half, _, _ = _protocol_solve(req, sizes, n, horizon * tau_ref, v0, 1)
    t_half = half.time_to_release(req.fraction)
    quad = 0.0
    if fine is not None:
        check, _, _ = _protocol_solve(req, sizes, fine, horizon * tau_ref, v0, 2)
        quad = abs(check.time_to_release(req.fraction) / t - 1.0)
    return {"time": t, "release": best, "radii": radii, "runs": runs,
            "numerical": abs(t_half / t - 1.0), "quadrature": quad,
            "nodes": len(radii), "check_nodes": None if fine is None else fine,
            "horizon": horizon, "texts": prot.texts}


def protocol_parts(res: dict[str, Any]) -> dict[str, Part]:
    """The answer's parts under a protocol (module doc), in numbers and words."""
    return {
        "numerical": Part(res["numerical"], (
            f"numerical: {res['numerical']:.1e} (the coupled solve's steps halved); the "
            "mechanics' n / 2 check is not run per node (the single bead's drug dose under "
            "the protocol gives it)")),
        "interfacial_length_range": Part(None, (
            "interfacial length: not measured under a protocol (each node runs at its own "
            "ell = xi_dry / a_d)")),
        "model_form": Part(None, (
            "model form: D0 is held at the protocol's hottest temperature; what that costs "
            "is not run per node (the single bead's drug dose under the protocol bounds "
            "it)")),
    }
