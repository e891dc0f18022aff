"""A schedule for a batch of beads: actuation times whose summed release meets each dose
(issue 26; sec. Application, fig. multidose_schematic).

A schedule heats at T_end and rests at T_start; while it rests each bead takes up fluid
(module ``protocol``).  A bead of dry radius R_k has tau_k = tau_ref rho_k, rho_k =
(R_k / R_ref)^2 (eq. timescale), so the schedule's actuation times d_i and rests r_i, in the
reference (number-weighted mean) bead's tau, are the protocol d_i / rho_k, r_i / rho_k in
bead k's own time: every size is its own run.  Heating i of the batch delivers

    D_i = sum_k v_k D_i,k,   D_i,k = (a_k(start_i)^3 - a_k(end_i)^3) / (a0^3 - 1)

of the batch's stored fluid (eq. FluidVolExpelled; v_k the volume weights: a bead's fluid
is ~ R^3).  :class:`BatchHeatings` is the :class:`dosing.question.shooting.Heatings` of that sum, so
the one shooting routine (``protocol.shoot_durations``: read off a longer heating, then the
secant method) finds the durations.  No reduced model covers the rests (the slow-heating
front model heats only), so each node is the truth's full-solver run of the protocol at the
bead's own interfacial length (ell = xi_dry / a_d, as every truth's) through the planner's
cache, the nodes of a run side by side.

The sum over sizes is a few-node Gauss rule over the volume-weighted law (``RULES``:
Gauss-Hermite in ln R for a lognormal, Gauss-Legendre for a normal, the distinct sizes of a
measured table exactly).  The durations found with n nodes are run on the next rung's
rule; the largest change of a dose is the quadrature error.  Above ``QUADRATURE_SHARE`` of
the tolerance the shooting is repeated on the finer rule (from the durations found).
A CV of 0 is one node, the mean bead: the same runs, the same shooting, the single bead's
schedule exactly.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass, field, replace
from itertools import accumulate
from typing import Any

import numpy as np

from solver.errors import NotApplicableError, ParameterError

from ..answers import HoldRow
from ..heating.cycles import cycle_scenario
from ..quantity import micrometres
from ..question import shooting
from ..question.events import schedule_events
from ..question.schedule import SchedulePlanner, ScheduleViews, hold_schedule, with_seconds
from ..question.shooting import (
    FluidHeatings,
    Member,
    NodeHeatings,
    Reach,
    delivery,
    windows,
)
from ..request import ScheduleRequest, _clamp_length
from ..runs.scenario import Scenario, SolverSettings
from ..truth import Part, truth_text
from ..units import timescale
from .bands import size_settings
from .front import Quadrature
from .sizes import DrySizes, as_distribution

RULES = (3, 5, 9)  # nodes of the rungs (Gauss-Hermite / Gauss-Legendre); each checks the last
LEGENDRE_RULES = (8, 16, 32)  # a normal's rungs (Gauss-Legendre over its +-8 SD support)
MAX_TABLE_SIZES = 12  # a measured table's distinct sizes a schedule runs (one run each)
QUADRATURE_SHARE = 0.25  # the quadrature error allowed, a share of the doses' tolerance
MODEL = "full-solver-per-size"
F = "size_distribution"


# ----------------------------------------------------------------------------- the sizes
def schedule_sizes(req: ScheduleRequest, size_distribution: Any) -> DrySizes:
    """The batch's dry radii; the request's bead size is its number-weighted mean (a spread
    without a size takes it; a law with its own size must agree with it)."""
    d = as_distribution(size_distribution)
    own = "dry_radius_um" if d.state == "dry" else "swollen_radius_um"
    size = getattr(req, own)
    if size is None:
        raise ParameterError(own, None, f"a size > 0 (um): the {d.state} number-weighted mean "
                             "of the batch (a batch schedule needs its reference bead)")
    size = micrometres(size, own)
    if not d.has_size:
        d = d.with_mean(size)
    elif not math.isclose(d.number_mean_um(), size, rel_tol=1e-9):
        raise ParameterError(own, size, f"the size_distribution's number-weighted mean "
                             f"{d.number_mean_um():.6g} um")
    sizes = d.resolve(req.start_radius, req.t_start)
    if d.kind == "table" and len(sizes.nodes(0)[0]) > MAX_TABLE_SIZES:
        raise ParameterError(f"{F}.sizes_um", f"{len(sizes.nodes(0)[0])} distinct sizes",
                             f"at most {MAX_TABLE_SIZES} distinct sizes for a schedule (one "
                             "full-solver run each per shooting step): bin the table, or give "
                             "a lognormal by mean_um and cv")
    return sizes


def reference_fields(size_distribution: Any, dry_radius_um: Any,
                     swollen_radius_um: Any) -> dict[str, float]:
    """The request's bead size to fill in (the batch's number-weighted mean, in its state)
    when neither is given and the distribution carries its own size; else nothing."""
    d = as_distribution(size_distribution)
    if dry_radius_um is not None or swollen_radius_um is not None or not d.has_size:
        return {}
    return {"dry_radius_um" if d.state == "dry" else "swollen_radius_um": d.number_mean_um()}


def ladder(sizes: DrySizes) -> tuple[int, ...]:
    """The rules' node counts (a single rung of 0: the batch itself)."""
    if sizes.exact:
        return (0,)
    return LEGENDRE_RULES if sizes.spec.kind == "normal" else RULES


