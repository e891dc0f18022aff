"""``thermogel equilibrium``: every equilibrium of a gel at a temperature, and its folds."""

from __future__ import annotations

import argparse

from .common import add_gel_options, gel_from_args, print_json


def register(sub: argparse._SubParsersAction) -> None:
    """Add the sub-command."""
    p = sub.add_parser("equilibrium", help="equilibria (all branches) at a temperature")
    add_gel_options(p)
    p.add_argument("--temperature", type=float, required=True, help="temperature in K")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Print the equilibria and the fold temperatures."""
    from solver.equilibrium import equilibria, folds

    gel = gel_from_args(args)
    eqs = equilibria(gel, args.temperature)
    fl = folds(gel)
    if args.json:
        print_json({"gel": gel.to_dict(), "temperature": args.temperature,
                    "equilibria": [e.to_dict() for e in eqs],
                    "folds": [f.temperature for f in fl],
                    "fold_details": [f.to_dict() for f in fl]})
        return 0
    print(f"{gel.name} at {args.temperature:g} K: {len(eqs)} equilibria")
    for e in eqs:
        print(f"  stretch {e.stretch:.4f}  porosity {e.porosity:.4f}  "
              f"{'stable' if e.stable else 'unstable'}")
    for f in fl:
        print(f"  fold ({f.kind}) at {f.temperature:.4f} K, stretch {f.stretch:.4f}")
    return 0
