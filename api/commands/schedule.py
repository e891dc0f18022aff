"""``thermogel schedule``: actuation times for several doses with rests between them."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from solver.errors import ParameterError

from .common import (
    add_at_start_options,
    check_bounds,
    checked_cache,
    print_json,
    print_uncertainty,
    table_row,
    wrap,
)
from .dose import (
    _planner,
    add_batch_options,
    add_explain_option,
    add_planning_options,
    add_protocol_option,
    add_wait_options,
    close_planner,
    planning_values,
    print_lead,
    protocol_steps,
    request_from_args,
)
from .drug_options import add_drug_options, drug_from_args


def register(sub: argparse._SubParsersAction) -> None:
    """Add the sub-command."""
    p = sub.add_parser("schedule", help="multi-dose schedule: hold times, protocol check, "
                                        "corrected times")
    add_planning_options(p)
    add_protocol_option(p, "every heating follows the protocol's steps from T_start, then "
                           "holds at its last temperature until its actuation time ends")
    dd = p.add_mutually_exclusive_group(required=True)
    dd.add_argument("--doses", type=float, nargs="+",
                    help="doses as fractions of the stored fluid, e.g. 0.3 0.3 0.3 (with a "
                         "drug option: of the loaded drug)")
    dd.add_argument("--doses-ug", type=float, nargs="+",
                    help="with a drug: doses in ug (needs --load-ug)")
    add_at_start_options(p, "rests", "rests at T_start between doses (one fewer than doses)",
                         many=True)
    p.add_argument("--no-check", action="store_true",
                   help="skip the full-solver simulation of the protocol")
    p.add_argument("--no-correct", action="store_true",
                   help="skip the corrected (shooting) schedule")
    p.add_argument("--tolerance", type=float, default=0.01,
                   help="relative tolerance of each dose in the corrected schedule (0.01)")
    p.add_argument("--out", default=None, metavar="FILE.csv|.nc",
                   help="write the schedule's events (one row per step: heat, rest; the "
                        "corrected times when corrected) as tidy CSV or netCDF, with units "
                        "and provenance")
    p.add_argument("--plot", default=None, metavar="PNG",
                   help="with a drug: cumulative drug through the corrected protocol")
    add_drug_options(p)
    add_wait_options(p)
    add_batch_options(p)
    add_explain_option(p)
    p.set_defaults(func=run)


FLUID_ROWS = (("  delivered (fraction of stored)", "delivered_fractions", "{:.4g}"),
              ("  relative error", "relative_errors", "{:+.2%}"))
DRUG_ROWS = (("  drug delivered (of the load)", "delivered_fractions", "{:.4g}"),
             ("  ... squeezed out", "squeezed_fractions", "{:.4g}"),
             ("  fluid delivered (of stored)", "fluid_fractions", "{:.4g}"),
             ("  leaked in each rest", "rest_leak_fractions", "{:.4g}"))


def run(args: argparse.Namespace) -> int:
    """Print the schedule, whatever its cell: of fluid or (with a drug option or
    --doses-ug) of drug, one bead or a batch, after a jump or under --protocol."""
    from api.schemas import ScheduleRequest as HttpSchedule
    from dosing.question import Schedule, run

    steps = protocol_steps(args)
    check_bounds(HttpSchedule, {**planning_values(args), "protocol": steps,
                                "doses": args.doses, "rests": args.rests,
                                "rests_seconds": args.rests_seconds,
                                "tolerance": args.tolerance}, partial=args.doses is None)
    checked_cache(args.cache)
    drug = drug_from_args(args, always=args.doses_ug is not None)
    for flag, value in (("--medium-volume-ml", args.medium_volume_ml),
                        ("--bead-count", args.bead_count)):
        if value is not None:
            raise ParameterError(flag, value, "absent with a schedule (a shared medium is a "
                                 "drug batch's dose: thermogel dose)")
    if drug is None and args.plot:
        raise ParameterError("plot", args.plot, "used with a drug option (e.g. "
                             "--drug-diffusivity-cm2-s)")
    if args.out is not None and Path(args.out).suffix not in (".csv", ".nc"):
        raise ParameterError("--out", args.out, "a file ending in .csv or .nc")
    request = request_from_args(args, Schedule(
        doses=args.doses, doses_ug=args.doses_ug, rests=args.rests,
        rests_seconds=args.rests_seconds, check_protocol=not args.no_check,
        correct=not args.no_correct, tolerance=args.tolerance), steps, drug)
    planner = _planner(args)
    try:
        result = run(planner, request)
        if args.plot:
            _plot(planner, request.planned, result.answer, args.plot)
    finally:
        close_planner(planner)
    req, ans = request.planned, result.answer
    if args.out is not None:
        wrote = write_events(result, args)
        if not args.json:
            print(f"wrote {wrote}")
    if args.json:
        print_json(result.to_dict())
        return 0
    print_lead(result, f"heat for ({result.reading} times)", args.explain)
    print(result.headline)
    print_events(result.events)
    if hasattr(ans, "nodes"):  # a batch's schedule: its nodes and quadrature
        print_batch_schedule(req, ans)
        return 0
    doses = (f"drug doses {', '.join(f'{d:.3g}' for d in ans.doses)} of the load"
             if drug is not None else f"doses {', '.join(f'{d:.0%}' for d in ans.doses)}")
    print(f"{req.gel.name} {req.t_start:g} K -> {req.t_end:g} K, {doses}, rests "
          f"{', '.join(f'{r:.4g}' for r in ans.rests) or '-'} (dimensionless)")
    print(table_row(f"hold assumption ({ans.model}):", [h.actuation_time for h in ans.hold]))
    for name, res in (("protocol check", ans.protocol_check), ("corrected", ans.corrected)):
        if not res or not res.get("actuation_times"):
            continue
        print(table_row(f"{name}: actuation times", res["actuation_times"]))
        for label, key, fmt in FLUID_ROWS if drug is None else DRUG_ROWS:
            print(table_row(label, res[key] or [0.0], fmt))
        if res.get("actuation_seconds"):
            print(table_row("  actuation seconds", res["actuation_seconds"]))
    if drug is None:
        print(wrap(ans.timescale_formula))
    for w in getattr(ans, "warnings", ()):
        print(f"  WARNING: {w}")
    if ans.truth:
        print(wrap(f"truth of the {'drug' if drug is not None else 'protocol'} runs: "
                   f"{ans.truth}"))
    if drug is not None:
        print_uncertainty(ans.uncertainty, "the simulated schedule")
    print(wrap(ans.note))
    return 0


def print_events(events: list[dict[str, Any]]) -> None:
    """The events a controller or a lab notebook takes: one line per step."""
    if not events:
        return
    rough = " (ROUGH: the hold reading, not checked on the full solver)" if events[0]["rough"] \
        else ""
    print(f"events ({events[0]['reading']} times){rough}:")
    for e in events:
        start = "-" if e["start_s"] is None else f"{e['start_s']:.4g} s"
        dur = (f"{e['duration_tau']:.4g} tau" if e["duration_s"] is None
               else f"{e['duration_s']:.4g} s")
        dose = "-" if e["dose_fraction"] is None else f"{e['dose_fraction']:.4g}"
        print(f"  {e['step']:>2} {e['kind']:<4} at {start:>11} for {dur:>11} "
              f"at {e['temperature_K']:.5g} K  delivers {dose:>8}  released "
              f"{e['released_fraction']:.4g}" + (f"  [{e['program']}]" if e["program"] else ""))


def write_events(result: Any, args: argparse.Namespace) -> Path:
    """The answer's events (dosing.question.events) to ``args.out`` (.csv or .nc)."""
    from dosing.present import export

    from .outfile import request_of

    return export.save(result.to_xarray(request_of(args)), args.out)


