"""Print the front model's error against the full solver over doses (the planner's prior).

    python -m dosing.calibrate [--cache PATH]

For ANB 302->308 K and HHT 304->308 K and doses 10 %..90 % of the stored fluid: the
front model's time (started from the equilibrium alone), the full solver's on the
Eulerian (N = 400) and Lagrangian grids, and the relative gaps |t_front - t_grid| / t_front.
The largest gap per dose, over both cases and grids, is the prior error estimate of an
unvalidated answer (planner.PRIOR_GAPS, rounded up).
"""

from __future__ import annotations

import argparse
from concurrent.futures import ThreadPoolExecutor

from .planner import Planner, front_prior
from .request import DoseRequest

CASES = (("ANB", 302.0, 308.0), ("HHT", 304.0, 308.0))
FRACTIONS = tuple(round(0.1 * k, 1) for k in range(1, 10))


def table(planner: Planner) -> list[dict[str, float | str]]:
    """One row per (case, dose): front time, both grids' times, gaps."""
    rows = []
    for gel, t0, t1 in CASES:
        for f in FRACTIONS:
            ans = planner.dose(DoseRequest(gel, t0, t1, dose_fraction=f), validate=True)
            g = ans.validation["grids"]
            te, tl = g["eulerian"].get("time"), g["lagrangian"].get("time")
            rows.append({"case": f"{gel} {t0:g}->{t1:g}", "fraction": f, "model": ans.model,
                         "front": ans.time, "eulerian": te, "lagrangian": tl,
                         "gap_eulerian": abs(ans.time - te) / ans.time,
                         "gap_lagrangian": abs(ans.time - tl) / ans.time,
                         "volume_error_eulerian": g["eulerian"].get("front_volume_error")})
    return rows


def main(argv: list[str] | None = None) -> int:
    """Print the table and the largest gap."""
    p = argparse.ArgumentParser(prog="python -m dosing.calibrate", description=__doc__)
    p.add_argument("--cache", default=None, help="validation cache file")
    args = p.parse_args(argv)
    with Planner(cache_path=args.cache, executor=ThreadPoolExecutor(2)) as planner:
        rows = table(planner)
    print(f"{'case':<14}{'f':>5}{'front':>10}{'eulerian':>10}{'lagrang.':>10}"
          f"{'gap E':>9}{'gap L':>9}{'dV E':>9}")
    for r in rows:
        print(f"{r['case']:<14}{r['fraction']:>5.1f}{r['front']:>10.4f}{r['eulerian']:>10.4f}"
              f"{r['lagrangian']:>10.4f}{r['gap_eulerian']:>9.1%}{r['gap_lagrangian']:>9.1%}"
              f"{r['volume_error_eulerian']:>9.2%}")
    print("largest gap per dose (either case, either grid) against the planner's prior:")
    for f in FRACTIONS:
        worst = max(max(r["gap_eulerian"], r["gap_lagrangian"]) for r in rows
                    if r["fraction"] == f)
        print(f"  f = {f:.1f}: measured {worst:7.1%}   prior {front_prior(f):7.1%}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
