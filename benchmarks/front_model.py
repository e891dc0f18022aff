"""Front model: speed, and accuracy against the full solver (paper sec. FrontSoln, fig. 13).

Run:  .venv/bin/python benchmarks/front_model.py [--n-lagrangian 400] [--no-full]

Prints
  * speed: one whole trajectory to the centre and one dose query, warm (median of repeats);
  * ANB 302->308 at t = 0.2: the closed-form A at the full solution's (a, R_f) against
    a^2 da/dt of the full solution (eq. SphereEvolve_Dimless), with R_f as tracked by the full
    solver and as implied by solid conservation, and A / R_f (the paper's printed -3.25);
  * the 80% doses (a = 1.47 ANB, 1.67 HHT) started from the full solver's state at
    t = 0.001 / 0.01: the paper's two ODEs (measured R_f) and the conservative form;
  * per gel, full grid (Eulerian N = 400, Lagrangian) and start (equilibrium, full@t0
    conservative, full@t0 paper): the max relative error of the times to expel 10%, ..., 90%
    of the stored fluid (doses the full solution passes before t0 are skipped).
The full solver's front speed depends on the grid (the model is ill-posed there, see the
full-solver issue), so the Eulerian and Lagrangian errors differ in sign and size.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import numpy as np

from solver import ANB, HHT
from solver.front import flux_constant, fraction_radius, front_levels, front_trajectory
from solver.front.evolve import front_of_radius

# gel, T_start, T_end, the paper's start time t0, the paper's 80% radius, its 80% time
CASES = {"ANB": (ANB, 302.0, 308.0, 0.001, 1.47, 0.092), "HHT": (HHT, 304.0, 308.0, 0.01, 1.67,
                                                                  0.123)}
UNTIL = {("ANB", "eulerian"): 0.21, ("HHT", "eulerian"): 0.23,  # past the 90% dose (and t=0.2)
         ("ANB", "lagrangian"): 0.21, ("HHT", "lagrangian"): 0.34}
FRACTIONS = np.arange(1, 10) / 10.0


def median_time(fun: Callable[[], object], repeats: int) -> float:
    """Median wall time of ``fun`` in seconds after one warm-up call."""
    fun()
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fun()
        times.append(time.perf_counter() - t)
    return float(np.median(times))


def speed(repeats: int) -> None:
    """Warm timings of a whole trajectory and of a single dose query."""
    print("speed (warm, median):")
    for name, (gel, t0, t1, _, a80, _) in CASES.items():
        def whole(gel=gel, t0=t0, t1=t1) -> object:
            return front_trajectory(gel, t0, t1)

        res = whole()
        tr = median_time(whole, repeats)
        q = median_time(lambda res=res, a80=a80: res.time_to_radius(a80), 20 * repeats)
        print(f"  {name}: whole trajectory {tr * 1e3:6.3f} ms, dose query {q * 1e6:6.1f} us")


def full_run(name: str, grid: str, n: int):
    """The full solver (Eulerian as the paper, or Lagrangian) to past the 90% dose."""
    from solver.full import simulate

    gel, t0, t1 = CASES[name][:3]
    tic = time.perf_counter()
    run = simulate(gel, t0, t1, until=UNTIL[name, grid], grid=grid, n=n, every=1e-3)
    print(f"  full {name} {grid} N={n}: {time.perf_counter() - tic:.1f} s")
    return run


def flux_check(full) -> dict:
    """A vs a^2 da/dt of the full solution, ANB at t = 0.2 (acceptance: within 2%)."""
    gel, t0, t1 = CASES["ANB"][:3]
    lev = front_levels(gel, t0, t1)
    a, rf, _ = full.state_at(0.2)
    ref = a * a * float(np.interp(0.2, full.step_t, full.step_rate)) / lev.k_plus
    out = {"radius": a, "a2_dadt": ref}
    for label, x in (("tracked", rf), ("conservative", float(front_of_radius(lev, 1.0, a)))):
        amp = flux_constant(a, x, lev.phi_minus, lev.phi_plus, gel, t1)
        out[label] = (x, amp, amp / ref - 1.0)
        print(f"  ANB t=0.2 {full.grid}: a={a:.4f} R_f={x:.4f} ({label}) A={amp:.4f} "
              f"A/R_f={amp / x:.3f}  a^2 da/dt={ref:.4f}  rel {amp / ref - 1:+.2%}")
    return out


def starts(name: str, full) -> dict:
    """The three starts: (start, conservative) by label."""
    ts = CASES[name][3]
    a, rf, _ = full.state_at(ts)
    return {"equilibrium": (None, True), f"full@{ts:g} conservative": ((ts, a, rf), True),
            f"full@{ts:g} paper": ((ts, a, rf), False)}


def dose_errors(name: str, full) -> dict:
    """Relative dose-time errors (10..90%) and 80% times per start, printed."""
    gel, t0, t1, _, a80, paper80 = CASES[name]
    radii = fraction_radius(float(full.radius[0]), FRACTIONS)
    t_full = np.array([full.time_to_radius(a) for a in radii])
    out = {}
    for label, (st, cons) in starts(name, full).items():
        res = front_trajectory(gel, t0, t1, start=st, conservative=cons)
        ok = radii <= res.radius[0]
        err = np.array([res.time_to_radius(a) for a in radii[ok]]) / t_full[ok] - 1.0
        t80 = res.time_to_radius(a80)
        out[label] = (float(np.abs(err).max()), t80)
        print(f"  {name} {full.grid:10s} {label:24s} max |dose-time error| {np.abs(err).max():6.1%}"
              f" (signed: {' '.join(f'{e:+.2f}' for e in err)})  t(a={a80})={t80:.4f} "
              f"[full {full.time_to_radius(a80):.4f}, paper {paper80}]")
    return out


def main() -> None:
    """Print the measurements."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--n-lagrangian", type=int, default=400,
                   help="Lagrangian grid size (its dose times barely depend on N)")
    p.add_argument("--no-full", action="store_true", help="speed only")
    args = p.parse_args()
    speed(200)
    if args.no_full:
        return
    runs = {(name, grid): full_run(name, grid, 400 if grid == "eulerian" else args.n_lagrangian)
            for name in CASES for grid in ("eulerian", "lagrangian")}
    for grid in ("eulerian", "lagrangian"):
        flux_check(runs["ANB", grid])
    for (name, _), full in runs.items():
        dose_errors(name, full)


if __name__ == "__main__":
    main()
