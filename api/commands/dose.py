"""``thermogel dose``: how long to heat a bead to release a dose (sec. Application)."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from dosing.runs.scenario import GRIDS, METHODS
from solver.errors import ParameterError

from .common import (
    add_at_start_options,
    add_gel_options,
    check_bounds,
    checked_cache,
    gel_bounds,
    gel_from_args,
    print_json,
    print_uncertainty,
    wrap,
)
from .constants_options import add_constants_options, constants_from_args, constants_values
from .drug_options import add_drug_options, drug_from_args
from .outfile import add_format_option, figure_path


def add_planning_options(p: argparse.ArgumentParser) -> None:
    """Jump, bead size, timescale constants, solver settings and cache options."""
    add_gel_options(p)
    p.add_argument("--t-start", type=float, required=True, help="start temperature in K")
    p.add_argument("--t-end", type=float, required=True, help="heating temperature in K")
    p.add_argument("--branch", choices=["swollen", "shrunken"], default=None,
                   help="start branch at T_start (default swollen)")
    size = p.add_mutually_exclusive_group()
    size.add_argument("--dry-radius-um", type=float, default=None, help="dry bead radius in um")
    size.add_argument("--swollen-radius-um", type=float, default=None,
                      help="bead radius in um, swollen at T_start")
    add_constants_options(p.add_argument_group("timescale constants (eq. timescale)"))
    s = p.add_argument_group("full solver (validation truth)")
    s.add_argument("--validation-method", choices=list(METHODS), default="direct",
                   help="'direct' (default): the regularized model at ell itself on the "
                        "moving grid (N and N/2 cells); 'ladder': its limit ell -> 0 from "
                        "uniform runs at L, L/2, L/4")
    s.add_argument("--interfacial-length", type=float, default=None, metavar="L",
                   help="interfacial length ell in dry radii (default: the bead's own, "
                        "xi_dry / a_d, or 1e-4 for the limit without a bead size; ladder: "
                        "0.005, 0.0025-0.01); 0 = the paper's model, checked on both grids")
    s.add_argument("--grid", choices=list(GRIDS), default=None,
                   help="truth grid (default moving; ladder: lagrangian; eulerian, the "
                        "paper's, with --interfacial-length 0)")
    s.add_argument("--n", type=int, default=None,
                   help="grid cells of the (coarsest) run (default 400; ladder: 4/L)")
    p.add_argument("--cache", default=None,
                   help="validation cache file (default $THERMOGEL_CACHE or "
                        "~/.cache/thermogel/validations.sqlite)")
    p.add_argument("--json", action="store_true", help="print one JSON object")


def planning_values(args: argparse.Namespace) -> dict[str, Any]:
    """The options ``dose`` and ``schedule`` share, as HTTP request fields (for bounds)."""
    return {"gel": gel_bounds(args), "t_start": args.t_start, "t_end": args.t_end,
            "branch": args.branch, "dry_radius_um": args.dry_radius_um,
            "swollen_radius_um": args.swollen_radius_um,
            "constants": constants_values(args)}
    # --interfacial-length is left to SolverSettings: with --n (which HTTP does not offer)
    # its valid range moves with the grid


def planning_kwargs(args: argparse.Namespace) -> dict[str, Any]:
    """Request keyword arguments shared by ``dose`` and ``schedule``."""
    from dosing import SolverSettings

    return {"gel": gel_from_args(args), "t_start": args.t_start, "t_end": args.t_end,
            "branch": args.branch, "dry_radius_um": args.dry_radius_um,
            "swollen_radius_um": args.swollen_radius_um,
            "constants": constants_from_args(args),
            "settings": SolverSettings(grid=args.grid, n=args.n,
                                       interfacial_length=args.interfacial_length,
                                       method=args.validation_method)}


def register(sub: argparse._SubParsersAction) -> None:
    """Add the sub-command."""
    p = sub.add_parser("dose", help="actuation time to release a dose")
    add_planning_options(p)
    add_protocol_option(p, "the answer is the time from the protocol's start")
    d = p.add_mutually_exclusive_group(required=True)
    d.add_argument("--fraction", type=float, help="dose as a fraction of the stored fluid "
                   "(with a drug option: of the loaded drug)")
    d.add_argument("--volume-ul", type=float, help="dose volume in uL (needs a bead size)")
    d.add_argument("--drug-mass-ug", type=float,
                   help="drug mass in ug (needs --concentration-ug-per-ul and a bead size)")
    p.add_argument("--concentration-ug-per-ul", type=float, default=None,
                   help="drug concentration of the loaded fluid in ug/uL")
    p.add_argument("--validate", action="store_true",
                   help="also run the full solver's validation runs (blocking, cached)")
    p.add_argument("--plot", default=None, metavar="PNG",
                   help="with --validate: draw the validation (dose time against ell with "
                        "its bounds, the model-form bound and the answer) to this file "
                        "(needs matplotlib)")
    add_explain_option(p)
    add_format_option(p)
    add_batch_options(p)
    add_drug_options(p)
    add_wait_options(p)
    p.set_defaults(func=run)


def add_explain_option(p: argparse.ArgumentParser) -> None:
    """--explain: the parts, the model and the runs behind the three lines."""
    p.add_argument("--explain", action="store_true",
                   help="after the answer, its envelope and how to pin it: every "
                        "uncertainty part, the model, the truth and the runs")


def print_lead(result: Any, what: str, explain: bool) -> None:
    """The three lines every text answer leads with (the answer with its envelope, the
    dominant part, how to pin it); with ``explain`` every part in words after them."""
    env = getattr(result, "envelope", None)
    if env is None:
        return
    for line in env.lines(what):
        print(line)
    if explain:
        print("uncertainty parts (the envelope is the point times their factors):")
        for part in env.parts:
            tag = "" if part.counted else " (listed, not in the envelope)"
            print(wrap(f"  {part.name} x{part.factor:.3g}{tag}: {part.text}"))
    print("the point answer:")


def add_protocol_option(p: argparse.ArgumentParser, what: str) -> None:
    """--protocol in place of --t-end (repeatable; the step grammar of dosing.heating.grammar)."""
    for action in p._actions:  # --protocol stands in for --t-end (checked in run)
        if action.dest == "t_end":
            action.required = False
            action.help = "heating temperature in K (or give --protocol)"
    p.add_argument("--protocol", action="append", default=None, metavar="STEP",
                   help="a heating step in place of --t-end, repeatable, or several joined "
                        "by ';' ('Heat to 308 K at 5 K/min', 'Hold at 308 K until 30 %% "
                        "released', 'Rest at 302 K for 10 min', 'Bath at 308 K with a time "
                        f"constant of 30 s', 'Trace from run.csv'; docs/heating.md): {what}")


def add_batch_options(p: argparse.ArgumentParser) -> None:
    """A batch of beads (issue 26, docs/batch.md): a size spread or a measured table."""
    b = p.add_argument_group("a batch of beads (docs/batch.md)")
    sz = b.add_mutually_exclusive_group()
    sz.add_argument("--size-cv", type=float, default=None, metavar="CV",
                    help="the batch's coefficient of variation of size, 0-2; --dry-radius-um "
                         "(--swollen-radius-um) is its number-weighted mean")
    sz.add_argument("--sizes", default=None, metavar="FILE.csv",
                    help="a measured table: a column of radii or diameters (the header says "
                         "which and its unit, e.g. 'diameter (um)'; none: radii in um), "
                         "optionally a column of counts")
    b.add_argument("--size-kind", choices=["lognormal", "normal"], default="lognormal",
                   help="the law with --size-cv (default lognormal)")
    b.add_argument("--size-weighting", choices=["number", "volume"], default="number",
                   help="the sizes are number- (default) or volume-weighted (--sizes; with "
                        "--size-cv the mean is always by number)")
    b.add_argument("--medium-volume-ml", default=None, metavar="ML",
                   help="with a drug: the release medium the batch shares, in mL (or with a "
                        "unit, '250 uL'); default a perfect sink")
    b.add_argument("--bead-count", type=float, default=None, metavar="N",
                   help="with --medium-volume-ml: the number of beads in the batch")


def batch_distribution(args: argparse.Namespace) -> Any:
    """The size distribution the batch options give (None: a single bead)."""
    from dosing.population.sizes import SizeDistribution, read_sizes_csv

    state = "swollen" if args.swollen_radius_um is not None else "dry"
    if args.sizes is not None:
        try:
            # the column's header says dry or swollen; --swollen-radius-um says swollen
            return read_sizes_csv(args.sizes, "--sizes", weighting=args.size_weighting,
                                  state="swollen" if state == "swollen" else None)
        except ParameterError as exc:
            if exc.field.startswith("--sizes"):
                raise
            raise ParameterError(f"--sizes ({exc.field})", exc.value, exc.valid) from None
    if args.size_cv is None:
        return None
    try:
        return SizeDistribution(kind=args.size_kind, cv=args.size_cv, state=state)
    except ParameterError as exc:
        raise ParameterError("--size-cv", args.size_cv, exc.valid) from None


def print_batch(b: Any) -> None:
    """The batch's answer in words."""
    secs = "" if b.seconds is None else f" = {b.seconds:.4g} s"
    print(f"  batch ({b.description}): heat for t = {b.time:.4g}{secs} "
          f"({b.delay:+.1%} against the number-weighted mean bead, "
          f"{b.reference_dry_radius_um:.4g} um dry)")
    p10, _, p90 = b.percentile_seconds or b.percentile_times
    unit = " s" if b.percentile_seconds else ""
    print(f"  {b.fraction_delivered:.0%} of the beads have delivered their own dose by then; "
          f"the 10th-90th percentile bead's own time {p10:.4g}-{p90:.4g}{unit}")
    q = b.quadrature
    print(f"  quadrature: {q.rule}; {q.nodes} nodes, error {q.error:.1e}")
    for part in (b.uncertainty or {}).values():
        if hasattr(part, "text"):  # a part, or the nodes' split (not the bands' list)
            print(wrap(part.text))


