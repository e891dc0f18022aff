"""How far the no-bead-size truth (ell = 1e-4) is from the sharp limit, per dose (issue 28).

Runs the regularized model on the moving grid (400 cells, rtol 1e-5, the truth's settings)
at ell = 1e-4, 5e-5, 2.5e-5 for ANB 302 -> 308 K and HHT 304 -> 308 K and prints the time of
each fluid dose (10-50 % by default: the small doses, where the front's nucleation delay at
the edge shrinks with ell) and the relative change from ell = 1e-4 to 2.5e-5.  About 30-60 s
of CPU per run on the shared machine; ``--until`` longer for the larger doses.

    .venv/bin/python benchmarks/sharp_limit.py [--gels ANB HHT] [--until 0.02]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from solver.full import simulate

STARTS = {"ANB": 302.0, "HHT": 304.0}
ELLS = (1e-4, 5e-5, 2.5e-5)
DOSES = (0.1, 0.3, 0.5, 0.7, 0.9)


def dose_times(gel: str, ell: float, until: float, n: int = 400) -> list[float | None]:
    """Times at which DOSES of the stored fluid are expelled (None past ``until``)."""
    res = simulate(gel, STARTS[gel], 308.0, grid="moving", n=n, interfacial_length=ell,
                   until=until, every=until / 4000, rtol=1e-5)
    a3 = res.radius**3
    frac = (a3[0] - a3) / (a3[0] - 1.0)
    out: list[float | None] = []
    for f in DOSES:
        hit = np.nonzero(frac >= f)[0]
        if hit.size == 0 or hit[0] == 0:
            out.append(None)
            continue
        j = int(hit[0])
        out.append(float(res.t[j - 1] + (f - frac[j - 1]) / (frac[j] - frac[j - 1])
                         * (res.t[j] - res.t[j - 1])))
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--gels", nargs="+", default=list(STARTS), choices=list(STARTS))
    p.add_argument("--until", type=float, default=0.02)
    args = p.parse_args()
    for gel in args.gels:
        rows = {}
        for ell in ELLS:
            started = time.perf_counter()
            rows[ell] = dose_times(gel, ell, args.until)
            print(f"{gel} ell = {ell:g}: {time.perf_counter() - started:.1f} s", flush=True)
        print(f"{gel} {STARTS[gel]:g} -> 308 K   " + "  ".join(f"{e:>10g}" for e in ELLS)
              + "   change 1e-4 -> 2.5e-5")
        for k, f in enumerate(DOSES):
            ts = [rows[e][k] for e in ELLS]
            if any(t is None for t in ts):
                continue
            change = ts[0] / ts[-1] - 1.0
            print(f"  {f:>4.0%} dose          " + "  ".join(f"{t:10.6g}" for t in ts)
                  + f"   {change:+.1%}")


if __name__ == "__main__":
    main()
