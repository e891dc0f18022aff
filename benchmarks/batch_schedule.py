"""A schedule for a batch of beads on the truth (issue 26, dosing.population.cycles).

Run:  PYTHONPATH=. .venv/bin/python benchmarks/batch_schedule.py [--cv 0 0.2] [--cache FILE]

ANB 302 -> 308 K, mean dry radius 50 um, doses 30 / 30 / 20 % of the stored fluid with
rests of 0.5 tau; the truth (moving grid, N = 400, each size node at its own interfacial
length).  Prints per CV the actuation times (s), the batch's delivered doses, the nodes, the
quadrature error, the shooting's runs, the interfacial-length and model-form parts (the
largest change of a delivered dose at the found times) and the wall / CPU seconds (a fresh
cache unless --cache is given; the runs of one CV are reused by the next where they
coincide).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from dosing import ScheduleRequest
from dosing.population.cycles import plan_batch_schedule


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--cv", type=float, nargs="+", default=[0.0, 0.2])
    p.add_argument("--cache", default=None)
    args = p.parse_args()
    cache = args.cache or str(Path(tempfile.mkdtemp()) / "batch_schedule.sqlite")
    req = ScheduleRequest("ANB", 302.0, 308.0, doses=[0.3, 0.3, 0.2], rests=[0.5, 0.5],
                          dry_radius_um=50.0)
    print("| batch | actuation times (s) | delivered | nodes | quadrature error | runs | "
          "interfacial length | model form | wall | CPU |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for cv in args.cv:
        w, c = time.perf_counter(), time.process_time()
        a = plan_batch_schedule(req, {"cv": cv}, cache_path=cache)
        w, c = time.perf_counter() - w, time.process_time() - c
        k = a.corrected
        q = a.quadrature
        nodes = f"{q.nodes}" + (f" (checked on {k['check_nodes']})" if "check_nodes" in k
                                else "")
        print(f"| CV {cv:g} | {' / '.join(f'{x:.2f}' for x in k['actuation_seconds'])} | "
              f"{' / '.join(f'{x:.5f}' for x in k['delivered_fractions'])} | {nodes} | "
              f"{q.error:.1e} | {k['runs']} | "
              f"{a.uncertainty['interfacial_length_range'].relative:.2%} | "
              f"{a.uncertainty['model_form'].relative:.1%} | {w:.0f} s | "
              f"{c:.0f} s (this process) |")


if __name__ == "__main__":
    main()