def request_from_args(args: argparse.Namespace, question: Any, steps: list[str] | None,
                      drug: Any) -> Any:
    """The one request (dosing.question.Request) the options ask: the case, the payload
    (a drug option: a drug), the population (--size-cv / --sizes: a batch), the heating
    (--protocol or --t-end) and ``question``."""
    from dosing.question import Batch, Drug, Fluid, Heating, Jump, OneBead, Request

    case = planning_kwargs(args)
    dist = batch_distribution(args)
    payload = Fluid() if drug is None else Drug(
        drug, wait=getattr(args, "wait", None), wait_seconds=getattr(args, "wait_seconds", None),
        medium_volume_ml=getattr(args, "medium_volume_ml", None),
        bead_count=getattr(args, "bead_count", None))
    flags = {"size_distribution": "--size-cv" if args.size_cv is not None else "--sizes",
             "protocol": "--protocol"}
    try:
        return Request(**{k: v for k, v in case.items() if k != "t_end"},
                       heating=Jump(args.t_end) if steps is None else Heating(steps),
                       question=question, payload=payload,
                       population=OneBead() if dist is None else Batch(dist),
                       validate=bool(getattr(args, "validate", False)))
    except ParameterError as exc:  # the cell's own refusal names the option that chose it
        if exc.field not in flags:
            raise
        raise ParameterError(flags[exc.field], exc.value, exc.valid) from None


