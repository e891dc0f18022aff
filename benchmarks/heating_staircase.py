"""Heating protocols on the planner's truth: the staircase adapter's convergence and cost.

Run:  .venv/bin/python benchmarks/heating_staircase.py [--rates 5 1] [--fractions 0.3 0.8]

A 50 um dry ANB bead (the bead's own ell = 8e-5, moving grid, n = 400, rtol 1e-5) heated
from 302 K to 308 K at each rate: the dose time from the protocol's start when the ramp
runs as staircases of 0.2, 0.1, 0.05 (the planner's) and 0.025 K per stair, with the wall
time of each run, beside the instant jump's time (the old answer).  The successive gaps
show the staircase's observed order and the 0.05 K staircase's error.  Until the solver's
continuous T(t) lands this is the planner's ramp.
"""

from __future__ import annotations

import argparse
import time

from dosing.heating.grammar import Protocol
from dosing.heating.program import staircase
from dosing.units import PhysicalConstants, radius_after_dose, timescale
from solver.full import simulate
from solver.gel import preset

STAIRS = (0.2, 0.1, 0.05, 0.025)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rates", type=float, nargs="+", default=[5.0])
    ap.add_argument("--fractions", type=float, nargs="+", default=[0.3, 0.8])
    args = ap.parse_args()
    gel, dry = preset("ANB"), 50.0
    tau = timescale(dry, 308.0, PhysicalConstants.paper()).seconds  # the recorded table's
    opts = dict(grid="moving", n=400, rtol=1e-5, interfacial_length=4e-3 / dry)
    jump = simulate(gel, 302.0, protocol=[(0.5, 308.0)], **opts)
    a0 = float(jump.radius[0])
    targets = {f: radius_after_dose(a0, f) for f in args.fractions}
    print(f"tau = {tau:.4g} s at 308 K; jump: " + ", ".join(
        f"{f:.0%} {jump.time_to_radius(a) * tau:.4g} s" for f, a in targets.items()))
    for rate in args.rates:
        prot = Protocol(302.0, [f"Heat to 308 K at {rate:g} K/min"])
        ramp_tau = 6.0 / rate * 60.0 / tau
        prev: dict[float, float] = {}
        for k in STAIRS:
            st = staircase(prot.program(tau), 0.5 + ramp_tau, k)
            t0 = time.perf_counter()
            res = simulate(gel, 302.0, protocol=st, **opts)
            wall = time.perf_counter() - t0
            cells = []
            for f, a in targets.items():
                s = res.time_to_radius(a) * tau
                gap = "" if f not in prev else f" (gap {abs(s - prev[f]) / s:.2%})"
                cells.append(f"{f:.0%} {s:.5g} s{gap}")
                prev[f] = s
            print(f"{rate:g} K/min, {k:g} K/stair ({len(st)} steps, {wall:.1f} s): "
                  + ", ".join(cells), flush=True)


if __name__ == "__main__":
    main()