def rule(sizes: DrySizes, n: int) -> tuple[np.ndarray, np.ndarray, str]:
    """(dry radii in um, volume weights summing to 1, the rule in words) with ``n`` nodes."""
    if sizes.exact:
        r, v = sizes.nodes(0)
        text = ("exact: a single size" if len(r) == 1
                else "exact: the sum over the table's distinct sizes")
        return np.asarray(r, dtype=float), np.asarray(v, dtype=float), text
    if sizes.spec.kind == "lognormal":
        r, v = sizes.law.hermite(n)
        return r, v / v.sum(), "Gauss-Hermite in ln R over the volume-weighted lognormal"
    r, v = sizes.nodes(n)
    return r, v, "Gauss-Legendre in R over the volume-weighted normal"


# ------------------------------------------------------------------------ the heatings
@dataclass(frozen=True)
class Node:
    """One size of the rule: dry radius (um), volume weight, rho = (R / R_ref)^2, and the
    truth's settings at its own interfacial length."""

    radius_um: float
    weight: float
    rho: float
    settings: SolverSettings


def nodes_of(req: ScheduleRequest, radii: np.ndarray, weights: np.ndarray,
             ref_um: float) -> list[Node]:
    """The rule's nodes; the reference bead's own (R = R_ref) keep the request's settings."""
    out = []
    for r, v in zip(radii.tolist(), weights.tolist(), strict=True):
        if math.isclose(r, ref_um, rel_tol=1e-12):
            out.append(Node(ref_um, v, 1.0, req.settings))
            continue
        settings = size_settings(req.settings, req.constants, ref_um, r)
        out.append(Node(r, v, (r / ref_um) ** 2, settings))
    return out


class FluidNode:
    """One size node's fluid heatings in its own tau (a member of
    :class:`dosing.question.shooting.NodeHeatings`): what each heating delivers of the node's own
    stored fluid (eq. FluidVolExpelled), the rests over its rho."""

    max_horizon = math.inf

    def __init__(self, req: ScheduleRequest, node: Node) -> None:
        self.req, self.rests = req, [r / node.rho for r in req.rests]

    def delivered(self, tr: Any, durations: Sequence[float]) -> list[float]:
        """Each heating's delivery, fractions of the node's stored fluid."""
        return delivery(tr, durations, self.rests, self.req.start_radius).delivered

    def released_within(self, tr: Any, durations: Sequence[float], k: int, x: float) -> float:
        """What heating k has delivered ``x`` (own tau) after its start."""
        start = windows(durations, self.rests)[k][0]
        a3 = tr.radius_at(start) ** 3
        return (a3 - tr.radius_at(start + x) ** 3) / (self.req.start_radius**3 - 1.0)

    def reach(self, tr: Any, durations: Sequence[float], k: int) -> Reach:
        """The single bead's own reading (a node of the reference size)."""
        return FluidHeatings(lambda steps: tr, self.req).reach(tr, durations, k)


