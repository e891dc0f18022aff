"""Print the front model's validated error over doses (the planner's prior).

    python -m dosing.fits.calibrate [--cache PATH] [--method direct|ladder] [--interfacial-length L]

For ANB 302->308 K and HHT 304->308 K and doses 10 %..90 % of the stored fluid: the
front model's time (started from the equilibrium alone), the truth's time and the
validated error estimate.  With the default truth (``--method direct``: the regularized
model on the moving grid at ell = 1e-4, no bead size, standing for the limit ell -> 0) the
estimate is the gap to it plus its numerical bound (n vs n / 2 cells); with ``--method
ladder`` (the limit ell -> 0 from the ladder L, L/2, L/4) the gap to the limit plus the
limit's error bound; with ``--interfacial-length 0`` (the paper's model) it is the
largest gap to either grid.  The largest estimate per dose over both cases is the prior
of an unvalidated answer (validation.PRIOR_GAPS, rounded up).
"""

from __future__ import annotations

import argparse
from concurrent.futures import ThreadPoolExecutor

from ..planner import Planner
from ..request import DoseRequest
from ..runs.scenario import SolverSettings
from ..validation import PRIOR_FRACTIONS, front_prior

CASES = (("ANB", 302.0, 308.0), ("HHT", 304.0, 308.0))


def table(planner: Planner, settings: SolverSettings) -> list[dict[str, float | str]]:
    """One row per (case, dose): model, front time, truth time, validated estimate."""
    rows = []
    for gel, t0, t1 in CASES:
        for f in PRIOR_FRACTIONS:
            ans = planner.dose(DoseRequest(gel, t0, t1, dose_fraction=f, settings=settings),
                               validate=True)
            v = ans.validation
            rows.append({"case": f"{gel} {t0:g}->{t1:g}", "fraction": f, "model": ans.model,
                         "front": ans.time, "truth": v.time, "truth_error": v.error,
                         "estimate": ans.error_estimate})
    return rows


def main(argv: list[str] | None = None) -> int:
    """Print the table and the largest estimate per dose."""
    p = argparse.ArgumentParser(prog="python -m dosing.fits.calibrate", description=__doc__)
    p.add_argument("--cache", default=None, help="validation cache file")
    p.add_argument("--method", choices=["direct", "ladder"], default="direct",
                   help="the truth: direct (default) or the ladder's limit")
    p.add_argument("--interfacial-length", type=float, default=None, metavar="L",
                   help="truth's interfacial length (default: the planner's; 0: the paper's)")
    args = p.parse_args(argv)
    settings = SolverSettings(interfacial_length=args.interfacial_length, method=args.method)
    with Planner(cache_path=args.cache, executor=ThreadPoolExecutor(2)) as planner:
        rows = table(planner, settings)
    print(f"{'case':<14}{'f':>5}{'model':>13}{'front':>10}{'truth':>10}{'truth err':>11}"
          f"{'estimate':>10}")
    for r in rows:
        print(f"{r['case']:<14}{r['fraction']:>5.1f}{r['model']:>13}{r['front']:>10.5f}"
              f"{r['truth']:>10.5f}{r['truth_error']:>11.2%}{r['estimate']:>10.1%}")
    model = str(rows[0]["model"])
    if model == "front-sharp" and settings.direct:
        model = "front-sharp-direct"
    print(f"largest validated estimate per dose (either case) against the prior of '{model}':")
    for f in PRIOR_FRACTIONS:
        worst = max(float(r["estimate"]) for r in rows if r["fraction"] == f)
        print(f"  f = {f:.1f}: measured {worst:7.1%}   prior {front_prior(f, model):7.1%}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
