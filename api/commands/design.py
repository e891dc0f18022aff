"""``thermogel design``: the heating that meets a target, the experiment that pins the model.

    thermogel design heating --gel ANB --t-start 302 --fraction 0.5 --at "60 s" \\
        --dry-radius-um 50 [--ramp --t-end 308 | --bath] [--validate] [--confidence 0.9]
    thermogel design experiment --gel ANB --t-start 302 --t-end 308 --fraction 0.8 \\
        --dry-radius-um 50 --size-noise 0.005 [--max-duration "1 h"] [--out plan.csv]

(dosing/design/, docs/design.md.)
"""

from __future__ import annotations

import argparse
from typing import Any

from .common import print_json
from .constants_options import add_constants_options, constants_values


def _seconds(field: str):
    def convert(text: str) -> float:
        try:
            return float(text)
        except ValueError:
            pass
        from dosing.quantity import seconds
        from solver.errors import ParameterError

        try:
            return float(seconds(text, field))
        except ParameterError as exc:
            raise argparse.ArgumentTypeError(f"{text!r}: {exc.valid}") from None
    convert.__name__ = "time"
    return convert


def _floats(text: str) -> tuple[float, ...]:
    try:
        return tuple(float(v) for v in text.replace(";", ",").split(",") if v.strip())
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: numbers separated by commas") from None


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``design heating`` and ``design experiment``."""
    p = sub.add_parser("design", help="the heating that meets a target; the experiment "
                       "that pins the model (docs/design.md)")
    ds = p.add_subparsers(dest="design_kind", required=True)
    h = ds.add_parser("heating", help="the jump temperature (or ramp rate, or bath set "
                      "point) at which the dose is out at the asked time")
    h.add_argument("--gel", default="ANB", help="preset or stored fitted gel (default ANB)")
    h.add_argument("--t-start", type=float, required=True, help="start temperature in K")
    dose = h.add_mutually_exclusive_group(required=True)
    dose.add_argument("--fraction", type=float, default=None,
                      help="dose as a fraction of the stored fluid")
    dose.add_argument("--dose-ug", type=float, default=None,
                      help="dose as a drug mass in ug (with --concentration-ug-per-ul)")
    h.add_argument("--concentration-ug-per-ul", type=float, default=None,
                   help="the drug's concentration in the stored fluid, ug/uL")
    h.add_argument("--at", type=_seconds("at"), required=True,
                   help="when the dose must be out, from the heating's start ('60 s', "
                        "'2 min'; a number is seconds)")
    h.add_argument("--dry-radius-um", type=float, required=True,
                   help="dry bead radius, um (a batch's reference size)")
    add_constants_options(h.add_argument_group("timescale constants (eq. timescale)"))
    h.add_argument("--size-cv", type=float, default=None,
                   help="a batch: lognormal sizes of this CV around --dry-radius-um")
    mode = h.add_mutually_exclusive_group()
    mode.add_argument("--ramp", action="store_true",
                      help="find the rate of 'Heat to T_END K at r K/min' (needs --t-end)")
    mode.add_argument("--bath", action="store_true",
                      help="find the set point of 'Bath at T K with a time constant of "
                           "--time-constant-s'")
    h.add_argument("--t-end", type=float, default=None, help="the ramp's final temperature, K")
    h.add_argument("--time-constant-s", type=float, default=30.0,
                   help="the bath's time constant (default 30 s)")
    h.add_argument("--range", type=_floats, default=None, metavar="LO,HI",
                   help="the search range (K; K/min for a ramp; default T_start to "
                        "T_start + 20 K, a ramp 0.05-2000 K/min)")
    h.add_argument("--validate", action="store_true",
                   help="polish on the truth: the full solver's validation at the heating "
                        "found, the target corrected by its ratio, until within 1 %%")
    h.add_argument("--confidence", type=float, default=None, metavar="P",
                   help="also the heating at which the dose is out by --at with probability "
                        "P (the envelope's parts read as log-uniform)")
    h.add_argument("--no-full", action="store_true",
                   help="search only where the reduced models answer (no blocking "
                        "full-solver runs)")
    h.add_argument("--cache", default=None, help="validation cache file")
    h.add_argument("--json", action="store_true", help="print one JSON object")
    h.set_defaults(func=run_heating)

    e = ds.add_parser("experiment", help="the shrinking-curve measurement that best pins "
                      "the answer's dominant parts, with its predicted envelope")
    e.add_argument("--gel", default="ANB", help="preset or stored fitted gel (default ANB)")
    e.add_argument("--t-start", type=float, required=True, help="start temperature in K")
    e.add_argument("--t-end", type=float, required=True, help="the answer's jump, K")
    e.add_argument("--fraction", type=float, required=True,
                   help="the answer's dose (fraction of the stored fluid)")
    e.add_argument("--dry-radius-um", type=float, required=True, help="the answer's bead, um")
    add_constants_options(e.add_argument_group("timescale constants (eq. timescale)"))
    e.add_argument("--size-noise", type=float, default=0.01,
                   help="relative noise of one measured radius (default 0.01)")
    e.add_argument("--max-duration", type=_seconds("max_duration"), default=3600.0,
                   help="the longest measurement ('1 h'; default 3600 s)")
    e.add_argument("--n-points", type=int, default=20, help="radii measured (default 20)")
    e.add_argument("--min-interval", type=_seconds("min_interval"), default=1.0,
                   help="shortest time between two samples (default 1 s)")
    e.add_argument("--sizes-um", type=_floats, default=None, metavar="R1,R2,...",
                   help="the dry bead radii the lab can make (default the answer's)")
    e.add_argument("--jumps", type=_floats, default=None, metavar="T1,T2,...",
                   help="candidate jump temperatures of the experiment, K (default: a few "
                        "where a front forms, the answer's own among them)")
    e.add_argument("--criterion", choices=["d-optimal", "interval"], default="d-optimal",
                   help="sampling times: robust D-optimal for tau (default) or the widest "
                        "predicted dose-time interval minimised")
    e.add_argument("--simulate", type=int, default=0, metavar="N",
                   help="also check the Fisher interval with N simulated fits over noise "
                        "seeds (default none)")
    e.add_argument("--out", default=None, metavar="plan.csv",
                   help="write the sampling table a lab fills in (time_s, radius_um)")
    e.add_argument("--cache", default=None, help="validation cache file")
    e.add_argument("--json", action="store_true", help="print one JSON object")
    e.set_defaults(func=run_experiment)


def _planner(cache: str | None) -> Any:
    from concurrent.futures import ThreadPoolExecutor

    from dosing import Planner

    return Planner(cache_path=cache, executor=ThreadPoolExecutor(1))


def _close(p: Any) -> None:
    p.close()
    p.jobs.executor.shutdown(wait=True)


def heating_target(args: argparse.Namespace) -> Any:
    """The HeatingTarget the options describe (checked: a ParameterError names the field)."""
    from dosing.design import HeatingTarget
    from solver.errors import ParameterError

    mode = "ramp" if args.ramp else "bath" if args.bath else "jump"
    if mode != "ramp" and args.t_end is not None:
        raise ParameterError("t_end", args.t_end, "only with --ramp (a jump's or a bath's "
                             "temperature is what is found)")
    rng = args.range
    if rng is not None and len(rng) != 2:
        raise ParameterError("range", list(rng), "two numbers LO,HI")
    return HeatingTarget(args.gel, args.t_start, args.at, fraction=args.fraction,
                         dose_ug=args.dose_ug,
                         concentration_ug_per_ul=args.concentration_ug_per_ul,
                         dry_radius_um=args.dry_radius_um, size_cv=args.size_cv, mode=mode,
                         t_end=args.t_end, time_constant_s=args.time_constant_s,
                         bounds=rng, validate=args.validate, confidence=args.confidence,
                         full=not args.no_full, constants=constants_values(args) or None)


def run_heating(args: argparse.Namespace) -> int:
    """Find the heating, print it (or JSON)."""
    from dosing.design import design_heating

    target = heating_target(args)
    p = _planner(args.cache)
    try:
        out = design_heating(target, p)
    finally:
        _close(p)
    if args.json:
        print_json(out.to_dict())
        return 0
    for line in out.lines():
        print(line)
    return 0


def experiment_ask(args: argparse.Namespace) -> Any:
    """The ExperimentAsk the options describe."""
    from dosing.design import ExperimentAsk

    return ExperimentAsk(args.gel, args.t_start, args.t_end, args.fraction,
                         args.dry_radius_um, size_noise=args.size_noise,
                         max_duration_s=args.max_duration, n_points=args.n_points,
                         min_interval_s=args.min_interval, sizes_um=args.sizes_um,
                         jumps=args.jumps, criterion=args.criterion,
                         simulate=args.simulate, constants=constants_values(args) or None)


def run_experiment(args: argparse.Namespace) -> int:
    """Design the experiment, print it (or JSON), write its sampling table."""
    import sys
    from pathlib import Path

    from dosing.design import design_experiment

    ask = experiment_ask(args)
    p = _planner(args.cache)
    try:
        out = design_experiment(ask, p)
    finally:
        _close(p)
    d = out.to_dict()
    if args.out:
        Path(args.out).write_text(out.csv())
        d["file"] = str(args.out)
        print(f"sampling table written to {args.out}", file=sys.stderr)
    if args.json:
        print_json(d)
        return 0
    for line in out.lines():
        print(line)
    return 0