def run(args: argparse.Namespace) -> int:
    """Print the answer, whatever its cell (one request, dosing.question)."""
    from api.schemas import DoseTimeRequest
    from dosing.question import Dose, run

    steps = protocol_steps(args)
    check_bounds(DoseTimeRequest, {
        **planning_values(args), "protocol": steps, "dose_fraction": args.fraction,
        "dose_volume_ul": args.volume_ul, "drug_mass_ug": args.drug_mass_ug,
        "concentration_ug_per_ul": args.concentration_ug_per_ul})
    checked_cache(args.cache)
    drug = drug_from_args(args)
    batch = args.size_cv is not None or args.sizes is not None
    for flag, value in (("--medium-volume-ml", args.medium_volume_ml),
                        ("--bead-count", args.bead_count)):
        if value is not None and (drug is None or not batch):
            raise ParameterError(flag, value, "with a drug option and --size-cv or --sizes "
                                 "(the medium a drug batch shares)")
    if drug is not None and batch and args.fraction is None:
        raise ParameterError("--fraction", None, "a fraction of the batch's load, 0-1")
    if args.plot and not args.validate:
        raise ParameterError("plot", args.plot, "used with --validate")
    if args.plot and drug is not None:
        raise ParameterError("plot", args.plot, "used with a fluid dose (the figure is the "
                             "fluid answer's validation; a drug answer states its parts in "
                             "--explain)")
    request = request_from_args(args, Dose(
        fraction=args.fraction, volume_ul=args.volume_ul, drug_mass_ug=args.drug_mass_ug,
        concentration_ug_per_ul=args.concentration_ug_per_ul), steps, drug)
    s = request.planned.settings
    if steps is not None:
        print(f"planning the protocol dose: the reduced model inside its region, else the "
              f"full solver ({s.grid} grid, {s.n} cells and {s.n // 2}): seconds to minutes "
              "the first time, then cached", file=sys.stderr, flush=True)
    elif args.validate:
        runs = ", ".join(f"ell = {r.interfacial_length:.3g} N = {r.n}" if r.regularized
                         else f"{r.grid} N = {r.n}" for r in s.rungs())
        print(f"validating with the full solver ({runs}): seconds to minutes the first "
              "time, then cached", file=sys.stderr, flush=True)
    planner = _planner(args)
    try:
        result = run(planner, request)
    finally:
        close_planner(planner)
    if args.plot:
        from api.plots.validation import draw_validation

        path = figure_path(args.plot, args.format)
        try:
            print(f"wrote {draw_validation(result.answer.to_dict(), path)}", file=sys.stderr)
        except ValueError as exc:  # no regularized validation (the paper's model)
            raise ParameterError("plot", args.plot, "a dose with a regularized validation",
                                 str(exc)) from None
    if args.json:
        print_json(result.to_dict())
        return 0
    what = f"{_dose_words(request)} after"  # the lead: '80% of the bead's fluid after ...'
    print_lead(result, what, args.explain)
    if result.batch is not None:  # the batch's own time first: the answer asked for
        print(result.headline)
    if result.answer is None:  # a drug batch: its answer is the batch's
        print_drug_batch(request.planned, result.batch)
        return 0
    print_dose(request.planned, result.answer, result.batch)
    return 0


