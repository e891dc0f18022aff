"""``thermogel classify``: what a temperature jump does (smooth, front, delayed front, spinodal)."""

from __future__ import annotations

import argparse

from .common import add_gel_options, gel_from_args, print_json


def register(sub: argparse._SubParsersAction) -> None:
    """Add the sub-command."""
    p = sub.add_parser("classify", help="classify a temperature jump T_start -> T_end")
    add_gel_options(p)
    p.add_argument("--t-start", type=float, required=True, help="start temperature in K")
    p.add_argument("--t-end", type=float, required=True, help="end temperature in K")
    p.add_argument("--branch", choices=["swollen", "shrunken"], default=None,
                   help="start branch (default: swollen when heating, shrunken when cooling)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Print the classification."""
    from solver.phase import classify_jump

    c = classify_jump(gel_from_args(args), args.t_start, args.t_end, args.branch)
    if args.json:
        print_json(c.to_dict())
        return 0
    print(f"{c.t_start:g} K -> {c.t_end:g} K: {c.direction}, {c.behaviour} "
          f"(stretch {c.start_stretch:.4f} -> {c.final_stretch:.4f})")
    print(f"  {c.reason}")
    return 0
