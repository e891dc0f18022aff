"""``thermogel front``: the step-function front model a(t), R_f(t) after a shrinking jump."""

from __future__ import annotations

import argparse

from solver.errors import ParameterError, SolverError
from solver.front import front_trajectory
from solver.front.sharp import sharp_front_trajectory

from .common import add_gel_options, gel_from_args, print_json


def register(sub: argparse._SubParsersAction) -> None:
    """Add the sub-command."""
    p = sub.add_parser("front", help="reduced core-shell front model: radius and front in time")
    add_gel_options(p)
    p.add_argument("--t-start", type=float, required=True, help="start temperature in K")
    p.add_argument("--t-end", type=float, required=True, help="end temperature in K")
    p.add_argument("--branch", choices=["swollen", "shrunken"], default=None,
                   help="start branch (default: swollen when heating)")
    p.add_argument("--start-from-full", type=float, default=None, metavar="T0",
                   help="start from the full solver's (a, R_f) at dimensionless time T0 "
                        "(default: from the initial equilibrium alone)")
    p.add_argument("--paper-start", action="store_true",
                   help="with --paper and --start-from-full: keep the measured R_f as the paper "
                        "did (default: R_f from solid conservation)")
    model = p.add_mutually_exclusive_group()
    model.add_argument("--sharp", dest="paper", action="store_false",
                       help="the front condition of the sharp-interface limit of the well-posed "
                            "model (front-sharp, docs/interfacial.md sec. 8): the default, as "
                            "in the planner")
    model.add_argument("--paper", dest="paper", action="store_true",
                       help="the paper's own front condition (front-leading; its full model "
                            "without interfacial energy is ill-posed)")
    p.set_defaults(paper=False)
    p.add_argument("--until", type=float, default=None, help="stop at this dimensionless time")
    p.add_argument("--target-radius", type=float, default=None,
                   help="stop when the radius reaches this value")
    p.add_argument("--every", type=float, default=None, metavar="DT",
                   help="sample spacing in dimensionless time (default: 201 samples)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def _full_start(args: argparse.Namespace, gel: object) -> tuple[float, float, float]:
    """(t0, a, R_f) from the full solver at --start-from-full (Eulerian grid, N = 400)."""
    try:
        from solver.full import simulate
    except ImportError as exc:
        raise SolverError(f"--start-from-full needs the full solver: {exc}") from exc
    t0 = args.start_from_full
    full = simulate(gel, args.t_start, args.t_end, until=t0, grid="eulerian", n=400)
    a, rf, _ = full.state_at(t0)
    return t0, a, rf


def run(args: argparse.Namespace) -> int:
    """Print the trajectory (JSON: the series t, radius, front, flux and diagnostics)."""
    gel = gel_from_args(args)
    if not args.paper and args.paper_start:
        raise ParameterError("paper_start", True,
                             "only with --paper (the sharp model starts conservatively)")
    start = _full_start(args, gel) if args.start_from_full is not None else None
    common = dict(branch=args.branch, start=start, until=args.until,
                  target_radius=args.target_radius, every=args.every)
    if not args.paper:
        res = sharp_front_trajectory(gel, args.t_start, args.t_end, **common)
    else:
        res = front_trajectory(gel, args.t_start, args.t_end, conservative=not args.paper_start,
                               **common)
    if args.json:
        print_json({"gel": gel.to_dict(), "t_start": args.t_start, "t_end": args.t_end,
                    **res.to_json_dict()})
        return 0
    d = res.diagnostics
    print(f"{gel.name} {args.t_start:g} K -> {args.t_end:g} K: {d['behaviour']} "
          f"({res.model}, start {res.start})")
    print(f"  phi_- = {res.phi_minus:.5f}, phi_+ = {res.phi_plus:.5f}; front at the centre "
          f"at t = {d['t_centre']:.5g} with radius {d['radius_centre']:.5g}")
    print(f"  {'t':>10} {'radius':>10} {'front':>10}")
    for t, a, x in zip(res.t, res.radius, res.front, strict=True):
        print(f"  {t:10.5f} {a:10.5f} {x:10.5f}")
    return 0
