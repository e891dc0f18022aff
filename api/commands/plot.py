"""``thermogel plot``: figures of a saved full-solver run (paper figs. 5-10)."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:
    """Add the sub-command."""
    p = sub.add_parser("plot", help="porosity colour map and profiles of a saved run (.npz)")
    p.add_argument("run", help="a file written by 'thermogel simulate --out'")
    p.add_argument("--out", default=".", help="output directory (default: current)")
    p.add_argument("--format", choices=["png", "pdf"], default="png", help="image format")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Draw the figures and report the files written."""
    from api.plots.runs import draw_run
    from solver.full import FullResult

    for path in draw_run(FullResult.load(args.run), args.out, args.format):
        print(f"wrote {path}")
    return 0
