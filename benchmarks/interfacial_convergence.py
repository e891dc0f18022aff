"""Interfacial energy (docs/interfacial.md): grid convergence at fixed ell, the limit ell -> 0,
the smooth cases, and the sharp-interface front model.

    .venv/bin/python benchmarks/interfacial_convergence.py                 # everything (~45 min)
    .venv/bin/python benchmarks/interfacial_convergence.py --section grid  # one section
    .venv/bin/python benchmarks/interfacial_convergence.py --quick         # coarse ladders

Sections:
  grid    80% dose time of ANB 302->308 K and HHT 304->308 K vs N at ell = 0.02, 0.01, 0.005
          on both grids (--all-eulerian adds ell = 0.0025), wall time, observed order, last
          change, the Richardson-extrapolated value with its estimated error, and the two
          grids' gap.
  limit   the dose times 10%..90% at ell = 0.01 ... 0.000625 (Lagrangian, resolved) and when
          the front nucleates at the edge; the limit ell -> 0 of the times (plain Richardson)
          and of the times after nucleation (dosing.ladder.dose_limit, with its error bound);
          the paper's model (ell = 0) on both grids for comparison.
  smooth  max relative change of a(t) by the term in the smooth cases, and its order in ell.
  model   the paper's and the sharp-interface front models against the ell -> 0 limit.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from dosing.ladder import Limit, dose_limit, observed_order, richardson
from solver.equilibrium import equilibrium
from solver.front import front_trajectory
from solver.front.result import fraction_radius
from solver.front.sharp import sharp_front_trajectory
from solver.full import simulate
from solver.gel import preset
from solver.phase import nucleation_level

CASES = {"ANB": (302.0, 308.0), "HHT": (304.0, 308.0)}
ELLS = (0.02, 0.01, 0.005)  # both grids converge to 0.5 % here in minutes
LIMIT_ELLS = (0.01, 0.005, 0.0025, 0.00125, 0.000625)
FRACTIONS = np.arange(1, 10) / 10.0
# cells per ell on each grid: the Lagrangian grid resolves the interface with ~2/ell cells,
# the Eulerian grid (uniform in r, the shrunken side compressed) needs about eight times more
LADDER = {"lagrangian": (2, 4, 8), "eulerian": (8, 16, 32)}
LIMIT_CELLS = 4  # Lagrangian cells per ell for the ell -> 0 runs (4 and 8 agree to 1e-4)
RTOL = 1e-5
UNTIL = {"ANB": 0.1, "HHT": 0.25}  # first try for the run length (doubled if too short)


def dose_times(gel: str, ell: float, grid: str, n: int,
               fractions: np.ndarray = FRACTIONS) -> tuple[np.ndarray, float, int, float | None]:
    """(times to expel each fraction, wall time, steps, nucleation time) of one regularized
    run (nucleation None if it never happens); the front has nucleated at the edge when the
    outermost cell's porosity falls midway between the start and final porosities
    (solver.phase.nucleation_level; step resolved)."""
    t_start, t_end = CASES[gel]
    a0 = equilibrium(preset(gel), t_start).stretch
    targets = fraction_radius(a0, fractions)
    until = UNTIL[gel] * (1.6 if fractions.max() > 0.8 else 1.0)
    started = time.perf_counter()
    while True:
        res = simulate(gel, t_start, t_end, until=until, grid=grid, n=n,
                       interfacial_length=ell, rtol=RTOL, every=until / 400)
        if res.radius.min() <= targets.min() or until > 5.0:
            break
        until *= 2.0
    times = np.array([_crossing(res, a) for a in targets])
    t_nuc = res.nucleation_time(nucleation_level(preset(gel), t_start, t_end))
    return times, time.perf_counter() - started, int(res.diagnostics["steps"]), t_nuc


def _crossing(res: object, a: float) -> float:
    try:
        return float(res.time_to_radius(a))  # type: ignore[attr-defined]
    except ValueError:
        return math.nan


def section_grid(gels: list[str], quick: bool, all_eulerian: bool = False) -> None:
    print("== grid convergence of the 80% dose time at fixed ell (rtol 1e-5) ==")
    print(f"{'gel':4} {'grid':10} {'ell':>7} {'N':>6} {'t80':>10} {'wall s':>7} {'steps':>6}")
    finest: dict[tuple[str, str, float], float] = {}
    for gel in gels:
        for grid in ("lagrangian", "eulerian"):
            ells = ELLS[:1] if quick else ELLS + ((0.0025,) if all_eulerian else ())
            for ell in ells:
                values = []
                for c in LADDER[grid][:2] if quick else LADDER[grid]:
                    n = int(round(c / ell))
                    t, wall, steps, _ = dose_times(gel, ell, grid, n, np.array([0.8]))
                    values.append(float(t[0]))
                    print(f"{gel:4} {grid:10} {ell:7.4f} {n:6d} {t[0]:10.6f} {wall:7.2f} "
                          f"{steps:6d}", flush=True)
                change = abs(values[-1] - values[-2]) / values[-1]
                order = observed_order(values) if len(values) >= 3 else math.nan
                extra = richardson(values, order) if math.isfinite(order) else values[-1]
                print(f"     -> last refinement changes t80 by {100 * change:.3f}%, "
                      f"observed order {order:.2f}, extrapolated {extra:.6f} (finest off by "
                      f"{100 * abs(values[-1] - extra) / extra:.3f}%)")
                finest[(gel, grid, ell)] = (values[-1], extra)
        for ell in ELLS[:1] if quick else ELLS:
            if (gel, "eulerian", ell) not in finest:
                continue
            (lag, lag_x), (eul, eul_x) = (finest[(gel, g, ell)] for g in ("lagrangian",
                                                                           "eulerian"))
            print(f"  {gel} ell={ell}: grids differ by {100 * abs(eul - lag) / lag:.3f}% "
                  f"(finest), {100 * abs(eul_x - lag_x) / lag_x:.3f}% (extrapolated)")


def section_limit(gels: list[str], quick: bool) -> dict[str, list[Limit]]:
    print("== the limit ell -> 0 (Lagrangian, N = 4/ell): dose times for 10%..90%, and the "
          "time the front nucleates at the edge ==")
    limits = {}
    ells = LIMIT_ELLS[:3] if quick else LIMIT_ELLS
    for gel in gels:
        rows, nucs = [], []
        for ell in ells:
            n = int(round(LIMIT_CELLS / ell))
            t, wall, _, t_nuc = dose_times(gel, ell, "lagrangian", n)
            rows.append(t)
            nucs.append(t_nuc)
            print(f"{gel} ell={ell:<8} N={n:5d} " + " ".join(f"{x:.5f}" for x in t)
                  + "  nucleation " + ("none" if t_nuc is None else f"{t_nuc:.5f}")
                  + f"  ({wall:.1f} s)", flush=True)
        arr = np.array(rows)
        orders = np.array([observed_order(list(arr[:, j])) for j in range(arr.shape[1])])
        plain = np.array([richardson(list(arr[:, j]), orders[j]) for j in range(arr.shape[1])])
        print(f"{gel} order in ell   " + " ".join(f"{x:7.2f}" for x in orders))
        print(f"{gel} ell -> 0       " + " ".join(f"{x:.5f}" for x in plain)
              + "   (plain Richardson, last three ell)")
        last = list(ells[-3:])
        lims = [dose_limit(last, list(arr[-3:, j]), nucs[-3:])
                for j in range(arr.shape[1])]
        print(f"{gel} after nucl.    " + " ".join(f"{x.time:.5f}" for x in lims)
              + "   (dosing.ladder.dose_limit, last three ell)")
        print(f"{gel} its bound      " + " ".join(f"{x.error / x.time:6.2%} " for x in lims))
        limits[gel] = lims
        t_start, t_end = CASES[gel]
        a80 = fraction_radius(equilibrium(preset(gel), t_start).stretch, 0.8)
        for grid, n in (("eulerian", 400), ("lagrangian", 400)):
            res = simulate(gel, t_start, t_end, until=0.4, grid=grid, n=n, rtol=RTOL)
            print(f"{gel} ell = 0 (paper's model), {grid} N={n}: t80 = "
                  f"{res.time_to_radius(a80):.5f}")
    return limits


def section_smooth(quick: bool) -> None:
    print("== smooth cases: max relative change of a(t) by the term (N = 400) ==")
    for gel, t_start, t_end, until in (("ANB", 308.0, 302.0, 1.0), ("HHT", 304.0, 307.6, 8.0)):
        for grid in ("lagrangian", "eulerian"):
            base = simulate(gel, t_start, t_end, until=until, grid=grid, n=400, rtol=1e-7,
                            every=until / 50).radius
            changes = []
            for ell in (0.02, 0.01, 0.005):
                a = simulate(gel, t_start, t_end, until=until, grid=grid, n=400, rtol=1e-7,
                             every=until / 50, interfacial_length=ell).radius
                changes.append(float(np.max(np.abs(a - base) / base)))
            print(f"{gel} {t_start:g}->{t_end:g} {grid:10}: change at ell = 0.02, 0.01, 0.005: "
                  + ", ".join(f"{c:.2e}" for c in changes)
                  + f"; order {math.log2(changes[-2] / changes[-1]):.2f} "
                  "(O(ell^2) would be 2)")
            if quick:
                break


def section_model(gels: list[str], limits: dict[str, list[Limit]]) -> None:
    print("== front models against the regularized limit ell -> 0 (after nucleation): "
          "relative time error, '+' where within the limit's error bound ==")
    for gel in gels:
        t_start, t_end = CASES[gel]
        paper = front_trajectory(preset(gel), t_start, t_end)
        sharp = sharp_front_trajectory(preset(gel), t_start, t_end)
        ref = np.array([x.time for x in limits[gel]])
        bound = np.array([x.error for x in limits[gel]])
        for name, model in (("paper", paper), ("sharp", sharp)):
            t = np.array([model.time_to_fraction(f) for f in FRACTIONS])
            err = (t - ref) / ref
            inside = np.abs(t - ref) <= bound
            print(f"{gel} {name:5} " + " ".join(f"{100 * e:6.1f}%{'+' if k else ' '}"
                                             for e, k in zip(err, inside, strict=True)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--section", choices=["grid", "limit", "smooth", "model", "all"],
                    default="all")
    ap.add_argument("--gel", choices=["ANB", "HHT", "both"], default="both")
    ap.add_argument("--quick", action="store_true", help="coarse ladders (minutes, not tens)")
    ap.add_argument("--all-eulerian", action="store_true",
                    help="also ell = 0.0025 (Eulerian N up to 12800: hours)")
    args = ap.parse_args()
    gels = ["ANB", "HHT"] if args.gel == "both" else [args.gel]
    if args.section in ("grid", "all"):
        section_grid(gels, args.quick, args.all_eulerian)
    limits: dict[str, list[Limit]] = {}
    if args.section in ("limit", "model", "all"):
        limits = section_limit(gels, args.quick)
    if args.section in ("smooth", "all"):
        section_smooth(args.quick)
    if args.section in ("model", "all"):
        section_model(gels, limits)


if __name__ == "__main__":
    main()
