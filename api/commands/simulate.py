"""``thermogel simulate``: run the full poro-elastic PDE solver (paper sec. DynamicModel)."""

from __future__ import annotations

import argparse
import shutil
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np

from dosing.runs.scenario import GRIDS, PAPER, TRUTH
from solver.errors import ParameterError

from .common import add_gel_options, gel_from_args, print_json
from .outfile import OUT_HELP, request_of, save

# the moving grid's fewest cells at the default ell = 1e-4 (ANB 302 -> 308 K to t = 0.3:
# 50 cells exhaust 20,000 steps by t = 0.002, 80 take 11,000 steps, 100 take 2,800)
MOVING_N_FLOOR = 100


def _pairs(text: str) -> list[tuple[float, float]]:
    """'0.1:308,0.5:302' -> [(0.1, 308.0), (0.5, 302.0)]."""
    try:
        return [(float(d), float(t)) for d, t in (item.split(":") for item in text.split(","))]
    except ValueError:
        raise ParameterError("--protocol", text, "duration:temperature pairs separated by "
                             "commas (e.g. 0.1:308,0.5:302), or steps of the grammar "
                             "('Heat to 308 K at 5 K/min; Hold at 308 K for 2 min')") from None


def protocol_pairs(args: argparse.Namespace, dry_radius_um: float | None = None,
                   constants: Any = None) -> list[tuple[float, float]] | None:
    """The --protocol steps as (duration in tau, temperature) pairs: given so ('0.05:308,
    0.5:302'), or steps of the heating grammar (dosing.heating.grammar: 'Heat to 308 K at 5 K/min',
    'Hold at 308 K for 2 min', baths, traces; repeatable or joined by ';'), run as their
    staircase of holds (0.05 K stairs, dosing.heating.program.staircase; seconds through tau
    at the protocol's hottest temperature with a bead size); None without --protocol."""
    if not args.protocol:
        return None
    texts = [t.strip() for arg in args.protocol for t in arg.split(";") if t.strip()]
    if not any(c.isalpha() for t in texts for c in t):
        return [pair for t in texts for pair in _pairs(t)]
    from dosing.heating.grammar import Protocol
    from dosing.heating.program import staircase
    from dosing.units import timescale

    prot = Protocol(args.t_start, texts)
    for i in prot.until_steps:
        raise ParameterError(f"protocol[{i}].until", texts[i], "a step with a duration (an "
                             "until-step is the planner's: thermogel dose --protocol)")
    tau_s = None if dry_radius_um is None else timescale(dry_radius_um, prot.hottest,
                                                          constants).seconds
    return staircase(prot.program(tau_s), 0.0)


def add_protocol_options(p: argparse.ArgumentParser, t_start_help: str) -> None:
    """--t-start, and a jump (--t-end, --until) or --protocol steps, and --branch: the
    temperature history of ``simulate`` and ``release``."""
    p.add_argument("--t-start", type=float, required=True, help=t_start_help)
    p.add_argument("--t-end", type=float, default=None, help="end temperature in K (one jump)")
    p.add_argument("--until", type=float, default=None,
                   help="dimensionless duration of the jump (with --t-end)")
    p.add_argument("--protocol", action="append", default=None, metavar="STEPS",
                   help="temperature steps instead of --t-end/--until: duration:temperature "
                        "pairs in tau (0.05:308,0.5:302), or steps of the heating grammar "
                        "('Heat to 308 K at 5 K/min', 'Hold at 308 K for 2 min'; repeatable "
                        "or joined by ';'; docs/heating.md), run as their 0.05 K staircase")
    p.add_argument("--branch", choices=["swollen", "shrunken"], default=None,
                   help="start branch (default: swollen when heating, shrunken when cooling)")


