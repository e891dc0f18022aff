"""What the envelope (issue 36) costs an answer: CPU seconds side by side in one run.

For a warm planner (its runs stored), per answer: the cell's own answer
(``request.cell.now``, what `answer` cost before issue 36) against the same answer with its
envelope (``dosing.question.answer``), for a jump and a ramp; and once, cold and blocking
(``dosing.question.run``), the answer with every run it needs (a ramp at the default
constants is 1.8 K/tau for 50 um ANB, below the reduced model's region: the full solver),
the delayed-law lattice runs of the front-law part and the timescale candidates' reruns
(stored after it).  CPU time (process_time), medians
of ``--repeat`` rounds, the ratio beside them.

    python -m benchmarks.envelope_cost [--repeat 200]
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor

from dosing import Planner
from dosing.question import Dose, Heating, Jump, Request, answer, run


def _cpu(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.process_time()
        fn()
        times.append(time.process_time() - t)
    return statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=200)
    args = ap.parse_args()
    cases = {"jump ANB 302->308 K, 80 %, 50 um":
             Request("ANB", 302, Jump(308), Dose(0.8), dry_radius_um=50),
             "ramp ANB 302 K at 5 K/min to 308 K, 80 %, 50 um":
             Request("ANB", 302, Heating(["Heat to 308 K at 5 K/min"]), Dose(0.8),
                     dry_radius_um=50)}
    with tempfile.TemporaryDirectory() as tmp, \
            Planner(cache_path=f"{tmp}/c.sqlite", executor=ThreadPoolExecutor(1)) as p:
        print(f"{'case':50s} {'cold envelope':>14s} {'cell (ms)':>10s} "
              f"{'+envelope (ms)':>15s} {'ratio':>6s}")
        for name, req in cases.items():
            t = time.process_time()
            run(p, req)  # cold: the runs and the lattice runs, stored
            cold = time.process_time() - t
            bare = _cpu(lambda req=req: req.cell.now(p, req), args.repeat)
            full = _cpu(lambda req=req: answer(p, req), args.repeat)
            print(f"{name:50s} {cold:13.3f}s {1e3 * bare:10.3f} {1e3 * full:15.3f} "
                  f"{full / bare:6.2f}")
        p.jobs.executor.shutdown(wait=True)


if __name__ == "__main__":
    main()