class BatchHeatings(NodeHeatings):
    """The batch's heatings (:class:`dosing.question.shooting.Heatings`): the population seam
    (:class:`~dosing.question.shooting.NodeHeatings`) over each size node's fluid heatings
    (:class:`FluidNode`), durations in the reference bead's tau, the doses of the batch's
    stored fluid; a run is every node's trajectory of its own heat/rest cycles, run side by
    side through the planner (admitted as one group), counted."""

    max_horizon = math.inf  # a dose beyond every bead's reach is refused exactly (reach)

    def __init__(self, planner: SchedulePlanner, req: ScheduleRequest,
                 nodes: Sequence[Node]) -> None:
        from ..heating.response import mode_for

        super().__init__([Member(n.weight, n.rho, FluidNode(req, n)) for n in nodes],
                         req.doses, req.tolerance)
        self.max_horizon = math.inf
        self.planner, self.req, self.nodes = planner, req, list(nodes)
        self.mode = mode_for(planner, req)
        self.tau_ref = timescale(req.bead_dry_radius_um, req.t_end, req.constants).seconds

    def scenario(self, node: Node, durations: Sequence[float]) -> Scenario:
        """Node's heat/rest cycles in its own time (durations and rests over rho; a heating
        protocol's program in the node's own tau: ``dosing.heating.cycles``)."""
        return cycle_scenario(self.req, [d / node.rho for d in durations],
                              [r / node.rho for r in self.req.rests], self.tau_ref * node.rho,
                              node.settings, self.mode)

    def run(self, durations: Sequence[float]) -> list[Any]:
        """Every node's trajectory of the protocol with these actuation times."""
        self.count += 1
        scs = [self.scenario(n, durations) for n in self.nodes]
        if len(scs) == 1:
            return [self.planner.trajectory(scs[0])]
        together = getattr(self.planner, "_trajectories", None)  # admitted as one group
        if together is None:
            with ThreadPoolExecutor(len(scs)) as pool:
                return list(pool.map(self.planner.trajectory, scs))
        out = together(scs, None, 0.0)
        for x in out:
            if isinstance(x, BaseException):
                raise x
        return out

    def per_node(self, result: list[Any], durations: Sequence[float]) -> list[list[float]]:
        """Each node's delivery per heating (fractions of its own stored fluid)."""
        return [m.heatings.delivered(tr, self.own(m, durations))
                for tr, m in zip(result, self.members, strict=True)]

    def reach(self, result: list[Any], durations: Sequence[float], k: int) -> Reach:
        """Where the batch's heating k delivers dose k (:meth:`NodeHeatings.reach`); a dose
        beyond what the batch can still give up at T_end is refused exactly."""
        if len(self.nodes) > 1 or self.nodes[0].rho != 1.0:
            req = self.req
            af3, scale = req.jump.final_radius**3, req.start_radius**3 - 1.0
            most = sum(m.weight * (tr.radius_at(windows(self.own(m, durations), m.heatings.rests)
                                                [k][0]) ** 3 - af3) / scale
                       for tr, m in zip(result, self.members, strict=True))
            if self.targets[k] >= most:
                raise ParameterError(f"doses[{k}]", self.targets[k], f"below {most:.4f}",
                                     "after the earlier doses and rests the batch can give "
                                     "up at most that fraction of its stored fluid at T_end")
        return super().reach(result, durations, k)


def check(h: BatchHeatings, durations: Sequence[float]) -> dict[str, Any]:
    """Run the protocol with these actuation times on every node; compare with the doses."""
    result = h.run(durations)
    got = h.delivered(result, durations)
    errors = [g / f - 1.0 for g, f in zip(got, h.req.doses, strict=True)]
    return {"actuation_times": list(map(float, durations)), "delivered_fractions": got,
            "relative_errors": errors,
            "node_delivered_fractions": h.per_node(result, durations)}


