"""``thermogel release``: a temperature protocol with the drug (full solver + solute)."""

from __future__ import annotations

import argparse
import math

import numpy as np

from solver.errors import ParameterError

from .common import add_gel_options, gel_from_args, print_json
from .constants_options import add_constants_options, constants_from_args
from .drug_options import add_drug_options, drug_from_args
from .outfile import OUT_HELP, request_of, save
from .simulate import add_protocol_options, protocol_pairs


def register(sub: argparse._SubParsersAction) -> None:
    """Add the sub-command."""
    p = sub.add_parser("release", help="drug released by a temperature protocol: full solver "
                                       "with the drug carried by the pore fluid")
    add_gel_options(p)
    add_protocol_options(p, "start (loading) temperature, K")
    p.add_argument("--dry-radius-um", type=float, default=None,
                   help="dry bead radius in um (for seconds and a release volume)")
    add_constants_options(p.add_argument_group(
        "timescale constants (eq. timescale; tau at the hottest step)"))
    add_drug_options(p, required=True)
    p.add_argument("--n", type=int, default=None,
                   help="cells (default: the planner's truth, 400 on the moving grid)")
    p.add_argument("--interfacial-length", type=float, default=None, metavar="L",
                   help="interfacial length ell in dry radii (default: the planner's truth, "
                        "the bead's own xi_dry / a_d with --dry-radius-um, else 1e-4 for "
                        "the sharp limit; 0: the paper's model on the Lagrangian grid)")
    p.add_argument("--rtol", type=float, default=None,
                   help="mechanics tolerance (default: the truth's, 1e-5)")
    p.add_argument("--samples", type=int, default=2000,
                   help="mechanics samples the drug is integrated on (default 2000)")
    p.add_argument("--out", default=None, help="save the release result to this file: "
                   + OUT_HELP)
    p.add_argument("--plot", default=None, metavar="PNG",
                   help="draw cumulative release and concentration profiles (matplotlib)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--profiles", action="store_true", help="with --json: include the profiles")
    p.add_argument("--compare", default=None, metavar="MEASURED.csv",
                   help="state f1/f2 (FDA rules; a bootstrap over replicate units) between the "
                        "prediction and this measured profile (needs --dry-radius-um), beside "
                        "the residuals and chi-square (dosing.analysis)")
    p.add_argument("--measured-loaded-ug", type=float, default=None,
                   help="the load, when the measured profile is given as a mass")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Simulate, then print (or JSON) the release."""
    from dosing.request import bead_settings
    from dosing.runs.scenario import SolverSettings
    from dosing.runs.solute import drug_settings
    from dosing.units import timescale
    from solver.equilibrium import equilibrium
    from solver.gel import check_temperature
    from solver.solute import simulate_release

    if args.protocol is None and (args.t_end is None or args.until is None):
        raise ParameterError("t_end/until", None, "both --t-end and --until, or --protocol")
    measured = None
    if args.compare is not None:
        from dosing.analysis import read_profile

        if args.dry_radius_um is None:
            raise ParameterError("dry_radius_um", None, "a dry radius in um with --compare "
                                 "(the prediction in seconds)")
        measured = read_profile(args.compare, args.measured_loaded_ug)
    gel = gel_from_args(args)
    constants = constants_from_args(args).for_gel(gel.omega)
    protocol = protocol_pairs(args, args.dry_radius_um, constants)
    temps = [T for _, T in protocol] if protocol else [args.t_end]
    t_ref = check_temperature(max(temps), "t_end")
    # the planner's truth (one set of defaults): the drug dose's mechanics at the bead's ell
    settings = drug_settings(bead_settings(
        SolverSettings(n=args.n, rtol=args.rtol, interfacial_length=args.interfacial_length),
        constants, args.dry_radius_um)[0])
    branch = args.branch or ("swollen" if temps[0] >= args.t_start else "shrunken")
    a0 = equilibrium(gel, check_temperature(args.t_start, "t_start"), branch).stretch
    drug = drug_from_args(args, always=True)
    solute = drug.solute(a0, t_ref, constants, args.dry_radius_um)
    res, rel = simulate_release(gel, args.t_start, solute, t_end=args.t_end, until=args.until,
                                protocol=protocol, branch=args.branch,
                                grid=settings.grid, n=settings.n,
                                interfacial_length=settings.interfacial_length,
                                rtol=settings.rtol, samples=args.samples)
    tau = timescale(args.dry_radius_um, t_ref, constants) if args.dry_radius_um else None
    d_gel = constants.diffusivity(t_ref) * 1e4
    d_eff = rel.effective_diffusivity * d_gel
    saved = (save(args.out, rel.save, lambda: _dataset(rel, args, tau, settings))
             if args.out else None)
    if args.plot:
        from api.plots.release import draw_release

        print(f"wrote {draw_release(rel, args.plot, tau and tau.seconds)}")
    out = {"t": rel.t, "seconds": None if tau is None else rel.t * tau.seconds,
           "released_fraction": rel.released_fraction,
           "squeezed_fraction": rel.squeezed_fraction,  # the D0 = 0 twin's release
           "advected_fraction": rel.advected_fraction,
           "expelled_fraction": rel.expelled_fraction, "radius": rel.radius,
           "in_gel_fraction": rel.in_gel_fraction,
           "effective_diffusivity_cm2_s": d_eff,
           "drug_diffusivity_cm2_s": drug.d0_cm2_s(t_ref, constants),
           "gel_diffusivity_cm2_s": d_gel, "timescale_seconds": tau and tau.seconds,
           "solute": solute.to_dict(), "mass_balance_error": rel.mass_balance_error,
           "grid": settings.grid, "n": settings.n,
           "interfacial_length": settings.interfacial_length,
           "mechanics_seconds": res.diagnostics.get("wall_time"),
           "solute_seconds": rel.diagnostics.get("wall_time")}
    if args.release_volume_ul is not None:
        out["medium_concentration_ug_per_ul"] = _medium(rel, drug, args, a0)
    from dosing.payload.drug import sieved_out

    warning = sieved_out(solute, a0, float(rel.released_fraction[-1]),
                         float(np.max(rel.expelled_fraction)))
    out["warnings"] = [warning] if warning else []
    if saved is not None:
        out["file"] = str(saved)
        out["files"] = [str(f) for f in saved.files]
        out["file_notes"] = saved.notes
    if measured is not None:
        from dosing.analysis.similarity import measured_against_predicted

        out["compare"] = measured_against_predicted(measured, out["seconds"],
                                                    rel.released_fraction)
    if args.json:
        if args.profiles:
            out.update(profile_t=rel.profile_t, profiles=rel.profiles,
                       profile_radii=rel.profile_radii)
        print_json(out)
        return 0
    secs = "" if tau is None else f", tau = {tau.seconds:.4g} s"
    print(f"{gel.name} from {args.t_start:g} K: drug D0 = {out['drug_diffusivity_cm2_s']:.3g} "
          f"cm^2/s, hindered to {d_eff:.3g} cm^2/s at the start (gel's D = {d_gel:.3g})"
          f"{secs}; mass balance {rel.mass_balance_error:.1e}")
    for w in out["warnings"]:
        print(f"  WARNING: {w}")
    print("       t   released  squeezed  expelled fluid")
    for k in np.unique(np.linspace(0, rel.t.size - 1, 11).astype(int)):
        print(f"  {rel.t[k]:8.4f}  {rel.released_fraction[k]:8.4f}  "
              f"{rel.squeezed_fraction[k]:8.4f}  {rel.expelled_fraction[k]:8.4f}")
    if saved is not None:
        print("\n".join(saved.report()))
    if measured is not None:
        _print_compare(out["compare"], measured.label)
    return 0


def _print_compare(c: dict, label: str) -> None:
    """Measured against predicted: residuals, chi-square, the FDA similarity."""
    s = c["similarity"]
    chi = (f", chi2 {c['chi2']:.4g} on {c['chi2_dof']} points (SEM of the units)"
           if "chi2" in c else "")
    print(f"measured ({label}) against predicted: rms residual "
          f"{c['rms_residual_percent']:.3g} % of the load{chi}")
    print(f"  {s['notes'][0]}")
    print(f"  {s['f1_outcome']}")
    print(f"  {s['outcome']}")
    if s["bootstrap"]:
        print(f"  {s['bootstrap']['outcome']}")


def _medium(rel: object, drug: object, args: argparse.Namespace, a0: float) -> list | None:
    """Concentration in the finite release volume, ug/uL (needs the load)."""
    from dosing.units import volume_to_ul

    if args.dry_radius_um is None:
        return None
    stored = volume_to_ul(4.0 * math.pi / 3.0 * (a0**3 - 1.0), args.dry_radius_um)
    load = drug.load(stored)  # type: ignore[attr-defined]
    if load is None:
        return None
    grown = volume_to_ul(4.0 * math.pi / 3.0 * (a0**3 - rel.radius**3),  # type: ignore[attr-defined]
                         args.dry_radius_um)
    return (rel.released_fraction * load / (args.release_volume_ul + grown)).tolist()  # type: ignore[attr-defined]


def _dataset(rel: object, args: argparse.Namespace, tau: object, settings: object) -> object:
    """The release run as an xarray Dataset with units and provenance (the run's own grid,
    cells and interfacial length: the resolved settings, whatever the options left unset)."""
    from dosing.present.export import release_dataset

    ell = settings.interfacial_length  # type: ignore[attr-defined]
    return release_dataset(
        rel, args.dry_radius_um, tau and tau.seconds, request_of(args),  # type: ignore[arg-type,attr-defined]
        f"full solver ({settings.grid} grid, N = {settings.n}) with the drug carried by the "  # type: ignore[attr-defined]
        "pore fluid; " + (f"interfacial length {ell:g}" if ell
                          else "the paper's model (no interfacial energy)"))
