"""``thermogel fit``: fit a gel to measured swelling (eq. EqlEqn) or shrinking data.

    thermogel fit swelling curve.csv [--json] [--plot fit.png] [--save NAME]
    thermogel fit kinetics shrink.csv --gel NAME --t-start 302 --t-end 308 --dry-radius-um 50

A saved name works as ``--gel NAME`` in dose, schedule and simulate.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from solver.errors import ParameterError

from .common import print_json
from .outfile import add_format_option, figure_path, request_of


def _fix(text: str) -> tuple[str, float]:
    try:
        k, v = text.split("=")
        return k.strip(), float(v)
    except ValueError:
        raise argparse.ArgumentTypeError("expected NAME=VALUE, e.g. omega=100") from None


def _viscosity(text: str) -> float | str:
    return text if text.strip().lower() == "water" else float(text)


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``fit swelling`` and ``fit kinetics``."""
    p = sub.add_parser("fit", help="fit a gel to measured swelling or shrinking data")
    fs = p.add_subparsers(dest="fit_kind", required=True)
    s = fs.add_parser("swelling", help="fit Omega, A0, B0, A1, B1 and the size scale to an "
                      "equilibrium curve (CSV: temperature_K and radius | diameter | "
                      "volume_ratio, optional weight)")
    s.add_argument("file", help="CSV file with a header row")
    s.add_argument("--sigma-t", type=float, default=0.05,
                   help="temperature noise in K (default 0.05)")
    s.add_argument("--size-rel-sigma", type=float, default=0.01,
                   help="relative size noise (default 0.01); only the ratio to --sigma-t "
                        "matters unless the noise is known")
    s.add_argument("--fix", type=_fix, action="append", default=[], metavar="NAME=VALUE",
                   help="keep a parameter fixed (omega, scale, b0, b1; a0 with b0, a1 with "
                        "b1), e.g. --fix omega=100; repeatable")
    s.add_argument("--starts", type=int, default=6, help="polished starts (default 6)")
    _common(s)
    s.set_defaults(func=run_swelling)
    k = fs.add_parser("kinetics", help="fit tau (hence k0) to a shrinking curve after a jump "
                      "(CSV: time_s and radius | diameter | volume_ratio)")
    k.add_argument("file", help="CSV file with a header row; time 0 is the jump")
    k.add_argument("--gel", default="ANB", help="preset or stored fitted gel (default ANB)")
    k.add_argument("--t-start", type=float, required=True, help="start temperature in K")
    k.add_argument("--t-end", type=float, required=True, help="jump temperature in K")
    k.add_argument("--branch", choices=["swollen", "shrunken"], default=None)
    size = k.add_mutually_exclusive_group()
    size.add_argument("--dry-radius-um", type=float, default=None,
                      help="dry bead radius in um (for k0)")
    size.add_argument("--swollen-radius-um", type=float, default=None,
                      help="bead radius in um at T_start (for k0)")
    k.add_argument("--viscosity", type=_viscosity, default=1.0e-3,
                   help="fluid viscosity in Pa s or 'water' (default 1e-3)")
    k.add_argument("--polymer-volume-m3", type=float, default=3.0e-25,
                   help="Omega_p in m^3 (default 3e-25)")
    k.add_argument("--model", choices=["auto", "front", "front-sharp", "full"], default="auto",
                   help="model of the curve (default auto: the front model where it applies)")
    k.add_argument("--fit-beta", action="store_true",
                   help="also fit beta of k = phi/(1-phi)^beta (needs --model full)")
    k.add_argument("--beta", type=float, default=None,
                   help="permeability exponent (fixed, or the start with --fit-beta)")
    k.add_argument("--interfacial-length", type=float, default=None, metavar="L",
                   help="full solver's interfacial length (default 0.005)")
    k.add_argument("--size-rel-sigma", type=float, default=0.01, help="relative size noise")
    k.add_argument("--cache", default=None, help="validation cache file for full-solver runs")
    _common(k)
    k.set_defaults(func=run_kinetics)


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--plot", default=None, metavar="PNG", help="draw the fit to this file")
    add_format_option(p)
    p.add_argument("--out", default=None, metavar="FILE.nc",
                   help="write the fit as netCDF (.nc: estimates, intervals, covariance, "
                        "units and provenance) or tidy CSV (.csv)")
    p.add_argument("--save", default=None, metavar="NAME",
                   help="store the fitted gel under NAME (usable as --gel NAME)")
    p.add_argument("--gels-dir", default=None,
                   help="store directory (default $THERMOGEL_GELS or gels/ beside the cache)")


def _interval(iv: Any) -> str:
    return "not identifiable" if iv is None else f"[{iv[0]:.5g}, {iv[1]:.5g}]"