# ------------------------------------------------------------------------------ answer
@dataclass
class BatchScheduleAnswer(ScheduleViews):
    """A batch's schedule: actuation times (in the reference bead's tau and seconds) whose
    summed release meets each dose of the batch's stored fluid, the nodes it ran, the
    quadrature and its error, and the hold reading it started from."""

    model: str
    distribution: dict[str, Any]
    description: str
    doses: list[float]
    rests: list[float]
    reference_dry_radius_um: float
    timescale_seconds: float
    nodes: list[dict[str, Any]]
    hold: list[HoldRow]
    hold_model: str
    protocol_check: dict[str, Any] | None
    corrected: dict[str, Any] | None
    quadrature: Quadrature
    uncertainty: dict[str, Part]  # numerical, quadrature, interfacial_length_range, model_form
    truth: str
    note: str
    t_start: float
    t_end: float
    # the schedule as a lab runs it, one row per step (dosing.question.events)
    events: list[dict[str, Any]] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form (JSON-ready)."""
        d = asdict(self)
        d["quadrature"] = self.quadrature.to_dict()
        return d


def _node_dicts(req: ScheduleRequest, nodes: Sequence[Node], tau_ref: float) -> list[dict]:
    return [{"dry_radius_um": n.radius_um, "volume_weight": n.weight, "rho": n.rho,
             "tau_seconds": tau_ref * n.rho,
             "interfacial_length": n.settings.interfacial_length if n.settings.regularized
             else 0.0} for n in nodes]


def batch_hold(planner: SchedulePlanner, req: ScheduleRequest,
               size_distribution: Any) -> tuple[str, list[HoldRow]]:
    """The hold reading for the batch: the reference bead's hold times, each end stretched by
    the batch's delay at that cumulative dose (``dosing.population.front``, the front model);
    where the front model does not answer a batch, the reference bead's own (said in the
    model)."""
    from .curves import batch_protocol_answer
    from .front import batch_answer

    model, rows = hold_schedule(planner, req)
    tau = timescale(req.bead_dry_radius_um, req.t_end, req.constants).seconds
    out, prev = [], 0.0
    for row, cum in zip(rows, accumulate(req.doses), strict=True):
        try:
            dreq = dose_request(req, cum, size_distribution)
            b = (batch_answer if dreq.heating is None else batch_protocol_answer)(dreq)
        except (NotApplicableError, ParameterError):
            return f"{model} (the mean bead's: no front model for the batch)", rows
        end = row.end * (b.time / b.mean_bead_time)  # a CV of 0: the ratio is 1 exactly
        out.append(replace(row, start=prev, end=end, actuation_time=end - prev,
                           actuation_seconds=(end - prev) * tau))
        prev = end
    return f"{model} x the batch's delay (front model over the sizes)", out


def dose_request(req: ScheduleRequest, fraction: float, size_distribution: Any) -> Any:
    """The batch's dose request of ``fraction`` of its stored fluid on the same case."""
    from ..request import DoseRequest

    fields = req.case_fields()
    fields["settings"] = SolverSettings(**req.settings.request_dict())
    return DoseRequest(**fields, dose_fraction=fraction,
                       size_distribution=as_distribution(size_distribution))


