"""Fitting a user's gel (issue 14): error against run time.

Run:  .venv/bin/python benchmarks/fit.py [--seeds 5] [--no-full] [--coverage N]

Prints
  * equilibrium fits with the multi-start global search (synthetic data from the presets:
    30 points, 1% noise in size, 0.05 K in temperature; HHT over 290-320 K with all six
    parameters free, ANB over 300-312 K with Omega fixed at 100 as the paper took it): wall
    time per fit,
    the largest |error| / its 95% half-width over the parameters, and the transition
    temperatures' errors (K), per seed;
  * kinetics fits with the front model ('front-sharp') on a shrinking curve (ANB 302 -> 308 K,
    50 um bead, 1% noise) from the full solver at ell = 0.0025 (unless --no-full: then from
    the front model itself): wall time per fit and tau's relative error and interval;
  * the dose-time interval of a fitted HHT gel: the delta method's time and half-width
    against 300 parameter draws.
With --coverage N only: the 95 % dose-time intervals' coverage of the true dose time over N
noise seeds (HHT 304 -> 308 K, 80 %; tests/test_fit_objectives.py runs 50 of them).
Targets: an equilibrium fit < 10 s, a kinetics fit with the front model < 30 s.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from dosing import Planner
from dosing.fits.gel import (
    data_dict,
    fit_shrinking,
    fit_swelling,
    front_radius_model,
    kinetics_data,
)
from dosing.fits.uncertainty import dose_time_interval, sample_dose_times
from dosing.runs.scenario import Scenario, SolverSettings
from dosing.units import timescale
from solver.equilibrium import folds
from solver.fit import fit_gel
from solver.fit.synthetic import synthetic_swelling
from solver.gel import ANB, HHT


def equilibrium(seeds: int) -> None:
    print("equilibrium fit (multi-start): seconds, max |err|/half-width, transition errors (K)")
    for gel, scale, fixed, t_range in ((HHT, 0.4127, {}, (290.0, 320.0)),
                                       (ANB, 1.0, {"omega": 100.0}, (300.0, 312.0))):
        truth = {"omega": gel.omega, "a0": gel.a0, "b0": gel.b0, "a1": gel.a1, "b1": gel.b1,
                 "scale": scale}
        true_t = {f.kind: f.temperature for f in folds(gel)}
        for seed in range(seeds):
            data = synthetic_swelling(gel, scale=scale, seed=seed, t_range=t_range)
            t0 = time.perf_counter()
            res = fit_swelling(data, fixed=fixed)
            wall = time.perf_counter() - t0
            ratios = [abs(res.parameters[k] - v) / (0.5 * (res.intervals[k][1]
                                                           - res.intervals[k][0]))
                      for k, v in truth.items() if res.intervals[k]]
            trs = {t["kind"]: t["temperature"] for t in res.extra["transitions"]}
            errs = " ".join(
                f"{k} {trs.get(k, trs.get('continuous', float('nan'))) - v:+.3f}"
                for k, v in true_t.items())
            print(f"  {gel.name} seed {seed}: {wall:5.2f} s  max|err|/hw {max(ratios):.2f}  "
                  f"nfev {res.nfev}  {errs}")


def kinetics(full: bool) -> None:
    dry = 50.0
    tau = timescale(dry, 308.0, omega=ANB.omega).seconds  # the fit's default constants
    st = SolverSettings(interfacial_length=0.0025, method="ladder")
    with tempfile.TemporaryDirectory() as tmp:
        planner = Planner(cache_path=os.path.join(tmp, "c.sqlite"),
                          executor=ThreadPoolExecutor(1))
        try:
            if full:
                t0 = time.perf_counter()
                traj = planner.trajectory(Scenario(ANB, 302.0, 308.0, settings=st),
                                          need_radius=1.12)
                print(f"kinetics: synthetic curve from the full solver (ell = 0.0025) in "
                      f"{time.perf_counter() - t0:.1f} s")

                def curve(t):
                    return np.interp(t, traj.step_t, traj.step_radius)
            else:
                curve = front_radius_model(ANB, 302.0, 308.0, "swollen")(None)
                print("kinetics: synthetic curve from the front model")
            td = np.linspace(0.0, 0.3, 40)
            rng = np.random.default_rng(0)
            data = kinetics_data(td * tau, dry * curve(td) * (1 + 0.01 * rng.standard_normal(40)))
            for model in ("front-sharp", "full"):
                t0 = time.perf_counter()
                res = fit_shrinking(data, "ANB", 302.0, 308.0, dry_radius_um=dry, model=model,
                                    settings=st, planner=planner)
                wall = time.perf_counter() - t0
                lo, hi = res.intervals["tau"]
                print(f"  {model:11s}: {wall:6.3f} s  tau {res.parameters['tau']:.5g} s (true "
                      f"{tau:.5g}): error {res.parameters['tau'] / tau - 1:+.2%}, 95% "
                      f"[{lo:.5g}, {hi:.5g}] {'contains' if lo < tau < hi else 'MISSES'} it")
        finally:
            planner.close()
            planner.jobs.executor.shutdown(wait=True)


def dose_interval() -> None:
    data = synthetic_swelling(HHT, scale=0.4127, seed=3)
    res = fit_swelling(data)
    rec = {"name": "bench", "swelling": {"data": data_dict(data), "fit": res.to_dict()}}
    gel = fit_gel(res, "bench")
    print("dose-time interval (HHT fit, 300 -> 310 K): delta method vs 300 parameter draws")
    for f in (0.3, 0.5, 0.8):
        args = (300.0, 310.0, "swollen", f, True)
        t0 = time.perf_counter()
        iv = dose_time_interval(rec, gel, *args)
        t_delta = time.perf_counter() - t0
        t0 = time.perf_counter()
        times, failed = sample_dose_times(rec, gel, *args, n=300, seed=1)
        t_samp = time.perf_counter() - t0
        lo, hi = np.percentile(times, [2.5, 97.5])
        ratio = (iv["time"][1] - iv["time"][0]) / (hi - lo)
        print(f"  {f:.0%}: delta [{iv['time'][0]:.4g}, {iv['time'][1]:.4g}] in {t_delta:.2f} s;"
              f" sampled [{lo:.4g}, {hi:.4g}] in {t_samp:.1f} s ({failed} draws without a "
              f"front answer); width ratio {ratio:.3f}")


def coverage(seeds: int) -> None:
    """The dose-time intervals' coverage over ``seeds`` noise seeds (module doc): the test's
    synthetic HHT data (35 points, scale 41.27), one local fit warm-started at the truth."""
    from dosing.fits.uncertainty import dose_time

    true_t = dose_time(HHT, 304.0, 308.0, "swollen", 0.8, True)
    truth = {"omega": HHT.omega, "a0": HHT.a0, "b0": HHT.b0, "a1": HHT.a1, "b1": HHT.b1,
             "scale": 41.27}
    hits, z = 0, []
    for seed in range(seeds):
        d = synthetic_swelling(HHT, n=35, scale=41.27, seed=100 + seed)
        res = fit_swelling(d, start=truth)
        iv = dose_time_interval({"swelling": {"fit": res.to_dict()}}, fit_gel(res), 304.0,
                                308.0, "swollen", 0.8, True)
        if iv.get("time") is not None:
            lo, hi = iv["time"]
            hits += lo <= true_t <= hi
            z.append((true_t - 0.5 * (lo + hi)) / ((hi - lo) / (2 * 1.96)))  # in sigmas
    print(f"dose-time interval coverage (HHT 304 -> 308 K, 80 %): {hits}/{seeds} = "
          f"{hits / seeds:.3f}; z-scores mean {np.mean(z):+.2f}, sd {np.std(z):.2f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--no-full", action="store_true")
    ap.add_argument("--coverage", type=int, default=0, metavar="N")
    args = ap.parse_args()
    if args.coverage:
        coverage(args.coverage)
        return
    equilibrium(args.seeds)
    kinetics(not args.no_full)
    dose_interval()


if __name__ == "__main__":
    main()
