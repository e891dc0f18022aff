"""``thermogel fit``: fit a gel to measured swelling (eq. EqlEqn) or shrinking data; the
empirical release models to a release profile (``fit empirical``, api/commands/empirical.py).

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
from .constants_options import add_constants_options, constants_from_args
from .outfile import add_format_option, figure_path, request_of


def _fix(text: str) -> tuple[str, float]:
    try:
        k, v = text.split("=")
        return k.strip(), float(v)
    except ValueError:
        raise argparse.ArgumentTypeError("expected NAME=VALUE, e.g. omega=100") from None


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
    s.add_argument("--objective", choices=["orthogonal", "temperature"], default="orthogonal",
                   help="'orthogonal' (default): errors in both variables, judged by "
                        "chi-square under the stated noise; 'temperature': the paper's "
                        "residual T(lambda_i) - T_i")
    s.add_argument("--dry-size", type=float, default=None,
                   help="the measured dry (or preparation) size in the data's unit: fixes "
                        "the scale instead of fitting it")
    s.add_argument("--below-dry-sigmas", type=float, default=2.0,
                   help="no point more than this many size-noise widths below the fitted "
                        "dry size (default 2)")
    s.add_argument("--profile", default="", metavar="NAMES",
                   help="profile-likelihood intervals for these parameters, e.g. scale,omega "
                        "(a refit per point: seconds each)")
    s.add_argument("--compare-models", action="store_true",
                   help="AIC/BIC of nested chi models (full, b1=0, a1=b1=0): three fits")
    s.add_argument("--jump", default=None, metavar="T0:T1",
                   help="also state the dose time of this jump under both objectives, "
                        "flagged when they disagree beyond their intervals")
    s.add_argument("--dose-fraction", type=float, default=0.8,
                   help="the dose of --jump (fraction of the stored fluid, default 0.8)")
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
    add_constants_options(k, mesh=False, k0=False)
    k.add_argument("--model", choices=["auto", "front", "front-sharp", "full"], default="auto",
                   help="model of the curve (default auto: the front model where it applies)")
    k.add_argument("--fit-beta", action="store_true",
                   help="also fit beta of k = phi/(1-phi)^beta (needs --model full)")
    k.add_argument("--beta", type=float, default=None,
                   help="permeability exponent (fixed, or the start with --fit-beta)")
    k.add_argument("--interfacial-length", type=float, default=None, metavar="L",
                   help="full solver's interfacial length (default: the bead's own, "
                        "xi_dry / a_d, as in `thermogel dose`)")
    k.add_argument("--size-rel-sigma", type=float, default=0.01, help="relative size noise")
    k.add_argument("--compare-laws", action=argparse.BooleanOptionalAction, default=True,
                   help="also fit under both front laws (Maxwell: front-sharp; delayed: the "
                        "ell = 0 lattice, one full-solver run, about a second) and compare "
                        "them by AIC (default on; --no-compare-laws skips it)")
    k.add_argument("--cache", default=None, help="validation cache file for full-solver runs")
    _common(k)
    k.set_defaults(func=run_kinetics)
    r = fs.add_parser("release", help="fit a drug's free diffusivity D0 to a cumulative "
                      "release curve (CSV: time and released as a fraction, %% or ug)")
    r.add_argument("file", help="CSV file; time 0 is the start of release")
    r.add_argument("--gel", default="ANB", help="preset or stored fitted gel (default ANB)")
    r.add_argument("--t-start", type=float, required=True, help="temperature in K")
    r.add_argument("--t-end", type=float, default=None,
                   help="equal to --t-start (isothermal; or give --protocol)")
    r.add_argument("--protocol", action="append", default=None, metavar="STEP",
                   help="the heating the release ran under, from --t-start, repeatable or "
                        "joined by ';' ('Heat to 308 K at 5 K/min', 'Hold at 308 K for 10 "
                        "min', 'Bath at 308 K'; docs/heating.md): one full-solver run of "
                        "the protocol's mechanics, one solute run per trial D0")
    r.add_argument("--n", type=int, default=None,
                   help="full solver's cells under a protocol (default the truth's, 400)")
    r.add_argument("--rtol", type=float, default=None,
                   help="full solver's rtol under a protocol (default the truth's, 1e-5)")
    r.add_argument("--dry-radius-um", type=float, required=True, help="dry bead radius, um")
    r.add_argument("--hindrance", choices=["none", "free-volume", "ogston"], default="none",
                   help="hindrance of the drug by the gel (default none)")
    r.add_argument("--mesh-size-nm", type=float, default=None,
                   help="swollen mesh size for the free-volume sieve, nm")
    r.add_argument("--fiber-radius-nm", type=float, default=None,
                   help="polymer fibre radius for Ogston's law, nm")
    r.add_argument("--loaded-ug", type=float, default=None,
                   help="the load, when the release is given in ug")
    r.add_argument("--json", action="store_true", help="print one JSON object")
    r.add_argument("--plot", default=None, metavar="PNG",
                   help="draw data, fit and its 95%% band (matplotlib)")
    r.set_defaults(func=run_release)
    from .empirical import add_empirical

    add_empirical(fs)


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
    from dosing.fits.gel import data_dict, fit_swelling, read_swelling_csv
    from dosing.fits.gel_store import GelStore, check_name

    if args.save:
        check_name(args.save)
    read: dict[str, Any] = {}
    data = read_swelling_csv(args.file, read)
    prof = tuple(x.strip() for x in args.profile.split(",") if x.strip())
    bad = [x for x in prof if x not in ("omega", "b0", "b1", "scale")]
    if bad:
        raise ParameterError("profile", bad[0], "omega, b0, b1 or scale")
    jump = _jump(args.jump)
    res = fit_swelling(data, sigma_t=args.sigma_t, size_rel_sigma=args.size_rel_sigma,
                       fixed=dict(args.fix), n_starts=args.starts, objective=args.objective,
                       dry_size=args.dry_size, below_dry_sigmas=args.below_dry_sigmas,
                       profile=prof)
    report = res.to_dict()
    report["read"] = read
    if args.compare_models:
        from dosing.fits.gel import compare_chi_models

        report["model_comparison"] = compare_chi_models(
            data, sigma_t=args.sigma_t, size_rel_sigma=args.size_rel_sigma,
            objective=args.objective, fixed=dict(args.fix))
    if jump is not None:
        from dosing.fits.gel import dose_under_objectives

        report["dose_time_by_objective"] = dose_under_objectives(
            data, jump[0], jump[1], args.dose_fraction, sigma_t=args.sigma_t,
            size_rel_sigma=args.size_rel_sigma, fixed=dict(args.fix),
            fits={args.objective: res})
    dd = data_dict(data)
    if args.out:
        from dosing.present import export

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
    x = res.extra
    print(f"swelling fit of {len(data)} points ({data.kind}), {x['objective']} objective: "
          f"{'converged' if res.success else 'NOT converged'}; chi2 {x['chi2']:.4g} on "
          f"{x['dof']} dof (p = {x['chi2_p_value']:.3g}) under the stated noise, "
          f"AIC {x['aic']:.4g}, BIC {x['bic']:.4g}")
    tr = x["rms_temperature_residual_K"]
    print(f"  temperature residual rms {'-' if tr is None else f'{tr:.3g}'} K over "
          f"{x['n_temperature_residual']} points above the dry size; "
          f"{x['points_below_dry']} below it (at most {x['max_below_dry_relative']:.2%})")
    for name in res.names:
        tag = " (fixed)" if name in res.fixed else ""
        print(f"  {name:6s} {res.parameters[name]:12.6g}  95% {_interval(res.intervals[name])}"
              f"{tag}")
    for tr in res.extra.get("transitions", []):
        print(f"  transition ({tr['kind']}) {tr['temperature']:.3f} K  95% "
              f"{_interval(tr.get('interval'))}")
    for name, pr in (res.extra.get("profile_intervals") or {}).items():
        iv = pr.get("interval")
        print(f"  {name:6s} profile-likelihood 95% "
              + ("-" if iv is None else "[" + ", ".join("open" if v is None else f"{v:.5g}"
                                                       for v in iv) + "]"))
    for name, m in (report.get("model_comparison") or {}).get("models", {}).items():
        print(f"  chi model {name:9s} " + (m["error"] if "error" in m else
              f"k {m['k']}  chi2 {m['chi2']:.4g}  dAIC {m['delta_aic']:.3g}  "
              f"dBIC {m['delta_bic']:.3g}"))
    dj = report.get("dose_time_by_objective")
    if dj:
        for obj in ("orthogonal", "temperature"):
            o = dj[obj]
            print(f"  dose {dj['dose_fraction']:.0%} {dj['t_start']:g} -> {dj['t_end']:g} K "
                  f"({obj}): " + (f"none ({o['note']})" if o["time"] is None else
                                  f"t = {o['time']:.4g}  " + (
                                      f"95% {_interval(o['interval'])}" if o["interval"]
                                      else f"({o.get('model')}, no interval)")))
        print(f"  {'DISAGREE: ' if dj.get('disagree') else ''}{dj['note']}")
    for w in res.extra.get("not_pinned", []):
        print(f"  not pinned: {w}")
    _print_notes(res, report)
    return 0


def _jump(text: str | None) -> tuple[float, float] | None:
    if text is None:
        return None
    try:
        a, b = (float(v) for v in text.split(":"))
    except ValueError:
        raise ParameterError("jump", text, "T0:T1 in K, e.g. 304:308") from None
    return a, b


def _print_notes(res: Any, report: dict[str, Any]) -> None:
    """The fit's warnings on stdout; where it was saved and plotted on stderr."""
    for w in report.get("warnings", res.warnings):
        print(f"  warning: {w}")
    for key in ("saved", "plots"):
        if key in report:
            print(f"  {key}: {report[key]}", file=sys.stderr)