def _plot(planner: Any, req: Any, ans: Any, path: str) -> None:
    """Cumulative drug through the corrected (else the checked) protocol."""
    from api.plots.release import draw_schedule_release
    from dosing.payload.release import DrugHeatings
    from dosing.runs.solute import runs_for

    res = ans.corrected if ans.corrected and ans.corrected.get("actuation_times") \
        else ans.protocol_check
    if not res:
        raise ParameterError("plot", path, "used with the protocol check or the correction")
    rel = DrugHeatings(req, runs_for(planner), req.fractions).run(res["actuation_times"])
    print(f"wrote {draw_schedule_release(ans.to_dict(), rel, path)}")


def print_batch_schedule(req: Any, ans: Any) -> None:
    """A batch's schedule (dosing.population.cycles) in words: its readings, nodes and errors."""
    print(f"{req.gel.name} {req.t_start:g} K -> {req.t_end:g} K, a batch ({ans.description}), "
          f"doses {', '.join(f'{d:.0%}' for d in ans.doses)} of its stored fluid, rests "
          f"{', '.join(f'{r:.4g}' for r in ans.rests) or '-'} (reference tau "
          f"{ans.timescale_seconds:.4g} s, {ans.reference_dry_radius_um:.4g} um dry)")
    print(table_row(f"hold ({ans.hold_model}):", [h.actuation_time for h in ans.hold]))
    for name, res in (("protocol check", ans.protocol_check), ("corrected", ans.corrected)):
        if not res:
            continue
        print(table_row(f"{name}: actuation times", res["actuation_times"]))
        print(table_row("  actuation seconds", res["actuation_seconds"]))
        print(table_row("  batch delivered (of stored)", res["delivered_fractions"]))
        print(table_row("  relative error", res["relative_errors"], "{:+.2%}"))
    print("  nodes (dry um, fluid share, ell): " + ", ".join(
        f"{n['dry_radius_um']:.4g} {n['volume_weight']:.3f} {n['interfacial_length']:.3g}"
        for n in ans.nodes))
    for part in ans.uncertainty.values():
        print(wrap(part.text))
    print(wrap(f"truth of each node's runs: {ans.truth}"))
    print(wrap(ans.note))
