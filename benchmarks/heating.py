"""Heating a lab can do (issue 24): dose times of the full solver under ramps and baths.

    python -m benchmarks.heating [--gel ANB|HHT|custom] [--dry-radius-um 50]
                                 [--fractions 0.1 0.3 0.5 0.8 0.9] [--rates 0.5 1 5 20 100]
                                 [--baths 1 10 30 100 300] [--mobility constant]
    python -m benchmarks.heating --section validated [--fraction 0.8]

``--section validated``: a validated ramp dose ("Heat to 308 K at 5 K/min", ANB from
302 K, a 50 um dry bead) cold: a new process, a fresh cache; its CPU seconds (user +
system, all threads and children) for the imports, the validated answer (the truth, its
check on n / 2 cells and the two interfacial-length range runs, each stopped at the dose,
and the reduced model's gap as the model-form part) and a reduced-model answer of the
same dose, side by side.

The truth's settings (moving grid, the bead's own interfacial length ell = 4 nm / dry
radius, 400 cells, rtol 1e-5): for each heating (the jump, ramps in K/min, baths with time
constants in s, from T_start towards T_end) the time at which each dose fraction is
reached, from the protocol's start, in seconds (tau at T_end, dosing.units.timescale) and
as a multiple of the jump's ("x": the step answer's error under that heating) and the
error of the delayed-jump estimate t_c + t_jump (solver/front/heating.py; "dj": t_c the
time T(t) reaches the coexistence onset of the start state, t_jump the full solver's jump
answer), with each run's wall time.  One run per heating: ``stop`` at the largest
fraction, the smaller ones read from its dense record.  ``custom``: ANB's chi with Omega = 300.
"""

from __future__ import annotations

import argparse
import time

from dosing.units import PhysicalConstants, timescale
from solver.equilibrium import equilibrium
from solver.front.heating import onset_temperature, onset_time
from solver.full import simulate
from solver.gel import ANB, Gel, preset
from solver.heating import Bath, Program, Ramp, Released

STARTS = {"ANB": 302.0, "HHT": 304.0, "custom": 302.0}


def _gel(name: str) -> Gel:
    if name == "custom":
        return Gel(300.0, ANB.a0, ANB.b0, ANB.a1, ANB.b1, name="custom")
    return preset(name)


def run(args: argparse.Namespace) -> None:
    gel = _gel(args.gel)
    t0, t1 = STARTS.get(gel.name, 302.0), 308.0
    tau = timescale(args.dry_radius_um, t1, PhysicalConstants.paper()).seconds  # the table's
    ell = PhysicalConstants().interfacial_lengths(args.dry_radius_um)[0]
    a0 = equilibrium(gel, t0, "swollen").stretch
    targets = [float(Released(f).radius(a0)) for f in args.fractions]
    opts = {"grid": "moving", "n": 400, "interfacial_length": ell, "rtol": 1e-5}
    heatings: list[tuple[str, Program | None]] = [("jump", None)]
    heatings += [(f"ramp {r:g} K/min", Program((Ramp(t1, r / 60.0 * tau),),
                                               mobility=args.mobility))
                 for r in args.rates]
    heatings += [(f"bath {b:g} s", Program((Bath(t1, b / tau, duration=50.0),),
                                           mobility=args.mobility)) for b in args.baths]
    t_c = onset_temperature(gel, a0, t0, t1)
    assert t_c is not None, "no coexistence onset between the temperatures"
    print(f"{gel.name} {t0:g} -> {t1:g} K, dry radius {args.dry_radius_um:g} um, tau = "
          f"{tau:.0f} s, ell = {ell:.2e}, mobility {args.mobility}, onset T_c = {t_c:.2f} K")
    head = "".join(f"{f'{f:.0%} s':>9}{'x':>7}{'dj':>7}" for f in args.fractions)
    print(f"{'heating':<18}{head}{'wall s':>8}")
    base: list[float] = []
    for name, prog in heatings:
        w = time.perf_counter()
        if prog is None:
            res = simulate(gel, t0, t1, until=2.0, stop=min(targets), **opts)
        else:
            res = simulate(gel, t0, protocol=prog, until=50.0, stop=min(targets), **opts)
        wall = time.perf_counter() - w
        times = [res.time_to_radius(a) * tau for a in targets]
        if not base:
            base = times
        delay = 0.0 if prog is None else onset_time(prog, t0, t_c) * tau
        row = "".join(f"{t:9.1f}{t / b:7.2f}{(delay + b) / t - 1.0:7.1%}"
                      for t, b in zip(times, base, strict=True))
        print(f"{name:<18}{row}{wall:8.1f}")


COLD = """
import resource, sys, tempfile, time
from pathlib import Path

def cpu():
    r, c = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime + c.ru_utime + c.ru_stime

c0 = cpu()
from concurrent.futures import ThreadPoolExecutor
from dosing.planner import Planner
from dosing.request import DoseRequest
c1 = cpu()
req = DoseRequest("ANB", 302.0, protocol=["Heat to 308 K at 5 K/min"],
                  dose_fraction=float(sys.argv[1]), dry_radius_um=50.0)
with Planner(cache_path=Path(tempfile.mkdtemp()) / "c.sqlite",
             executor=ThreadPoolExecutor(1)) as p:
    w = time.perf_counter()
    ans = p.dose(req, validate=True)
    wall = time.perf_counter() - w
    c2 = cpu()
    fast = p.dose(req)
    c3 = cpu()
    p.dose(req)
    c4 = cpu()
unc = ans.uncertainty
print(f"validated: {ans.model}, {ans.seconds:.2f} s, error parts "
      f"{unc['numerical'].relative:.2g} / {unc['interfacial_length_range'].relative:.2g}"
      f" / {unc['model_form'].relative:.2g}")
print(f"reduced:   {fast.model}, {fast.seconds:.2f} s")
print(f"cpu s: imports {c1 - c0:.2f}, validated dose {c2 - c1:.2f} (wall {wall:.2f}), "
      f"reduced answer cold {c3 - c2:.3f}, warm {c4 - c3:.4f}")
"""


def validated_section(fraction: float) -> None:
    """The cold validated ramp dose in a new process (module doc)."""
    import subprocess
    import sys

    subprocess.run([sys.executable, "-c", COLD, str(fraction)], check=True)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--section", default="table", choices=["table", "validated"])
    p.add_argument("--fraction", type=float, default=0.8)
    p.add_argument("--gel", default="ANB")
    p.add_argument("--dry-radius-um", type=float, default=50.0)
    p.add_argument("--fractions", type=float, nargs="+", default=[0.1, 0.3, 0.5, 0.8, 0.9])
    p.add_argument("--rates", type=float, nargs="*", default=[0.5, 1.0, 5.0, 20.0, 100.0])
    p.add_argument("--baths", type=float, nargs="*", default=[1.0, 10.0, 30.0, 100.0, 300.0])
    p.add_argument("--mobility", default="constant", choices=["constant", "kT", "water"])
    args = p.parse_args()
    if args.section == "validated":
        validated_section(args.fraction)
    else:
        run(args)


if __name__ == "__main__":
    main()
