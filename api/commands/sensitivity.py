"""``thermogel sensitivity``: Sobol or Morris indices of the dose time
(dosing.studies.sensitivity)."""

from __future__ import annotations

import argparse

from .common import add_gel_options, gel_from_args, print_json


def register(sub: argparse._SubParsersAction) -> None:
    """Add the sub-command."""
    p = sub.add_parser("sensitivity", help="global sensitivity of the dose time in seconds "
                                           "(Sobol S1/ST or Morris, front model, SALib)")
    add_gel_options(p)
    p.add_argument("--t-start", required=True, help="start temperature (K, or '29 degC')")
    p.add_argument("--t-end", required=True, help="end temperature (K, or '35 degC')")
    p.add_argument("--fraction", type=float, required=True, help="dose fraction, 0-1")
    p.add_argument("--dry-radius-um", default="50", help="base dry radius in um (default 50)")
    p.add_argument("--vary", action="append", required=True, metavar="NAME=LO:HI[:log]",
                   help="an input to vary (repeat): dry_radius_um, permeability_m2, "
                        "viscosity_pa_s, polymer_volume_m3, t_start, t_end, dose_fraction, "
                        "omega, a0, b0, a1, b1; ':log' samples log-uniformly")
    p.add_argument("--method", choices=["sobol", "morris"], default="sobol")
    p.add_argument("--samples", type=int, default=1024,
                   help="Sobol base samples N (N (D+2) answers) or Morris trajectories")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--plot", default=None, metavar="FILE", help="bar plot of the indices")
    p.add_argument("--format", choices=["png", "svg", "pdf"], default=None,
                   help="plot format (default: the file's suffix, else png)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Compute and print the indices (or JSON), optionally the bar plot."""
    from dosing.studies.sensitivity import sensitivity

    res = sensitivity(gel_from_args(args), args.t_start, args.t_end, args.fraction,
                      args.vary, dry_radius_um=args.dry_radius_um, method=args.method,
                      samples=args.samples, seed=args.seed)
    out = res.to_dict()
    if args.plot:
        from api.plots.sensitivity import draw_sensitivity

        out["plot"] = str(draw_sensitivity(out, args.plot, args.format))
    if args.json:
        print_json(out)
        return 0
    o = res.output
    print(f"dose time (front model, {res.evaluations} answers in {res.seconds:.2f} s): "
          f"median {o['median']:.4g} s, 5-95% {o['p05']:.4g}-{o['p95']:.4g} s")
    keys = ("S1", "ST") if res.method == "sobol" else ("mu_star", "sigma")
    for n in res.names:
        i = res.indices[n]
        conf = [f" +- {i[k + '_conf']:.3f}" if k + "_conf" in i else "" for k in keys]
        print(f"  {n:18s} " + "   ".join(f"{k} = {i[k]:.4g}{c}"
                                         for k, c in zip(keys, conf, strict=True)))
    for note in res.notes:
        print(f"  note: {note}")
    if args.plot:
        print(f"wrote {out['plot']}")
    return 0
