"""The slow-heating front model against the truth: its error table (issue 24).

    python -m benchmarks.heating_reduced [--gel ANB HHT custom] [--markdown] [--summary]
    python -m benchmarks.heating_reduced --sizes 20 100 [--gel ANB HHT]

For each gel (ANB and the custom gel 302 -> 308 K, HHT 304 -> 308 K), heating (the jump,
ramps in K/min, baths with time constants in s) and dose (10-90 %), a 50 um dry bead: the
truth's time (the full solver at the bead's own interfacial length on the moving grid,
mobility 'kT', cached on disk by benchmarks/heating_truth.py) and the error of the
slow-heating front model (solver/front/slow.py, sharp-interface front condition), with the
model's CPU time per trajectory.  Where |error| <= the stated bound
(dosing.heating_reduced.STATED_ERROR) and inside the planner's region
(dosing.heating_reduced.choose) the planner answers from the model.  ``--summary``: one
table, each cell the largest |error| over the three gels, in brackets outside the region.
``--sizes``: other dry radii (the truth at each bead's own interfacial length; the same
heatings in K/min and s, so other rates in K per tau): the jump, 5 and 20 K/min ramps,
10 and 30 s baths.
"""

from __future__ import annotations

import argparse
import time

from dosing.units import timescale
from solver.equilibrium import equilibrium
from solver.front.slow import slow_front_trajectory
from solver.heating import Released

from .heating_truth import DRY_UM, FRACTIONS, STARTS, T_END, gel_named, heatings, program_for
from .heating_truth import truth as truth_run


def rows(gel_name: str) -> list[tuple[str, list[float], list[float], float]]:
    """(heating, truth seconds, model errors, model ms) for every heating of one gel."""
    gel = gel_named(gel_name)
    t0 = STARTS[gel_name]
    tau = timescale(DRY_UM, T_END).seconds
    a0 = equilibrium(gel, t0, "swollen").stretch
    targets = tuple(float(Released(f).radius(a0)) for f in FRACTIONS)
    out = []
    for label, kind, value in heatings(tau):
        tr = truth_run(gel_name, kind, value)
        prog = program_for(kind, value, tau)
        slow_front_trajectory(gel, t0, prog, targets=targets)  # warm the tables
        w = time.process_time()
        res = slow_front_trajectory(gel, t0, prog, targets=targets)
        ms = 1e3 * (time.process_time() - w)
        model = [res.time_to_radius(a) for a in targets]
        errs = [m / t - 1.0 for m, t in zip(model, tr["times"], strict=True)]
        out.append((label, [t * tau for t in tr["times"]], errs, ms))
    return out


SIZE_HEATINGS = (("jump", 0.0), ("ramp", 5.0), ("ramp", 20.0), ("bath", 10.0), ("bath", 30.0))


def sizes(dries: list[float], gels: list[str]) -> None:
    """The model's error at other bead sizes (markdown: heating, then each dose)."""
    print(f"\n| bead | gel | heating | {' | '.join(f'{f:.0%}' for f in FRACTIONS)} |")
    print("|---" * (len(FRACTIONS) + 3) + "|")
    for dry in dries:
        tau = timescale(dry, T_END).seconds
        for g in gels:
            gel = gel_named(g)
            a0 = equilibrium(gel, STARTS[g], "swollen").stretch
            tg = tuple(float(Released(f).radius(a0)) for f in FRACTIONS)
            for kind, v in SIZE_HEATINGS:
                tr = truth_run(g, kind, v, dry_um=dry)
                res = slow_front_trajectory(gel, STARTS[g], program_for(kind, v, tau),
                                            targets=tg)
                label = {"jump": "jump", "ramp": f"ramp {v:g} K/min",
                         "bath": f"bath {v:g} s"}[kind]
                cells = [f"{t * tau:.1f} s, {res.time_to_radius(a) / t - 1.0:+.1%}"
                         for a, t in zip(tg, tr["times"], strict=True)]
                print(f"| {dry:g} um | {g} | {label} | " + " | ".join(cells) + " |")


def in_region(kind: str, fraction: float) -> bool:
    """The planner's region for the table's heatings (dosing/heating_reduced.py)."""
    from dosing.heating_reduced import BATH_FRACTION_MIN, FRACTION_RANGE

    lo = BATH_FRACTION_MIN if kind.startswith("bath") else FRACTION_RANGE[0]
    return lo <= fraction <= FRACTION_RANGE[1]


def summary(gels: list[str]) -> None:
    """The largest |error| over the gels per heating and dose (markdown)."""
    from dosing.heating_reduced import STATED_ERROR

    per = [rows(g) for g in gels]
    print(f"\n| heating | {' | '.join(f'{f:.0%}' for f in FRACTIONS)} |")
    print("|---" * (len(FRACTIONS) + 1) + "|")
    worst_in = 0.0
    for k, (label, _, _, _) in enumerate(per[0]):
        cells = []
        for j, f in enumerate(FRACTIONS):
            e = max(abs(p[k][2][j]) for p in per)
            inside = in_region(label, f)
            worst_in = max(worst_in, e) if inside else worst_in
            cells.append(f"{e:.1%}" if inside else f"({e:.1%})")
        print(f"| {label} | " + " | ".join(cells) + " |")
    ms = max(r[3] for p in per for r in p)
    print(f"\nlargest |error| inside the region {worst_in:.1%} (stated {STATED_ERROR:.0%}); "
          f"model CPU per trajectory at most {ms:.1f} ms ({', '.join(gels)})")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--gel", nargs="+", default=["ANB", "HHT", "custom"])
    p.add_argument("--markdown", action="store_true")
    p.add_argument("--summary", action="store_true")
    p.add_argument("--sizes", type=float, nargs="*", default=None)
    args = p.parse_args()
    if args.sizes:
        sizes(args.sizes, args.gel if args.gel != ["ANB", "HHT", "custom"] else ["ANB", "HHT"])
        return
    if args.summary:
        summary(args.gel)
        return
    for g in args.gel:
        print(f"\n{g} {STARTS[g]:g} -> {T_END:g} K, {DRY_UM:g} um dry bead: truth s / model "
              "error")
        if args.markdown:
            print("\n| heating | " + " | ".join(f"{f:.0%}" for f in FRACTIONS) + " | ms |")
            print("|---" * (len(FRACTIONS) + 2) + "|")
        for label, secs, errs, ms in rows(g):
            cells = [f"{s:.1f} s, {e:+.1%}" for s, e in zip(secs, errs, strict=True)]
            if args.markdown:
                print(f"| {label} | " + " | ".join(cells) + f" | {ms:.1f} |")
            else:
                print(f"{label:16s} " + "  ".join(f"{c:>17s}" for c in cells) + f" {ms:6.1f}")


if __name__ == "__main__":
    main()
