"""Full solver speed and accuracy: wall time and max error of a(t) per case, grid, integrator.

Run:  .venv/bin/python benchmarks/full_solver.py [--n 400] [--repeats 3] [--rtols 1e-6,1e-4]
                                                  [--quick]

For each case (smooth: ANB 308->302, HHT 308->304, HHT 304->307.6; fronts: ANB 302->308,
HHT 304->308) and grid, after a warm-up run: the median wall time of the implicit
integrator (RODASP) at each rtol, its steps, and the max relative error of a(t) against a
reference run on the same grid and N (rtol 1e-10; dense a(t) from the per-step record).
The explicit forward Euler (the paper's scheme; dt = 0.8 of the stability limit, and the
paper's dt = 1e-8) runs a short horizon of the smooth ANB case.  The max error of a(t) is
taken over all t, so in the front cases it is dominated by the timing of the fast edge
collapse as the front forms (HHT: t ~ 0.01); later errors are ~10x smaller.
--quick skips the front cases.
Targets (issue 3, this 2-core machine): smooth < 0.1 s at N = 400; ANB front < 3 s
(Eulerian) and < 1 s (Lagrangian).  Timings are noisy when other jobs share the machine.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from solver import ANB, HHT
from solver.full import FullResult, simulate

SMOOTH = [("ANB 308->302", ANB, 308.0, 302.0, 1.0), ("HHT 308->304", HHT, 308.0, 304.0, 0.5),
          ("HHT 304->307.6", HHT, 304.0, 307.6, 8.0)]
FRONT = [("ANB 302->308", ANB, 302.0, 308.0, 0.3), ("HHT 304->308", HHT, 304.0, 308.0, 0.3)]
EXPLICIT_HORIZON = 0.002


def dense_radius(res: FullResult, times: np.ndarray) -> np.ndarray:
    """a(t) at ``times`` from the per-step record (cubic Hermite)."""
    t, a, d = res.step_t, res.step_radius, res.step_rate
    keep = np.concatenate([[True], np.diff(t) > 0])
    t, a, d = t[keep], a[keep], d[keep]
    i = np.clip(np.searchsorted(t, times) - 1, 0, t.size - 2)
    h = t[i + 1] - t[i]
    s = (times - t[i]) / h
    return ((1 + 2 * s) * (1 - s) ** 2 * a[i] + s * (1 - s) ** 2 * h * d[i]
            + s * s * (3 - 2 * s) * a[i + 1] + s * s * (s - 1) * h * d[i + 1])


def max_error(res: FullResult, ref: FullResult, until: float) -> float:
    """Max relative difference of a(t) on 4001 points of [0, until] (the explicit
    integrator records a(t) only at its outputs: compared there)."""
    if res.diagnostics["integrator"] == "explicit":
        return float(np.max(np.abs(res.radius - dense_radius(ref, res.t)) / res.radius))
    times = np.linspace(0.0, until, 4001)
    a, b = dense_radius(res, times), dense_radius(ref, times)
    return float(np.max(np.abs(a - b) / b))


def timed(repeats: int, **kwargs: object) -> tuple[float, FullResult]:
    """Median wall time of ``simulate(**kwargs)`` and the last result."""
    walls, res = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        res = simulate(**kwargs)
        walls.append(time.perf_counter() - t0)
    return float(np.median(walls)), res


def main() -> int:
    """Print the table."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=400)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--rtols", default="1e-6,1e-5,1e-4")
    ap.add_argument("--quick", action="store_true", help="skip the front-case references")
    args = ap.parse_args()
    rtols = [float(x) for x in args.rtols.split(",")]
    n = args.n
    for grid in ("eulerian", "lagrangian"):  # warm-up: load or compile the kernels
        simulate(ANB, 302, 308, until=1e-3, grid=grid, n=20)
        simulate(ANB, 308, 302, until=1e-4, grid=grid, n=20, integrator="explicit")
    print(f"{'case':<16}{'grid':<12}{'N':>5}  {'integrator':<18}{'wall s':>8}{'steps':>8}"
          f"{'max err a(t)':>14}")
    cases = SMOOTH + ([] if args.quick else FRONT)
    for name, gel, t0, t1, until in cases:
        for grid in ("eulerian", "lagrangian"):
            base = {"gel": gel, "t_start": t0, "t_end": t1, "until": until, "grid": grid,
                    "n": n, "every": until / 200}
            ref = simulate(**base, rtol=1e-10, atol=1e-13)
            for rtol in rtols:
                wall, res = timed(args.repeats, **base, rtol=rtol)
                print(f"{name:<16}{grid:<12}{n:>5}  {'implicit ' + format(rtol, 'g'):<18}"
                      f"{wall:>8.3f}{res.diagnostics['steps']:>8}"
                      f"{max_error(res, ref, until):>14.2e}", flush=True)
    name, gel, t0, t1, _ = SMOOTH[0]
    base = {"gel": gel, "t_start": t0, "t_end": t1, "until": EXPLICIT_HORIZON, "n": n,
            "every": EXPLICIT_HORIZON / 20}
    ref = simulate(**base, rtol=1e-10, atol=1e-13)
    wall_i, res_i = timed(args.repeats, **base)
    wall_e, res_e = timed(1, **base, integrator="explicit")
    wall_p, res_p = timed(1, **base, integrator="explicit", dt=1e-8)
    for label, wall, res in (("implicit 1e-6", wall_i, res_i), ("explicit 0.8 lim", wall_e, res_e),
                             ("explicit dt=1e-8", wall_p, res_p)):
        print(f"{name + ' t<=' + format(EXPLICIT_HORIZON, 'g'):<22}{'eulerian':<12}{n:>5}  "
              f"{label:<18}{wall:>8.3f}{res.diagnostics['steps']:>8}"
              f"{max_error(res, ref, EXPLICIT_HORIZON):>14.2e}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
