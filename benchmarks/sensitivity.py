"""Global sensitivity on the front model (issue 25): Sobol indices of the dose time in
seconds for six inputs with 1,000 base samples (N (D + 2) = 8,000 answers), timed.

    python -m benchmarks.sensitivity            # six inputs; t_end changes the jump
    python -m benchmarks.sensitivity --cheap    # the five inputs that keep one jump

Inputs that change the gel or the jump (t_end, gel parameters) cost a front trajectory
per distinct value (Saltelli's design holds 2 N of them per input); the bead size, the
constants and the dose reuse one trajectory.
"""

from __future__ import annotations

import argparse
import time

from dosing.studies.sensitivity import sensitivity

CHEAP = ["dry_radius_um=10:100:log", "permeability_m2=1e-20:1e-19:log",
         "viscosity_pa_s=5e-4:2e-3", "polymer_volume_m3=1e-25:1e-24:log",
         "dose_fraction=0.3:0.9"]
WITH_JUMP = [*CHEAP, "t_end=307.5:309"]


def main(argv: list[str] | None = None) -> None:
    """Run once and print the wall time and the indices."""
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--cheap", action="store_true", help="leave t_end out (one jump)")
    ap.add_argument("--samples", type=int, default=1000)
    args = ap.parse_args(argv)
    vary = CHEAP if args.cheap else WITH_JUMP
    t0 = time.perf_counter()
    res = sensitivity("ANB", 302.0, 308.0, 0.8, vary, samples=args.samples)
    wall = time.perf_counter() - t0
    print(f"{len(vary)} inputs, N = {args.samples}: {res.evaluations} answers in {wall:.1f} s")
    for n in res.names:
        i = res.indices[n]
        print(f"  {n:18s} S1 = {i['S1']:6.3f} +- {i['S1_conf']:.3f}   "
              f"ST = {i['ST']:6.3f} +- {i['ST_conf']:.3f}")


if __name__ == "__main__":
    main()