def over_rules(req: Any, sizes: DrySizes, lift: Any, reading: Any,
               guesses: Sequence[float], targets: Sequence[float], what: str
               ) -> tuple[dict[str, Any] | None, dict[str, Any] | None, Quadrature, list[Node]]:
    """A batch schedule's readings over the size rules, any payload (module doc): the check
    of ``guesses`` and the times shot (``shooting.corrected``) on the first rule's nodes
    (``lift(n)`` -> the lifted heatings, their nodes, the rule in words; ``reading(h, d)``
    what heatings ``h`` deliver at times ``d``), each run on the next rule: the largest
    change of a dose is the quadrature error, and the finer rule's delivery the answer.
    Above ``QUADRATURE_SHARE`` of the tolerance the shooting repeats on the finer rule."""
    rungs = ladder(sizes)
    table: list[tuple[int, float]] = []
    checked = corrected = None
    err, converged, used = 0.0, True, rungs[0]
    for i, n in enumerate(rungs):
        h, nodes, text = lift(n)
        used = n
        if req.check_protocol and checked is None:
            checked = reading(h, guesses)
        if req.correct:
            corrected = shooting.corrected(h, guesses, lambda d, h=h: reading(h, d),
                                           what=what)[0]
        res = corrected if req.correct else checked
        if res is None:
            break
        coarse, times = res["delivered_fractions"], res["actuation_times"]
        table.append((len(nodes), float(coarse[-1])))
        if sizes.exact:
            break
        if i + 1 == len(rungs):
            converged = False
            break
        fine, fine_nodes, _ = lift(rungs[i + 1])
        got = fine.delivered(fine.run(times), times)
        err = max(abs(g / c - 1.0) for g, c in zip(got, coarse, strict=True))
        table.append((len(fine_nodes), float(got[-1])))
        errors = [g / f - 1.0 for g, f in zip(got, targets, strict=True)]
        res.update(rule_nodes=len(nodes), rule_delivered_fractions=coarse,
                   delivered_fractions=got, check_nodes=len(fine_nodes),
                   relative_errors=errors)
        if res is corrected:
            worst = max(abs(e) for e in errors)
            res.update(max_relative_error=worst, met=bool(worst <= req.tolerance))
        converged = err <= QUADRATURE_SHARE * req.tolerance
        if converged or not req.correct:
            break
        guesses = times
    return checked, corrected, Quadrature(text, len(nodes), err, converged, table, used), nodes


def _quadrature_part(quad: Quadrature) -> Part:
    return Part(quad.error, (
        f"quadrature over sizes: {quad.rule}, {quad.nodes} nodes, error {quad.error:.1e} "
        "(the largest change of a dose on the next rule)"
        + ("" if quad.converged else "; NOT converged within the rules tried")))


def batch_schedule_with(planner: SchedulePlanner, req: ScheduleRequest,
                        size_distribution: Any) -> BatchScheduleAnswer:
    """Plan ``req`` for a batch of beads (module doc): hold times, the protocol check of
    them and the corrected times, each summed over the rule's nodes."""
    sizes = schedule_sizes(req, size_distribution)
    ref = sizes.mean_um
    tau = timescale(ref, req.t_end, req.constants).seconds
    hold_model, hold = batch_hold(planner, req, sizes.spec)

    def lift(n: int) -> tuple[BatchHeatings, list[Node], str]:
        r, v, text = rule(sizes, n)
        h = BatchHeatings(planner, req, nodes_of(req, r, v, ref))
        return h, h.nodes, text

    checked, corrected, quad, nodes = over_rules(
        req, sizes, lift, check, [row.actuation_time for row in hold], req.doses,
        "the batch's doses")
    with_seconds(tau, checked, corrected)
    parts = truth_parts(planner, req, nodes, corrected)
    return _answer(req, sizes, nodes, tau, (hold_model, hold), checked, corrected, quad, parts)


def truth_parts(planner: SchedulePlanner, req: ScheduleRequest, nodes: Sequence[Node],
                corrected: dict[str, Any] | None) -> dict[str, Part]:
    """The interfacial-length and model-form parts of a batch schedule: the largest
    relative change of a delivered dose when the found actuation times are run with every
    node at the mesh length's range (xi_lo, xi_hi: its ell scaled as its own) and on the
    delayed-transition lattice (``truth.delayed_settings``); the direct truth only."""
    from ..truth import delayed_settings

    if corrected is None or not req.settings.direct:
        why = ("no corrected times" if corrected is None else
               "the paper's model or a ladder (the direct truth, the default, states them)")
        return {"interfacial_length_range": Part(None, (
                    f"interfacial length: not measured ({why})")),
                "model_form": Part(None, f"model form: not measured ({why})")}
    durations, base = corrected["actuation_times"], corrected["rule_delivered_fractions"] \
        if "rule_delivered_fractions" in corrected else corrected["delivered_fractions"]

    def change(settings_of: Any) -> float:
        h = BatchHeatings(planner, req, [replace(n, settings=settings_of(n)) for n in nodes])
        got = check(h, durations)["delivered_fractions"]
        return max(abs(g / b - 1.0) for g, b in zip(got, base, strict=True))

    own, lo, hi = req.constants.interfacial_lengths(req.bead_dry_radius_um)
    ell = max(change(lambda n, x=x: n.settings.with_length(
        _clamp_length(n.settings.interfacial_length * x / own))) for x in (lo, hi))
    lattice = delayed_settings(req.settings)[-1]
    form = change(lambda n: lattice)
    xr = req.constants.mesh_length_range_nm
    return {
        "interfacial_length_range": Part(ell, (
            f"interfacial length: {ell:.2%}, the largest change of a delivered dose at the "
            f"found times with every node at xi_dry {xr[0]:g}-{xr[1]:g} nm")),
        "model_form": Part(form, (
            f"model form: {form:.2%}, the largest change of a delivered dose at the found "
            f"times if every bead followed the delayed-transition law (the ell = 0 Lagrangian "
            f"lattice, N = {lattice.n}; not part of the error estimate)"))}


