"""``thermogel phase-map``: draw the paper's fig. 3 for a gel."""

from __future__ import annotations

import argparse

from .common import add_gel_options, gel_from_args
from .outfile import add_format_option, figure_path


def register(sub: argparse._SubParsersAction) -> None:
    """Add the sub-command."""
    p = sub.add_parser("phase-map", help="draw the equilibrium curve with spinodal and "
                       "coexistence regions (paper fig. 3)")
    add_gel_options(p)
    p.add_argument("--out", default="phase_map.png", help="output file (PNG, SVG or PDF)")
    add_format_option(p)
    p.add_argument("--t-min", type=float, default=None, help="lowest temperature shown (K)")
    p.add_argument("--t-max", type=float, default=None, help="highest temperature shown (K)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Draw and report the file written."""
    from api.plots.phase_map import draw_phase_map

    path = draw_phase_map(gel_from_args(args), figure_path(args.out, args.format),
                          args.t_min, args.t_max)
    print(f"wrote {path}")
    return 0
