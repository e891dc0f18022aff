"""``thermogel simulate``: run the full poro-elastic PDE solver (paper sec. DynamicModel)."""

from __future__ import annotations

import argparse
import shutil
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager

import numpy as np

from dosing.scenario import GRIDS
from solver.errors import ParameterError

from .common import add_gel_options, gel_from_args, print_json
from .outfile import OUT_HELP, request_of, save


def _protocol(text: str) -> list[tuple[float, float]]:
    """'0.1:308,0.5:302' -> [(0.1, 308.0), (0.5, 302.0)]."""
    try:
        return [(float(d), float(t)) for d, t in (item.split(":") for item in text.split(","))]
    except ValueError:
        raise argparse.ArgumentTypeError(
            "expected duration:temperature pairs separated by commas, e.g. 0.1:308,0.5:302"
        ) from None


def add_protocol_options(p: argparse.ArgumentParser, t_start_help: str) -> None:
    """--t-start, and a jump (--t-end, --until) or --protocol steps, and --branch: the
    temperature history of ``simulate`` and ``release``."""
    p.add_argument("--t-start", type=float, required=True, help=t_start_help)
    p.add_argument("--t-end", type=float, default=None, help="end temperature in K (one jump)")
    p.add_argument("--until", type=float, default=None,
                   help="dimensionless duration of the jump (with --t-end)")
    p.add_argument("--protocol", type=_protocol, default=None, metavar="D:T,...",
                   help="temperature steps instead of --t-end/--until, e.g. 0.05:308,0.5:302")
    p.add_argument("--branch", choices=["swollen", "shrunken"], default=None,
                   help="start branch (default: swollen when heating, shrunken when cooling)")


def register(sub: argparse._SubParsersAction) -> None:
    """Add the sub-command."""
    p = sub.add_parser("simulate", help="full PDE solver: porosity, radius and front in time")
    add_gel_options(p)
    add_protocol_options(p, "start temperature in K")
    p.add_argument("--grid", choices=list(GRIDS), default="eulerian",
                   help="discretization: eulerian (the paper's, default), lagrangian (uniform "
                        "dry cells) or moving (cells that follow the interface)")
    p.add_argument("--n", type=int, default=400, help="grid cells (default 400)")
    p.add_argument("--integrator", choices=["implicit", "explicit"], default="implicit",
                   help="adaptive implicit (default) or the paper's forward Euler")
    p.add_argument("--rtol", type=float, default=1e-6, help="implicit tolerance (default 1e-6)")
    p.add_argument("--dt", type=float, default=None, help="explicit time step (default: 0.8 "
                   "of the stability limit)")
    p.add_argument("--every", type=float, default=None, metavar="DT",
                   help="output interval (default: 200 outputs)")
    p.add_argument("--max-steps", type=int, default=None, help="step budget")
    p.add_argument("--interfacial-length", type=float, default=0.0, metavar="L",
                   help="interfacial energy length ell in dry radii (default 0: the paper's "
                   "model; resolve it with --n >= 2/L on the Lagrangian grid, "
                   "docs/interfacial.md)")
    p.add_argument("--out", default=None, help="save the run to this file: " + OUT_HELP)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--profiles", action="store_true", help="with --json: include phi snapshots")
    p.set_defaults(func=run)


@contextmanager
def _progress_bar(enabled: bool) -> Iterator[Callable[[float], None] | None]:
    """A tqdm bar on stderr when it is a terminal (tqdm is imported only then)."""
    if not enabled:
        yield None
        return
    from tqdm import tqdm

    size = shutil.get_terminal_size((80, 24))  # a pty may report 0 x 0: tqdm then hides
    bar = tqdm(total=1000, desc="simulate", leave=False, file=sys.stderr,
               ncols=size.columns or 80, nrows=size.lines or 24,
               bar_format="{desc}: {percentage:3.0f}%|{bar}| [{elapsed}<{remaining}]")

    def update(fraction: float) -> None:
        target = int(round(1000 * min(max(fraction, 0.0), 1.0)))
        if target > bar.n:
            bar.update(target - bar.n)

    try:
        yield update
    finally:
        bar.close()


def run(args: argparse.Namespace) -> int:
    """Run, optionally save, and print a summary (or JSON)."""
    from solver.full import simulate

    if args.protocol is None and (args.t_end is None or args.until is None):
        raise ParameterError("t_end/until", None, "both --t-end and --until, or --protocol")
    with _progress_bar(sys.stderr.isatty()) as progress:
        res = simulate(gel_from_args(args), args.t_start, args.t_end, until=args.until,
                       protocol=args.protocol, grid=args.grid, n=args.n,
                       integrator=args.integrator, rtol=args.rtol, every=args.every,
                       branch=args.branch, dt=args.dt, max_steps=args.max_steps,
                       progress=progress, interfacial_length=args.interfacial_length)
    saved = save(args.out, res.save, lambda: res.to_xarray(
        request=request_of(args), truth=_truth(res))) if args.out else None
    if args.json:
        out = res.to_json_dict(profiles=args.profiles)
        if saved is not None:
            out["file"] = str(saved)
        print_json(out)
        return 0
    d = res.diagnostics
    print(f"{d['gel']['name']} from {d['t_start']:g} K ({d['branch']}), protocol "
          + ", ".join(f"{T:g} K for {dur:g}" for dur, T in d["protocol"])
          + f": {d['grid']} grid, N = {d['n']}, {d['integrator']}"
          + (f", interfacial length {d['interfacial_length']:g}"
             if d.get("interfacial_length") else ""))
    print(f"  {d['steps']} steps ({d['rejected']} rejected), {d['wall_time']:.2f} s, "
          f"max solid error {np.max(res.solid_error):.1e}")
    if res.spinodal:
        print(f"  WARNING: {d['message']}")
    print("       t        a(t)     R_f(t)   jump")
    for k in np.unique(np.linspace(0, res.t.size - 1, 11).astype(int)):
        fr = "-" if np.isnan(res.front[k]) else f"{res.front[k]:.5f}"
        jp = "-" if np.isnan(res.jump[k]) else f"{res.jump[k]:.3f}"
        print(f"  {res.t[k]:9.5f}  {res.radius[k]:8.5f}  {fr:>8}  {jp:>6}")
    if saved is not None:
        print(f"wrote {saved}")
    return 0


def _truth(res: object) -> str:
    """The model a run solved, in words (the export's ``truth`` attribute)."""
    d = res.diagnostics  # type: ignore[attr-defined]
    ell = d.get("interfacial_length")
    return (f"full solver, {d.get('grid')} grid, N = {d.get('n')}, {d.get('integrator')}; "
            + (f"the regularized model at interfacial length {ell:g}" if ell
               else "the paper's model (no interfacial energy)"))