def _answer(req: ScheduleRequest, sizes: DrySizes, nodes: Sequence[Node], tau: float,
            hold: tuple[str, list[HoldRow]], checked: dict[str, Any] | None,
            corrected: dict[str, Any] | None, quad: Quadrature,
            parts: dict[str, Part]) -> BatchScheduleAnswer:
    ref = sizes.mean_um
    worst = None if corrected is None else corrected["max_relative_error"]
    unc = {
        "numerical": Part(worst, (
            "numerical: each dose met within the tolerance "
            f"{req.tolerance:.0%} by the shooting (worst "
            + ("-" if worst is None else f"{worst:.2%}") + "); each node's run is the "
            "truth's (its numerical part as a single bead's schedule)")),
        "quadrature": _quadrature_part(quad),
        **parts,
    }
    heating = ("" if req.heating is None else
               f" Every heating follows the protocol ({'; '.join(req.heating.texts)}) from "
               f"T_start, then holds at its last temperature.")
    note = (f"A batch ({sizes.spec.describe()}): each size is its own full-solver run of the "
            f"protocol in its own time (tau ~ R^2, at its own interfacial length), its fluid "
            f"weighted by R^3; the actuation times (in the number-weighted mean bead's tau, "
            f"{ref:.4g} um dry, tau = {tau:.4g} s) were shot on the summed release so that "
            f"each heating delivers its dose of the batch's stored fluid within "
            f"{req.tolerance:.0%}. Quadrature: {quad.rule}, {quad.nodes} nodes, error "
            f"{quad.error:.1e}. Volumes are fluid volumes." + heating)
    ans = BatchScheduleAnswer(
        model=MODEL, distribution=sizes.spec.to_dict(), description=sizes.spec.describe(),
        doses=list(req.doses), rests=list(req.rests), reference_dry_radius_um=ref,
        timescale_seconds=tau, nodes=_node_dicts(req, nodes, tau), hold=hold[1],
        hold_model=hold[0], protocol_check=checked, corrected=corrected, quadrature=quad,
        uncertainty=unc, truth=truth_text(req), note=note, t_start=req.t_start, t_end=req.t_end)
    ans.events = schedule_events(ans, req)
    return ans


def plan_batch_schedule(req: ScheduleRequest, size_distribution: Any,
                        cache_path: str | None = None, **planner_kw: Any) -> BatchScheduleAnswer:
    """One batch schedule with a throw-away planner (the cache persists; cf.
    ``dosing.plan_schedule``)."""
    from .. import planner as planner_module

    planner = planner_module.one_shot(cache_path, None, **planner_kw)
    try:
        return batch_schedule_with(planner, req, size_distribution)
    finally:
        planner.close()
        planner.jobs.executor.shutdown(wait=True)


__all__ = ["BatchHeatings", "BatchScheduleAnswer", "batch_schedule_with",
           "plan_batch_schedule", "reference_fields", "schedule_sizes"]


# ------------------------------------------------------------------ a drug batch's schedule
DRUG_MODEL = "full+solute-per-size"