def run_kinetics(args: argparse.Namespace) -> int:
    """Fit, print, plot, save."""
    from dosing import Planner, SolverSettings
    from dosing.fits.gel import data_dict, kinetics_report, read_kinetics_csv
    from dosing.fits.gel_store import GelStore, check_name, lookup

    if args.save:
        check_name(args.save)
    read: dict[str, Any] = {}
    data = read_kinetics_csv(args.file, read)
    store = GelStore(args.gels_dir)
    gel = lookup(args.gel, store)
    settings = SolverSettings() if args.interfacial_length is None else SolverSettings(
        interfacial_length=args.interfacial_length)
    constants = constants_from_args(args).for_gel(gel.omega)
    from concurrent.futures import ThreadPoolExecutor

    planner = Planner(cache_path=args.cache, executor=ThreadPoolExecutor(1))
    try:
        res, report = kinetics_report(
            data, gel, args.t_start, args.t_end, compare_laws=args.compare_laws,
            branch=args.branch, dry_radius_um=args.dry_radius_um,
            swollen_radius_um=args.swollen_radius_um, constants=constants,
            fit_beta=args.fit_beta, beta=args.beta, model=args.model, settings=settings,
            size_rel_sigma=args.size_rel_sigma, planner=planner)
    finally:
        planner.close()
        planner.jobs.executor.shutdown(wait=True)
    report["read"] = read
    dd = data_dict(data)
    if args.out:
        from dosing.present import export

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
    if "diffusivity_cm2_s" in res.extra:
        print(f"  D      {res.extra['diffusivity_cm2_s']:12.6g} cm^2/s at "
              f"{res.extra['diffusivity_t_k']:g} K  95% "
              f"{_interval(res.extra['diffusivity_interval_cm2_s'])} (what the curve pins)")
    laws = report.get("front_laws") or {}
    for law, v in (laws.get("laws") or {}).items():
        print(f"  law {law:8s} tau {v['tau_s']:.5g} s  AIC {v['aic']:.4g}")
    if laws.get("note") or laws.get("error"):
        print(f"  {laws.get('note') or 'front laws not compared: ' + laws['error']}")
    if "k0_m2" in res.extra:
        print(f"  k0     {res.extra['k0_m2']:12.6g} m^2  95% "
              f"{_interval(res.extra['k0_interval_m2'])}")
    _print_notes(res, report)
    return 0


