"""A validated batch answer in a fresh cache (issue 26): the truth per interfacial-length band.

Run:  PYTHONPATH=. .venv/bin/python benchmarks/batch_validation.py [--cv 0.2] [--fraction 0.8]

Prints the CPU seconds (all threads) and wall time of a cold validation (2 workers, a
temporary cache: every band's truth, check and interfacial-length runs plus the shared
model-form lattice), the former way and the lean way (``validated_batch(lean=...)``: runs
not stopped at a dose that lies before their need, the lattice's finest rung alone) side by
side in one run, then of the same answer warm, the front model's and the truth's batch
times, the bands and the uncertainty.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from dosing import DoseRequest, Planner
from dosing.population.bands import validated_batch
from dosing.population.front import batch_answer


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cv", type=float, default=0.2)
    ap.add_argument("--fraction", type=float, default=0.8)
    ap.add_argument("--gel", default="ANB")
    ap.add_argument("--bands", type=int, default=3)
    ap.add_argument("--every-band", action="store_true",
                    help="check and interfacial-length runs in every band (15 runs, not 9)")
    args = ap.parse_args()
    req = DoseRequest(args.gel, 302.0, 308.0, dose_fraction=args.fraction, dry_radius_um=50.0,
                      size_distribution={"cv": args.cv})
    front = batch_answer(req)
    cold: dict[bool, tuple[float, float, float]] = {}
    for lean in (False, True):  # the former way, then the lean one: each in a fresh cache
        with tempfile.TemporaryDirectory() as d:
            p = Planner(cache_path=str(Path(d) / "c.sqlite"), executor=ThreadPoolExecutor(2))
            try:
                t0, c0 = time.perf_counter(), time.process_time()
                b = validated_batch(p, req, args.bands, args.every_band, lean)
                wall, cpu = time.perf_counter() - t0, time.process_time() - c0
                t0 = time.perf_counter()
                validated_batch(p, req, args.bands, args.every_band, lean)
                cold[lean] = (wall, cpu, time.perf_counter() - t0)
                times = cold[lean] + (b.time,)
                print(f"{'lean' if lean else 'former'}: cold {times[0]:.1f} s wall, "
                      f"{times[1]:.1f} s CPU in all threads; warm {times[2]:.2f} s; batch "
                      f"time {b.time:.6g}", flush=True)
            finally:
                p.close()
                p.jobs.executor.shutdown(wait=True)
    (w0, c0_, _), (w1, c1, warm) = cold[False], cold[True]
    print(f"{args.gel} 302 -> 308 K, {args.fraction:.0%}, lognormal CV {args.cv}, mean 50 um dry")
    print(f"validation cold, CPU in all threads: former {c0_:.1f} s, lean {c1:.1f} s "
          f"({c1 / c0_:.2f}x); wall {w0:.1f} s and {w1:.1f} s; warm {warm:.2f} s")
    print(f"front model: {front.time:.5g} ({front.delay:+.1%} vs its mean bead); truth per "
          f"band: {b.time:.5g} ({b.delay:+.1%} vs its mean bead; "
          f"{b.time / front.time - 1:+.2%} vs the front model)")
    u = b.uncertainty
    print("bands: " + ", ".join(f"{x['dry_radius_um']:.3g} um (ell {x['interfacial_length']:.3g})"
                                for x in u["bands"]))
    for k in ("numerical", "interfacial_length_range", "model_form", "quadrature"):
        print(f"  {u[k].text}")


if __name__ == "__main__":
    main()