def run_swelling(args: argparse.Namespace) -> int:
    """Fit, print, plot, save."""
    from dosing.fit import data_dict, fit_swelling, read_swelling_csv
    from dosing.gel_store import GelStore, check_name

    if args.save:
        check_name(args.save)
    data = read_swelling_csv(args.file)
    res = fit_swelling(data, sigma_t=args.sigma_t, size_rel_sigma=args.size_rel_sigma,
                       fixed=dict(args.fix), n_starts=args.starts)
    report = res.to_dict()
    dd = data_dict(data)
    if args.out:
        from dosing import export

        report["file"] = str(export.save(res.to_xarray(request=request_of(args)), args.out))
    if args.save:
        from solver.fit import fit_gel

        path = GelStore(args.gels_dir).save(args.save, fit_gel(res, args.save),
                                            swelling={"data": dd, "fit": report})
        report["saved"] = str(path)
    if args.plot:
        from api.plots.fit import draw_swelling_fit

        paths = draw_swelling_fit(report, dd, figure_path(args.plot, args.format))
        report["plots"] = [str(p) for p in paths]
    if args.json:
        print_json(report)
        return 0
    print(f"swelling fit of {len(data)} points ({data.kind}): "
          f"{'converged' if res.success else 'NOT converged'}, rms {res.rms_residual:.3g} K "
          f"(chi2/dof {res.chi2_reduced:.3g}, {res.nfev} evaluations)")
    for name in res.names:
        tag = " (fixed)" if name in res.fixed else ""
        print(f"  {name:6s} {res.parameters[name]:12.6g}  95% {_interval(res.intervals[name])}"
              f"{tag}")
    for tr in res.extra.get("transitions", []):
        print(f"  transition ({tr['kind']}) {tr['temperature']:.3f} K  95% "
              f"{_interval(tr.get('interval'))}")
    _print_notes(res, report)
    return 0


def _print_notes(res: Any, report: dict[str, Any]) -> None:
    """The fit's warnings on stdout; where it was saved and plotted on stderr."""
    for w in res.warnings:
        print(f"  warning: {w}")
    for key in ("saved", "plots"):
        if key in report:
            print(f"  {key}: {report[key]}", file=sys.stderr)


def run_kinetics(args: argparse.Namespace) -> int:
    """Fit, print, plot, save."""
    from dosing import PhysicalConstants, Planner, SolverSettings
    from dosing.fit import data_dict, fit_shrinking, read_kinetics_csv
    from dosing.gel_store import GelStore, check_name, lookup

    if args.save:
        check_name(args.save)
    data = read_kinetics_csv(args.file)
    store = GelStore(args.gels_dir)
    gel = lookup(args.gel, store)
    settings = SolverSettings() if args.interfacial_length is None else SolverSettings(
        interfacial_length=args.interfacial_length)
    constants = PhysicalConstants(args.viscosity, args.polymer_volume_m3)
    from concurrent.futures import ThreadPoolExecutor

    planner = Planner(cache_path=args.cache, executor=ThreadPoolExecutor(1))
    try:
        res = fit_shrinking(data, gel, args.t_start, args.t_end, branch=args.branch,
                            dry_radius_um=args.dry_radius_um,
                            swollen_radius_um=args.swollen_radius_um, constants=constants,
                            fit_beta=args.fit_beta, beta=args.beta, model=args.model,
                            settings=settings, size_rel_sigma=args.size_rel_sigma,
                            planner=planner)
    finally:
        planner.close()
        planner.jobs.executor.shutdown(wait=True)
    report = res.to_dict()
    dd = data_dict(data)
    if args.out:
        from dosing import export

        report["file"] = str(export.save(res.to_xarray(request=request_of(args)), args.out))
    if args.save:
        from solver.gel import Gel

        g = Gel.from_dict({**report["gel"], "name": args.save})
        if report.get("beta") is not None:
            g = g.with_permeability("power", report["beta"])
        if args.save in store.names() and args.save != args.gel:
            raise ParameterError("save", args.save, f"a new name or the fitted gel's own "
                                 f"({args.gel})", "it would replace another stored gel")
        swelling = store.load_record(args.gel).get("swelling") \
            if args.gel in store.names() else None
        path = store.save(args.save, g, swelling=swelling,
                          kinetics={"data": dd, "fit": report})
        report["saved"] = str(path)
    if args.plot:
        from api.plots.fit import draw_kinetics_fit

        report["plots"] = [str(draw_kinetics_fit(report, dd,
                                                 figure_path(args.plot, args.format)))]
    if args.json:
        print_json(report)
        return 0
    print(f"kinetics fit of {len(data)} points with the {res.extra['model']} model: "
          f"{'converged' if res.success else 'NOT converged'}, rms "
          f"{100 * res.rms_residual:.3g}% (chi2/dof {res.chi2_reduced:.3g})")
    for name in res.names:
        print(f"  {name:6s} {res.parameters[name]:12.6g}  95% {_interval(res.intervals[name])}")
    if "k0_m2" in res.extra:
        print(f"  k0     {res.extra['k0_m2']:12.6g} m^2  95% "
              f"{_interval(res.extra['k0_interval_m2'])}")
    _print_notes(res, report)
    return 0