def node_request(req: Any, node: Node) -> Any:
    """The drug schedule of one size node: the same drug, doses (fractions of its own load)
    and heating, its own bead size and interfacial length, the rests in its own tau."""
    from ..payload.cycles import DrugScheduleRequest

    if node.rho == 1.0:
        return req
    case = {**req.case_fields(), "dry_radius_um": node.radius_um, "settings": node.settings}
    return DrugScheduleRequest(**case, drug=req.drug, doses=req.fractions,
                               rests=[r / node.rho for r in req.rests], check_protocol=False,
                               correct=False, tolerance=req.tolerance)


def drug_batch_schedule_with(planner: SchedulePlanner, req: Any,
                             size_distribution: Any) -> BatchScheduleAnswer:
    """A batch's drug schedule: every size node its own drug run of the schedule (its own
    tau, interfacial length and solute), the batch's release the load-weighted sum (a
    bead's load ~ R^3: the volume weights), into a perfect sink; the reference bead's hold
    reading as the first guesses, shot on the lifted heatings (``shooting.NodeHeatings``)
    over the size rules as the fluid's (:func:`over_rules`)."""
    from ..payload.cycles import hold_reading
    from ..payload.release import DrugHeatings
    from ..runs.solute import runs_for

    sizes = schedule_sizes(req, size_distribution)
    ref = sizes.mean_um
    tau = timescale(ref, req.t_end, req.constants).seconds
    runs = runs_for(planner)
    hold_model, hold = hold_reading(planner, DrugHeatings(req, runs, req.fractions), tau)

    def lift(n: int) -> tuple[NodeHeatings, list[Node], str]:
        r, v, text = rule(sizes, n)
        nodes = nodes_of(req, r, v, ref)
        members = [Member(nd.weight, nd.rho, DrugHeatings(node_request(req, nd), runs,
                                                          req.fractions)) for nd in nodes]
        return NodeHeatings(members, req.fractions, req.tolerance), nodes, text

    def reading(h: NodeHeatings, d: Sequence[float]) -> dict[str, Any]:
        got = h.delivered(h.run(d), d)
        return {"actuation_times": list(d), "delivered_fractions": got, "relative_errors": [
            g / f - 1.0 for g, f in zip(got, req.fractions, strict=True)]}

    checked, corrected, quad, nodes = over_rules(
        req, sizes, lift, reading, [row.actuation_time for row in hold], req.fractions,
        "the batch's drug doses")
    with_seconds(tau, checked, corrected)
    worst = None if corrected is None else corrected["max_relative_error"]
    unc = {
        "numerical": Part(worst, (
            f"numerical: each drug dose met within the tolerance {req.tolerance:.0%} by the "
            "shooting (worst " + ("-" if worst is None else f"{worst:.2%}") + "); each node's "
            "drug run is the truth's mechanics with the solute on its cells")),
        "quadrature": _quadrature_part(quad),
        "interfacial_length_range": Part(None, (
            "interfacial length: not measured for a drug batch (a single bead's drug "
            "schedule states its numerical part; validate the fluid doses for the rest)")),
        "model_form": Part(None, "model form: not measured for a drug batch"),
    }
    heating = ("a jump to T_end" if req.heating is None else
               f"the protocol ({'; '.join(req.heating.texts)})")
    note = (f"A batch ({sizes.spec.describe()}) of drug-loaded beads releasing into a perfect "
            f"sink: each size is its own drug run of the schedule in its own time (tau ~ R^2, "
            f"its own interfacial length), every heating {heating}; doses are fractions of "
            f"the batch's load (a bead's load ~ R^3), times in the number-weighted mean "
            f"bead's tau ({ref:.4g} um dry, tau = {tau:.4g} s). The hold reading is the "
            f"reference bead's ({hold_model}).")
    ans = BatchScheduleAnswer(
        model=DRUG_MODEL, distribution=sizes.spec.to_dict(),
        description=sizes.spec.describe(), doses=list(req.fractions), rests=list(req.rests),
        reference_dry_radius_um=ref, timescale_seconds=tau,
        nodes=_node_dicts(req, nodes, tau), hold=hold, hold_model=hold_model,
        protocol_check=checked, corrected=corrected, quadrature=quad, uncertainty=unc,
        truth=truth_text(req), note=note, t_start=req.t_start, t_end=req.t_end)
    ans.events = schedule_events(ans, req)
    return ans