def _dose_words(request: Any) -> str:
    """'80 % of the fluid' / 'the dose' for the lead line."""
    q, p = request.question, request.payload
    who = f" of {'the batch' if request.population.key == 'batch' else 'the bead'}'s {p.key}"
    return (f"{q.fraction:.0%}{who}" if getattr(q, "fraction", None) is not None
            else "the dose")


def protocol_steps(args: argparse.Namespace) -> list[str] | None:
    """The --protocol steps (each option one step, or several joined by ';'), or None;
    --t-end is required without them and refused with them."""
    if not getattr(args, "protocol", None):
        if args.t_end is None:
            raise ParameterError("--t-end", None, "a temperature in K (or give --protocol)")
        return None
    if args.t_end is not None:
        raise ParameterError("--t-end", args.t_end, "absent with --protocol (the protocol's "
                             "steps set the heating)")
    return [s.strip() for arg in args.protocol for s in arg.split(";") if s.strip()]


def print_dose(req: Any, ans: Any, batch: Any = None) -> None:
    """One printer for a dose's answer (as ``thermogel schedule`` has one for a schedule):
    fluid, or drug (its payload: the wait, the leak, how the drug came out), after a jump or
    under a protocol; the parts an answer does not have are left out."""
    drug = hasattr(ans, "mechanism")
    steps, at_dose = _heating(ans)
    secs = "" if ans.seconds is None else f" = {ans.seconds:.4g} s"
    if steps is None:
        heat = f"{req.t_start:g} K -> {req.t_end:g} K"
        when = f"heat for t = {ans.time:.4g} (dimensionless){secs}"
    else:
        heat = f"from {req.t_start:g} K under {'; '.join(steps)}"
        when = f"t = {ans.time:.4g} tau{secs} from the protocol's start (at {at_dose:.4g} K)"
    if drug:
        what = "the loaded drug" + ("" if ans.dose_ug is None else f" = {ans.dose_ug:.4g} ug")
        when += "" if steps is not None else f", after waiting {ans.wait:.4g} at T_start"
    else:
        what = (f"the stored fluid (radius {ans.start_radius:.4g} -> {ans.final_radius:.4g} "
                "dry radii)")
    print(f"{req.gel.name} {heat}: release {ans.dose_fraction:.1%} of {what}")
    mean = "" if batch is None else " (the batch's number-weighted mean bead)"
    print(f"  {ans.model} model{mean}: {when}")
    for u in getattr(ans, "until_steps", None) or ():
        end = "" if u.end_seconds is None else f" = {u.end_seconds:.4g} s"
        print(f"  step {u.step} '{u.text}' ends at t = {u.end:.4g} tau{end}")
    if getattr(ans, "model_reason", ""):
        print(wrap(f"model: {ans.model}, {ans.model_reason}"))
    print(wrap(f"truth{' of the drug runs' if drug else ''}: {ans.truth}"))
    if getattr(ans, "program", ""):
        print(wrap(f"program: {ans.program}"))
    (_print_drug if drug else _print_fluid)(ans)
    print_uncertainty(ans.uncertainty, "the drug dose time" if drug else "the truth")
    if drug:
        print(wrap(ans.note))
    runs = getattr(getattr(ans, "validation", None), "runs", None)
    if runs:
        print(wrap("full solver: " + ", ".join(
            f"{e['grid']} N={e['n']} ell={e['interfacial_length']:g}: "
            + (f"{e['time']:.5g}" if "time" in e else "failed") for e in runs)))
    if batch is not None:
        print_batch(batch)


