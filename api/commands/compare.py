"""``thermogel compare``: two release profiles compared the way the FDA asks.

    thermogel compare REF.csv TEST.csv [--boot 1000] [--seed 0] [--json] [--plot both.png]

f1 and f2 on the guidance's points (zero excluded, one point after 85 % of both), the CV
rule on the replicate units, the outcome in the guidance's words, and Shah et al.'s
bootstrap f2 (90 % BCa interval) when units are given (``dosing.analysis.similarity``).
"""

from __future__ import annotations

import argparse

from .common import print_json
from .outfile import add_format_option, figure_path


def register(sub: argparse._SubParsersAction) -> None:
    """Add the sub-command."""
    from dosing.analysis.similarity import CONFIDENCE, N_BOOT

    p = sub.add_parser("compare", help="f1/f2 of two release profiles with the FDA rules "
                       "and a bootstrap f2 (Shah et al. 1998)")
    p.add_argument("reference", help="reference profile CSV (time, one column per unit)")
    p.add_argument("test", help="test profile CSV, on the same times")
    p.add_argument("--boot", type=int, default=N_BOOT,
                   help=f"bootstrap draws (default {N_BOOT}, at least 1000)")
    p.add_argument("--seed", type=int, default=0, help="bootstrap seed (default 0)")
    p.add_argument("--confidence", type=float, default=CONFIDENCE,
                   help="the bootstrap interval's level (default 0.90, Shah's)")
    p.add_argument("--loaded-ug", type=float, default=None,
                   help="the load, when the releases are given as masses")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--plot", default=None, metavar="PNG",
                   help="draw both profiles with their units' spread (matplotlib)")
    add_format_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Read both, compare, print (or JSON), plot."""
    from dosing.analysis import read_profile
    from dosing.analysis.similarity import compare

    ref = read_profile(args.reference, args.loaded_ug)
    test = read_profile(args.test, args.loaded_ug)
    rep = compare(ref, test, n_boot=args.boot, seed=args.seed,
                  confidence=args.confidence).to_dict()
    if args.plot:
        from api.plots.release_analysis import draw_comparison

        rep["plots"] = [str(draw_comparison(rep, ref.times.tolist(),
                                            figure_path(args.plot, args.format)))]
    if args.json:
        print_json(rep)
        return 0
    print(f"{ref.label} (reference, {ref.n_units} units) against {test.label} (test, "
          f"{test.n_units} units)")
    print(f"  {rep['notes'][0]}")
    print(f"  {rep['f1_outcome']}")
    print(f"  {rep['outcome']}")
    for name, c in rep["conditions"].items():
        print(f"  [{'met' if c['met'] else 'NOT met'}] {c['rule']}"
              + ("" if c["met"] or name != "cv" else f": {c['found']}"))
    b = rep["bootstrap"]
    print(f"  {b['outcome']}; {b['n_boot']} draws, seed {b['seed']}, percentile interval "
          f"{b['interval_percentile'][0]:.2f}-{b['interval_percentile'][1]:.2f}"
          if b else "  no bootstrap: neither profile has replicate units")
    for p in rep.get("plots", []):
        print(f"wrote {p}")
    return 0
