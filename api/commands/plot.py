"""``thermogel plot``: figures of a saved full-solver run (paper figs. 5-10)."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:
    """Add the sub-command."""
    p = sub.add_parser("plot", help="porosity colour map and profiles of a saved run "
                                    "(.npz or .nc)")
    p.add_argument("run", help="a file written by 'thermogel simulate --out'")
    p.add_argument("--out", default=".", help="output directory (default: current)")
    p.add_argument("--format", choices=["png", "pdf", "svg"], default="png",
                   help="image format")
    p.add_argument("--dry-radius-um", default=None,
                   help="the bead's dry radius (um, or '50 um'): axes in um and s "
                        "(a .nc run written with a bead size carries it)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Draw the figures and report the files written."""
    from api.plots.runs import draw_run
    from solver.full import FullResult

    dry, tau = None, None
    if args.run.endswith(".nc"):
        from dosing.present.export import open_netcdf, run_from_dataset

        ds = open_netcdf(args.run)
        res = run_from_dataset(ds)
        dry = ds.attrs.get("dry_radius_um") or None
        tau = ds.attrs.get("timescale_seconds") or None
    else:
        res = FullResult.load(args.run)
    if args.dry_radius_um is not None:
        from dosing.quantity import micrometres
        from dosing.units import timescale

        dry = micrometres(args.dry_radius_um, "dry_radius_um")
        t_end = max(T for _, T in res.diagnostics["protocol"])
        tau = timescale(dry, t_end, omega=float(res.diagnostics["gel"]["omega"])).seconds
    for path in draw_run(res, args.out, args.format, dry, tau):
        print(f"wrote {path}")
    return 0
