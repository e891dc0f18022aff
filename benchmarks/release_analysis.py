"""Release analysis (issue 38): the acceptance figures, with their run times.

Run:  .venv/bin/python benchmarks/release_analysis.py [--seeds 5] [--boot 5000]

Prints
  * the empirical zoo on a Weibull curve (Td 30 min, b 0.75, 12 times from 5 to 240 min,
    1 point of noise) per noise seed: the best model by AIC, Td's and b's errors, the AIC
    margin to the runner-up, the fit's wall time (all seven models);
  * Korsmeyer-Peppas's n over the first 60 % of Crank's sphere series (eq. 6.20), read for a
    sphere (Ritger & Peppas 1987: 0.43);
  * f1, f2 and the bootstrap (BCa and percentile 90 % intervals, standard error) of Shah et
    al. 1998's batches 1, 4, 5 against their reference (tests/data/release), beside the
    printed f2 and the disprofas package's published bootstrap of batch 4, and the time
    of 1000 draws.
Targets (tests/test_release_analysis.py): Weibull best, Td within 5 %, b within 0.04;
n = 0.43 +- 0.05; f2 to Shah's two decimals; the BCa interval within 0.35 of the published.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from dosing.analysis import fit_empirical, from_arrays, read_profile
from dosing.analysis.similarity import compare
from solver.solute.crank import crank_sphere

DATA = Path(__file__).resolve().parent.parent / "tests" / "data" / "release"
T = np.array([5, 10, 15, 20, 30, 45, 60, 90, 120, 150, 180, 240.0])
SHAH_PRINTED = {"test1": 60.03, "test4": 50.07, "test5": 48.05}
PUBLISHED_BATCH4 = "disprofas bootstrap_f2 (200 draws): SE 0.949, BCa 48.69-51.99, " \
                   "Shah's BCa 48.65-51.75"


def weibull(seeds: int) -> None:
    worst_td = worst_b = 0.0
    for seed in range(seeds):
        f = 100 * (1 - np.exp(-((T / 30.0) ** 0.75))) + \
            np.random.default_rng(seed).standard_normal(T.size)
        started = time.perf_counter()
        r = fit_empirical(from_arrays(T, f, time_unit="min", released_unit="percent"))
        spent = time.perf_counter() - started
        w = r.fits["weibull"]
        td, b = w.parameters["Td"] / 30.0 - 1.0, w.parameters["b"] - 0.75
        worst_td, worst_b = max(worst_td, abs(td)), max(worst_b, abs(b))
        nxt = r.ranked[1]
        print(f"weibull seed {seed:3d}: best {r.best:12s} Td {w.parameters['Td']:7.3f} min "
              f"({100 * td:+.2f} %)  b {w.parameters['b']:.4f} ({b:+.4f})  dAIC to {nxt} "
              f"{r.fits[nxt].aic - w.aic:5.1f}  {1000 * spent:6.1f} ms")
    print(f"weibull worst over {seeds} seeds: Td {100 * worst_td:.2f} %, b {worst_b:.4f}")


def crank() -> None:
    t = np.linspace(0.0, 0.3, 61)[1:]
    kp = fit_empirical(from_arrays(t, crank_sphere(t, 1.0, 1.0), time_unit="h"),
                       ["korsmeyer_peppas"]).fits["korsmeyer_peppas"]
    lo, hi = kp.intervals["n"]
    print(f"crank sphere, first 60 % ({kp.n_points} points): n = {kp.parameters['n']:.4f} "
          f"(95 % {lo:.3f}-{hi:.3f}): {kp.interpretation['mechanism']}")


def shah(boot: int) -> None:
    ref = read_profile(DATA / "shah1998_ref.csv")
    for name, printed in SHAH_PRINTED.items():
        test = read_profile(DATA / f"shah1998_{name}.csv")
        started = time.perf_counter()
        c = compare(ref, test, n_boot=1000, seed=0)
        spent = time.perf_counter() - started
        b = compare(ref, test, n_boot=boot, seed=7).bootstrap
        print(f"shah {name}: f2 {c.f2:.4f} (printed {printed}) f1 {c.f1:.3f}; {boot} draws: "
              f"SE {b['sd']:.3f}, BCa {b['interval_bca'][0]:.2f}-{b['interval_bca'][1]:.2f}, "
              f"percentile {b['interval_percentile'][0]:.2f}-"
              f"{b['interval_percentile'][1]:.2f}; 1000 draws {1000 * spent:.1f} ms")
    print(f"published, batch 4: {PUBLISHED_BATCH4}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=5, help="Weibull noise seeds (default 5)")
    ap.add_argument("--boot", type=int, default=5000, help="bootstrap draws (default 5000)")
    args = ap.parse_args()
    weibull(args.seeds)
    crank()
    shah(args.boot)


if __name__ == "__main__":
    main()
