"""Design-map speed: a 10 x 10 x 5 sweep (T_end x bead size x dose) with the front model.

Prints, for each executor, the wall time of the sweep (cold: the front trajectories of
this process computed on the way; warm: memoised) and the largest relative difference of
its times from Planner.dose answering the same points one by one (0: one code path).

    .venv/bin/python benchmarks/sweep.py            # inline and a 2-thread pool
    .venv/bin/python benchmarks/sweep.py --dask     # also a Dask LocalCluster (2 processes)
"""

from __future__ import annotations

import argparse
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from dosing import DoseRequest, Planner
from dosing.studies.sweep import SweepGrid, run_sweep

GRID = SweepGrid(t_ends=np.linspace(307.5, 311.5, 10), dry_radii_um=np.geomspace(10, 200, 10),
                 doses=[0.1, 0.3, 0.5, 0.7, 0.9])


def _difference(rows: list[dict]) -> float:
    """Largest |t_sweep - t_planner| / t_planner over every 7th answered point."""
    worst = 0.0
    with tempfile.TemporaryDirectory() as tmp, \
            Planner(cache_path=f"{tmp}/c.sqlite", executor=ThreadPoolExecutor(1)) as p:
        for r in rows[::7]:
            if r["status"] != "answered":
                continue
            ans = p.dose(DoseRequest("ANB", 302.0, r["t_end"], dose_fraction=r["dose_fraction"],
                                     dry_radius_um=r["dry_radius_um"]))
            worst = max(worst, abs(r["time"] - ans.time) / ans.time)
        p.jobs.executor.shutdown()
    return worst


def _report(name: str, run) -> None:
    t = time.perf_counter()
    res = run()
    wall = time.perf_counter() - t
    print(f"{name:28s} {GRID.size} points {wall:7.3f} s  {res.counts}  "
          f"max rel. difference from Planner.dose {_difference(res.rows):.1e}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--dask", action="store_true", help="also on a Dask LocalCluster")
    args = ap.parse_args()
    _report("inline (cold)", lambda: run_sweep(GRID))
    _report("inline (warm)", lambda: run_sweep(GRID))
    with ThreadPoolExecutor(2) as pool:
        _report("2 threads (warm)", lambda: run_sweep(GRID, executor=pool))
    if args.dask:
        import distributed

        with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                      dashboard_address=None) as cluster, \
                distributed.Client(cluster) as client:
            ex = client.get_executor()
            _report("dask 2 processes (cold)", lambda: run_sweep(GRID, executor=ex))
            _report("dask 2 processes (warm)", lambda: run_sweep(GRID, executor=ex))


if __name__ == "__main__":
    main()
