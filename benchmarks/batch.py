"""A batch of beads (issue 26): the speed of a batch answer from the front model, and the
spread figures of the issue.

Run:  PYTHONPATH=. .venv/bin/python benchmarks/batch.py [--repeats 20]

Prints
  * per size distribution (ANB 302 -> 308 K, number-weighted mean dry radius 50 um) and dose:
    the batch's dose time against its mean bead's, the fraction of beads delivered, the
    quadrature's nodes and error, and the wall time of one warm answer (median of repeats;
    the trajectory is memoised per jump, as in the service);
  * the issue's figures: the delay of the 30 / 50 / 80 % doses at CV 0.2 and 0.3.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from dosing import DoseRequest
from dosing.population.front import batch_answer

JUMP = {"gel": "ANB", "t_start": 302.0, "t_end": 308.0}
CASES = [("lognormal", 0.1), ("lognormal", 0.2), ("lognormal", 0.3), ("normal", 0.2),
         ("table", None)]
TABLE = {"kind": "table", "sizes_um": list(np.random.default_rng(0).lognormal(
    np.log(50.0), 0.2, 2000))}


def _req(f: float, kind: str, cv: float | None) -> DoseRequest:
    if kind == "table":
        return DoseRequest(**JUMP, dose_fraction=f, size_distribution=TABLE)
    return DoseRequest(**JUMP, dose_fraction=f, dry_radius_um=50.0,
                       size_distribution={"kind": kind, "cv": cv})


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=20)
    args = ap.parse_args()
    t0 = time.perf_counter()
    batch_answer(_req(0.8, "lognormal", 0.2))
    print(f"first answer (the front trajectory and its table, cold): "
          f"{time.perf_counter() - t0:.2f} s")
    print(f"{'distribution':<22}{'dose':>5}{'batch t':>10}{'mean t':>9}{'delay':>8}"
          f"{'deliv.':>8}{'nodes':>7}{'quad err':>10}{'ms (median)':>13}{'ms (max)':>10}")
    for kind, cv in CASES:
        for f in (0.3, 0.5, 0.8):
            req = _req(f, kind, cv)
            b = batch_answer(req)
            ts = []
            for _ in range(args.repeats):
                t = time.perf_counter()
                batch_answer(req)
                ts.append(time.perf_counter() - t)
            name = f"{kind} CV {cv}" if cv is not None else "table (2000 beads)"
            print(f"{name:<22}{f:>5.1f}{b.time:>10.5f}{b.mean_bead_time:>9.5f}"
                  f"{b.delay:>+8.1%}{b.fraction_delivered:>8.1%}{b.quadrature.nodes:>7d}"
                  f"{b.quadrature.error:>10.1e}{1e3 * np.median(ts):>13.2f}"
                  f"{1e3 * max(ts):>10.2f}")
    print("\nthe issue's figures (delay of the batch's dose against its mean bead's):")
    for cv in (0.2, 0.3):
        d = [batch_answer(_req(f, "lognormal", cv)).delay for f in (0.3, 0.5, 0.8)]
        print(f"  CV {cv}: 30 % {d[0]:+.1%}, 50 % {d[1]:+.1%}, 80 % {d[2]:+.1%}")


if __name__ == "__main__":
    main()