def run_release(args: argparse.Namespace) -> int:
    """Fit D0 to a release curve, print (or JSON), plot."""
    from dosing import SolverSettings
    from dosing.fits.release import fit_release, read_release_csv

    read: dict[str, Any] = {}
    t, y = read_release_csv(args.file, args.loaded_ug, read)
    steps = None if args.protocol is None else [
        s.strip() for arg in args.protocol for s in arg.split(";") if s.strip()]
    rep = fit_release(t, y, args.gel, args.t_start, args.t_end, args.dry_radius_um,
                      protocol=steps, hindrance=args.hindrance,
                      mesh_size_nm=args.mesh_size_nm, fiber_radius_nm=args.fiber_radius_nm,
                      settings=None if args.n is None and args.rtol is None else
                      SolverSettings(n=args.n, rtol=args.rtol))
    rep["read"] = read
    if args.plot:
        rep["plots"] = [_plot_release(rep, args.plot)]
    if args.json:
        print_json(rep)
        return 0
    d = rep["parameters"]["drug_diffusivity_cm2_s"]
    print(f"release fit of {rep['n_points']} points: D0 = {d:.4g} cm^2/s  95% "
          f"{_interval(rep['intervals']['drug_diffusivity_cm2_s'])}; effective "
          f"{rep['effective_diffusivity_cm2_s']:.4g} cm^2/s (hindrance {rep['hindrance']}, "
          f"factor {rep['hindrance_factor']:.3g})")
    print(f"  goodness of fit: rms residual {rep['rms_residual']:.3g} of the load, chi2/dof "
          f"{rep['chi2_reduced']:.3g}")
    print(f"  similarity of prediction and data (FDA rules, not a goodness of fit): "
          f"{rep['similarity']['outcome']}")
    for w in rep["warnings"] + [f"not pinned: {x}" for x in rep["not_pinned"]]:
        print(f"  {w}")
    return 0


def _plot_release(rep: dict[str, Any], path: str) -> str:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    b = rep["band"]
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.fill_between(b["time_s"], b["lower"], b["upper"], color="C1", alpha=0.3,
                    label="95% band (D0)")
    ax.plot(b["time_s"], b["released"], "C1-", label="fit")
    ax.plot(rep["time_s"], rep["released"], "C0o", ms=4, label="data")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("released fraction")
    ax.set_title(f"D0 = {rep['parameters']['drug_diffusivity_cm2_s']:.3g} cm^2/s, "
                 f"similarity f2 = {rep['f2']:.1f}", fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return str(path)
