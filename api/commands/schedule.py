"""``thermogel schedule``: actuation times for several doses with rests between them."""

from __future__ import annotations

import argparse
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
    add_batch_options,
    add_planning_options,
    batch_distribution,
    planning_kwargs,
    planning_values,
)
from .drug_cli import add_wait_options, run_drug_schedule
from .drug_options import add_drug_options, drug_from_args


def register(sub: argparse._SubParsersAction) -> None:
    """Add the sub-command."""
    p = sub.add_parser("schedule", help="multi-dose schedule: hold times, protocol check, "
                                        "corrected times")
    add_planning_options(p)
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
    p.add_argument("--plot", default=None, metavar="PNG",
                   help="with a drug: cumulative drug through the corrected protocol")
    add_drug_options(p)
    add_wait_options(p)
    add_batch_options(p)
    p.set_defaults(func=run)


def schedule_kwargs(args: argparse.Namespace) -> dict[str, Any]:
    """The ScheduleCase fields (dosing.request) of the options, fluid or drug."""
    return dict(rests=args.rests, rests_seconds=args.rests_seconds,
                check_protocol=not args.no_check, correct=not args.no_correct,
                tolerance=args.tolerance, **planning_kwargs(args))


FLUID_ROWS = (("  delivered (fraction of stored)", "delivered_fractions", "{:.4g}"),
              ("  relative error", "relative_errors", "{:+.2%}"))
DRUG_ROWS = (("  drug delivered (of the load)", "delivered_fractions", "{:.4g}"),
             ("  ... squeezed out", "squeezed_fractions", "{:.4g}"),
             ("  fluid delivered (of stored)", "fluid_fractions", "{:.4g}"),
             ("  leaked in each rest", "rest_leak_fractions", "{:.4g}"))


def run(args: argparse.Namespace) -> int:
    """Print the schedule, of fluid or (with a drug option or --doses-ug) of drug."""
    from api.schemas import ScheduleRequest as HttpSchedule
    from dosing import ScheduleRequest, plan_schedule

    check_bounds(HttpSchedule, {**planning_values(args), "doses": args.doses,
                                "rests": args.rests, "rests_seconds": args.rests_seconds,
                                "tolerance": args.tolerance}, partial=args.doses is None)
    checked_cache(args.cache)
    drug = drug_from_args(args, always=args.doses_ug is not None)
    for flag, value in (("--medium-volume-ml", args.medium_volume_ml),
                        ("--bead-count", args.bead_count)):
        if value is not None:
            raise ParameterError(flag, value, "absent with a schedule (a shared medium is a "
                                 "drug batch's dose: thermogel dose)")
    dist = batch_distribution(args)
    if dist is not None:  # a batch (issue 26; api/commands/batch_cli.py)
        if drug is not None:
            raise ParameterError("--size-cv" if args.size_cv is not None else "--sizes",
                                 args.size_cv if args.size_cv is not None else args.sizes,
                                 "absent with a drug (a drug batch's schedule is not built "
                                 "yet)")
        from .batch_cli import run_batch_schedule

        return run_batch_schedule(args, schedule_kwargs(args), dist)
    if drug is None and args.plot:
        raise ParameterError("plot", args.plot, "used with a drug option (e.g. "
                             "--drug-diffusivity-cm2-s)")
    if drug is None:
        req = ScheduleRequest(doses=args.doses, **schedule_kwargs(args))
        ans = plan_schedule(req, cache_path=args.cache)
    else:
        req, ans = run_drug_schedule(args, drug, schedule_kwargs(args))
    if args.json:
        print_json(ans.to_dict())
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