def _heating(ans: Any) -> tuple[list[str] | None, float | None]:
    """A dose answer's protocol steps and its temperature at the dose (None: a jump)."""
    p = getattr(ans, "protocol", None)
    if p is None:
        return None, None
    if isinstance(p, list):  # a fluid dose (dosing.heating.response.ProtocolDoseAnswer)
        return p, ans.temperature_at_dose
    return list(p.steps), p.temperature_at_dose  # a drug dose's (ProtocolDrugDose)


def _print_fluid(ans: Any) -> None:
    """The fluid payload: volumes, tau and the error estimate."""
    if ans.expelled_volume_ul is not None:
        print(f"  expels {ans.expelled_volume_ul:.4g} uL of {ans.stored_volume_ul:.4g} uL "
              f"stored; final radius {ans.final_radius_um:.4g} um")
    if getattr(ans, "reference", ""):
        print(wrap(ans.reference))
    if ans.timescale_formula:
        print(wrap(ans.timescale_formula))
    tu = getattr(ans, "timescale_uncertainty", None)
    if tu and ans.seconds is not None:
        lo, hi = tu["seconds_range"]
        print(wrap(("calibrated" if tu["calibrated"] else "UNCALIBRATED")
                   + f" seconds: {lo:.3g}-{hi:.3g} s over "
                   + ("the kinetics fit's 95% interval of D" if tu["calibrated"] else
                      f"the timescale constants' range (a factor {tu['factor']:.3g}); "
                      + tu["how_to_pin"])))
    if ans.error_estimate is not None:
        print(f"  error estimate {ans.error_estimate:.1%}:")
    print(wrap(ans.error_explanation))


def _print_drug(ans: Any) -> None:
    """The drug payload: the leak before heating, how the drug came out, the mesh."""
    print(f"  leaked before heating: {ans.leaked_before_heating:.4g} of the load; at T_start "
          f"the bead leaks 10% in {ans.leak_time_10pct:.4g} tau"
          + ("" if ans.leak_time_10pct_seconds is None
             else f" ({ans.leak_time_10pct_seconds:.4g} s)"))
    print(f"  mechanism: {ans.mechanism}; fluid expelled meanwhile {ans.fluid_fraction:.4g} of "
          f"the stored fluid; D_eff = {ans.effective_diffusivity_cm2_s:.3g} cm^2/s")
    for text in (ans.split, ans.mesh):
        if text:
            print(wrap(f"  {text}"))
    if ans.medium_concentration_ug_per_ul is not None:
        print(f"  release medium concentration {ans.medium_concentration_ug_per_ul:.4g} ug/uL")


def add_wait_options(p: argparse.ArgumentParser) -> None:
    """Time in the medium at T_start before the first heating (drug doses)."""
    add_at_start_options(p, "wait", "with a drug: time at T_start before heating (default 0)",
                         drug_only=True)


def _planner(args: argparse.Namespace) -> Any:
    """The command's one-shot planner (``dosing.planner.one_shot``: runs in this process; its
    executor stops with it, :func:`close_planner`)."""
    import dosing.planner

    return dosing.planner.one_shot(args.cache, None)


def close_planner(planner: Any) -> None:
    """Close the one-shot planner and stop its executor."""
    planner.close()
    planner.jobs.executor.shutdown(wait=True)


def print_drug_batch(req: Any, ans: Any) -> None:
    """A batch's drug dose into a shared medium (or a perfect sink), in words."""
    secs = "" if ans.seconds is None else f" = {ans.seconds:.4g} s"
    print(f"{req.gel.name} {req.t_start:g} K -> {req.t_end:g} K: a batch ({ans.description}) "
          f"releases {ans.dose_fraction:.1%} of its drug")
    print(f"  {ans.model}: heat for t = {ans.time:.4g} (reference tau){secs}")
    if ans.medium_volume_ml is not None:
        print(f"  medium {ans.medium_volume_ml:.4g} mL for {ans.bead_count:.4g} beads "
              f"({ans.medium_over_pore_volume:.3g}x their partition-weighted pore volume): "
              f"the perfect-sink sum says {ans.sink_time:.4g} and overstates the release at "
              f"the dose time by {ans.sink_overestimate:.1%}")
    if ans.medium_concentration_ug_per_ul is not None:
        print(f"  medium concentration at the dose {ans.medium_concentration_ug_per_ul:.4g} "
              "ug/uL")
    print(f"  errors: numerical {ans.numerical_error:.1e} (steps halved), quadrature "
          f"{ans.quadrature_error:.1e} ({ans.classes} size classes against twice as many); "
          f"mass balance {ans.mass_balance_error:.1e}")
    print(wrap(ans.note))
