"""``thermogel schedule``: actuation times for several doses with rests between them."""

from __future__ import annotations

import argparse

from .common import check_bounds, checked_cache, print_json
from .dose import _wrap, add_planning_options, planning_kwargs, planning_values


def register(sub: argparse._SubParsersAction) -> None:
    """Add the sub-command."""
    p = sub.add_parser("schedule", help="multi-dose schedule: hold times, protocol check, "
                                        "corrected times")
    add_planning_options(p)
    p.add_argument("--doses", type=float, nargs="+", required=True,
                   help="doses as fractions of the stored fluid, e.g. 0.3 0.3 0.3")
    r = p.add_mutually_exclusive_group()
    r.add_argument("--rests", type=float, nargs="*", default=None,
                   help="rests at T_start between doses, dimensionless (one fewer than doses)")
    r.add_argument("--rests-seconds", type=float, nargs="*", default=None,
                   help="rests in seconds (needs a bead size)")
    p.add_argument("--no-check", action="store_true",
                   help="skip the full-solver simulation of the protocol")
    p.add_argument("--no-correct", action="store_true",
                   help="skip the corrected (shooting) schedule")
    p.add_argument("--tolerance", type=float, default=0.01,
                   help="relative tolerance of each dose in the corrected schedule (0.01)")
    p.set_defaults(func=run)


def _row(label: str, values: list[float], fmt: str = "{:.4g}") -> str:
    return f"  {label:<34}" + "  ".join(fmt.format(v) for v in values)


def run(args: argparse.Namespace) -> int:
    """Print the schedule."""
    from api.schemas import ScheduleRequest as HttpSchedule
    from dosing import ScheduleRequest, plan_schedule

    check_bounds(HttpSchedule, {**planning_values(args), "doses": args.doses,
                                "rests": args.rests, "rests_seconds": args.rests_seconds,
                                "tolerance": args.tolerance})
    checked_cache(args.cache)
    rests = args.rests
    if rests is None and args.rests_seconds is None:
        rests = [0.0] * (len(args.doses) - 1)
    req = ScheduleRequest(doses=args.doses, rests=rests, rests_seconds=args.rests_seconds,
                          check_protocol=not args.no_check, correct=not args.no_correct,
                          tolerance=args.tolerance, **planning_kwargs(args))
    ans = plan_schedule(req, cache_path=args.cache)
    if args.json:
        print_json(ans.to_dict())
        return 0
    print(f"{req.gel.name} {req.t_start:g} K -> {req.t_end:g} K, doses "
          f"{', '.join(f'{d:.0%}' for d in ans.doses)}, rests "
          f"{', '.join(f'{r:.4g}' for r in ans.rests) or '-'} (dimensionless)")
    print(_row(f"hold assumption ({ans.model}):", [h["actuation_time"] for h in ans.hold]))
    for name, res in (("protocol check", ans.protocol_check), ("corrected", ans.corrected)):
        if res is None:
            continue
        print(_row(f"{name}: actuation times", res["actuation_times"]))
        print(_row("  delivered (fraction of stored)", res["delivered_fractions"]))
        print(_row("  relative error", res["relative_errors"], "{:+.2%}"))
        if res.get("actuation_seconds"):
            print(_row("  actuation seconds", res["actuation_seconds"]))
    print(_wrap(ans.timescale_formula))
    print(_wrap(ans.note))
    return 0