def register(sub: argparse._SubParsersAction) -> None:
    """Add the sub-command."""
    p = sub.add_parser("simulate", help="full PDE solver: porosity, radius and front in time")
    add_gel_options(p)
    add_protocol_options(p, "start temperature in K")
    p.add_argument("--grid", choices=list(GRIDS), default=None,
                   help="discretization: moving (cells that follow the interface; the default), "
                        "lagrangian (uniform dry cells) or eulerian (the paper's; the default "
                        "with --paper)")
    p.add_argument("--n", type=int, default=None,
                   help=f"grid cells (default {TRUTH.n}; on the moving grid at the default "
                        f"interfacial length at least {MOVING_N_FLOOR})")
    p.add_argument("--integrator", choices=["implicit", "explicit"], default="implicit",
                   help="adaptive implicit (default) or the paper's forward Euler")
    p.add_argument("--rtol", type=float, default=1e-6, help="implicit tolerance (default 1e-6)")
    p.add_argument("--dt", type=float, default=None, help="explicit time step (default: 0.8 "
                   "of the stability limit)")
    p.add_argument("--every", type=float, default=None, metavar="DT",
                   help="output interval (default: 200 outputs)")
    p.add_argument("--max-steps", type=int, default=None, help="step budget")
    model = p.add_mutually_exclusive_group()
    model.add_argument("--interfacial-length", type=float, default=None, metavar="L",
                       help="interfacial energy length ell in dry radii: the well-posed model "
                       f"(default {TRUTH.interfacial_length:g}, the planner's truth without a "
                       "bead size; on a uniform grid resolve it with --n >= 2/L, "
                       "docs/interfacial.md)")
    model.add_argument("--paper", action="store_true",
                       help="the paper's model (no interfacial energy, ill-posed where a front "
                            f"forms) on its Eulerian grid, N = {PAPER.n}")
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


def model_options(args: argparse.Namespace) -> tuple[str, int, float]:
    """(grid, n, ell) of a run: by default the planner's truth without a bead size (the
    well-posed model on the moving grid, dosing.runs.scenario.TRUTH); ``--paper`` the paper's
    model (dosing.runs.scenario.PAPER).  On the moving grid at ell <= the default, fewer than
    MOVING_N_FLOOR cells cannot follow the interface: refused (exit 2)."""
    base = PAPER if args.paper or args.interfacial_length == 0.0 else TRUTH
    ell = base.interfacial_length if args.interfacial_length is None \
        else args.interfacial_length
    grid = args.grid or base.grid
    n = base.n if args.n is None else args.n
    if grid == "moving" and 0.0 < ell <= TRUTH.interfacial_length and n < MOVING_N_FLOOR:
        raise ParameterError("n", n, f">= {MOVING_N_FLOOR} on the moving grid at interfacial "
                             f"length {ell:g} (or --paper, or a larger --interfacial-length)",
                             "fewer cells cannot follow the interface: ANB 302 -> 308 K on 50 "
                             "cells exhausts 20,000 steps by t = 0.002")
    return grid, n, ell


def run(args: argparse.Namespace) -> int:
    """Run, optionally save, and print a summary (or JSON)."""
    from solver.full import simulate

    if args.protocol is None and (args.t_end is None or args.until is None):
        raise ParameterError("t_end/until", None, "both --t-end and --until, or --protocol")
    grid, n, ell = model_options(args)
    with _progress_bar(sys.stderr.isatty()) as progress:
        res = simulate(gel_from_args(args), args.t_start, args.t_end, until=args.until,
                       protocol=protocol_pairs(args), grid=grid, n=n,
                       integrator=args.integrator, rtol=args.rtol, every=args.every,
                       branch=args.branch, dt=args.dt, max_steps=args.max_steps,
                       progress=progress, interfacial_length=ell)
    saved = save(args.out, res.save, lambda: res.to_xarray(
        request=request_of(args), truth=_truth(res))) if args.out else None
    if args.json:
        out = res.to_json_dict(profiles=args.profiles)
        if saved is not None:
            out["file"] = str(saved)
            out["files"] = [str(f) for f in saved.files]
            out["file_notes"] = saved.notes
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
    print(f"  model: {_truth(res)}" + ("" if args.paper else " (--paper: the paper's)"))
    if res.spinodal:
        print(f"  WARNING: {d['message']}")
    print("       t        a(t)     R_f(t)   jump")
    for k in np.unique(np.linspace(0, res.t.size - 1, 11).astype(int)):
        fr = "-" if np.isnan(res.front[k]) else f"{res.front[k]:.5f}"
        jp = "-" if np.isnan(res.jump[k]) else f"{res.jump[k]:.3f}"
        print(f"  {res.t[k]:9.5f}  {res.radius[k]:8.5f}  {fr:>8}  {jp:>6}")
    if saved is not None:
        print("\n".join(saved.report()))
    return 0


def _truth(res: object) -> str:
    """The model a run solved, in words (the export's ``truth`` attribute)."""
    d = res.diagnostics  # type: ignore[attr-defined]
    ell = d.get("interfacial_length")
    return (f"full solver, {d.get('grid')} grid, N = {d.get('n')}, {d.get('integrator')}; "
            + (f"the regularized model at interfacial length {ell:g}" if ell
               else "the paper's model (no interfacial energy)"))
