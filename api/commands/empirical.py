"""``thermogel fit empirical``: the empirical release models fitted to a release profile.

    thermogel fit empirical profile.csv [--models weibull,korsmeyer_peppas] [--lag] --json

The CSV: a time column with its unit and one release column per dosage unit (fraction,
``(%)`` or a mass with --loaded-ug); replicates are averaged and weighted by their spread
(``dosing.analysis``, docs/release_analysis.md).
"""

from __future__ import annotations

import argparse

from .common import print_json
from .outfile import add_format_option, figure_path


def add_empirical(fs: argparse._SubParsersAction) -> None:
    """Add ``fit empirical`` to the ``fit`` sub-commands."""
    from dosing.analysis.empirical import KP_WINDOW, MODELS

    e = fs.add_parser("empirical", help="fit the empirical release models (zero-order, "
                      "first-order, Higuchi, Korsmeyer-Peppas, Hixson-Crowell, Weibull, "
                      "Peppas-Sahlin) to a release profile; best by AIC")
    e.add_argument("file", help="CSV: time (s, min, h) and release columns (one per unit)")
    e.add_argument("--models", default=None, metavar="A,B",
                   help=f"comma-separated subset of: {', '.join(MODELS)} (default all)")
    e.add_argument("--lag", action="store_true",
                   help="fit a lag time where the model has one (Weibull: its location Ti)")
    e.add_argument("--kp-window", type=float, default=KP_WINDOW, metavar="PERCENT",
                   help="Korsmeyer-Peppas and Peppas-Sahlin are fitted on the points up to "
                        "this percent released (default 60; above it the fit is flagged)")
    e.add_argument("--loaded-ug", type=float, default=None,
                   help="the load, when the release is given as a mass")
    e.add_argument("--json", action="store_true", help="print one JSON object")
    e.add_argument("--plot", default=None, metavar="PNG",
                   help="draw the profile and every model (matplotlib)")
    add_format_option(e)
    e.set_defaults(func=run_empirical)


def run_empirical(args: argparse.Namespace) -> int:
    """Read, fit, print (or JSON), plot."""
    from dosing.analysis import fit_empirical, read_profile

    prof = read_profile(args.file, args.loaded_ug)
    models = None if args.models is None else [
        m.strip() for m in args.models.split(",") if m.strip()]
    res = fit_empirical(prof, models, lag=args.lag, kp_window=args.kp_window)
    rep = res.report()
    if args.plot:
        from api.plots.release_analysis import draw_empirical

        rep["plots"] = [str(draw_empirical(rep, figure_path(args.plot, args.format)))]
    if args.json:
        print_json(rep)
        return 0
    print(f"empirical models on {prof.label}: {prof.times.size} times, {prof.n_units} unit(s)"
          f"{' (weighted by their spread)' if res.weighted else ''}; times in "
          f"{res.time_unit}, F in % of the load")
    for name, f in res.fits.items():
        tag = " <- best by AIC" if name == res.best else (
            "" if f.delta_aic is not None else f"  (on its {f.window_percent:g} % window: "
            "not ranked)")
        print(f"  {f.title:17s} AIC {f.aic:9.3f}  R2adj {f.r2_adjusted:.5f}  MSC "
              f"{f.msc:7.3f}  n {f.n_points}{tag}")
        for p, v in f.parameters.items():
            iv = f.intervals[p]
            ivs = "no interval" if iv is None else f"95% [{iv[0]:.4g}, {iv[1]:.4g}]"
            print(f"      {p:5s} = {v:.5g} {f.units[p]}  {ivs}")
        if f.interpretation:
            print(f"      mechanism (sphere, 0.43/0.85): {f.interpretation['mechanism']}"
                  + (f"; {f.interpretation['note']}" if "note" in f.interpretation else ""))
        for w in f.warnings:
            print(f"      warning: {w}")
    for name, err in res.errors.items():
        print(f"  {name}: not fitted: {err}")
    for p in rep.get("plots", []):
        print(f"wrote {p}")
    return 0
