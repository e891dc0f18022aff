"""The slow-heating front model against the truth: its error table (issue 24).

    python -m benchmarks.heating_reduced [--gel ANB HHT custom] [--markdown] [--summary]
                                         [--constants consistent|paper]
                                         [--rates 0.5 1 ...] [--baths 1 10 ...]
    python -m benchmarks.heating_reduced --sizes 20 100 [--gel ANB HHT]

For each gel (ANB and the custom gel 302 -> 308 K, HHT 304 -> 308 K), heating (the jump,
ramps in K/min, baths with time constants in s) and dose (10-90 %), a 50 um dry bead: the
truth's time (the full solver at the bead's own interfacial length on the moving grid,
mobility 'kT', cached on disk by benchmarks/heating_truth.py) and the error of the
slow-heating front model (solver/front/slow.py, sharp-interface front condition), with the
model's CPU time per trajectory.  Where |error| <= the stated bound
(dosing.heating.reduced.STATED_ERROR) and inside the planner's region
(dosing.heating.reduced.choose) the planner answers from the model.  ``--summary``: one
table, each cell the largest |error| over the three gels, in brackets outside the region.
``--sizes``: other dry radii (the truth at each bead's own interfacial length; the same
heatings in K/min and s, so other rates in K per tau): the jump, 5 and 20 K/min ramps,
10 and 30 s baths.  ``--constants``: eq. timescale's constants (benchmarks/heating_truth.py):
'consistent' (the default, Omega_p = Omega Omega_f: tau 22.05 s for ANB's 50 um bead, 158.8 s
for HHT, 66.2 s for the custom gel) or 'paper' (Omega_p = 3e-25 m^3, tau = 2205 s, the first
table's).  Each row states its heating in the solver's units (K per tau, tau).
"""

from __future__ import annotations

import argparse
import math
import time

from solver.equilibrium import equilibrium
from solver.front.slow import slow_front_trajectory
from solver.heating import Released

from .heating_truth import (
    BATHS,
    CONSTANTS,
    DRY_UM,
    FRACTIONS,
    RATES,
    STARTS,
    T_END,
    gel_named,
    given,
    heatings,
    per_tau,
    program_for,
    tau_for,
)
from .heating_truth import truth as truth_run


def rows(gel_name: str, constants: str = "consistent", rates: tuple[float, ...] = RATES,
         baths: tuple[float, ...] = BATHS, dimensionless: bool = False
         ) -> list[tuple[str, list[float], list[float], float, float, float]]:
    """(heating, truth seconds, model errors, model ms, K per tau or tau, truth CPU s) for
    every heating of one gel (``dimensionless``: rates in K per tau, baths in tau)."""
    gel = gel_named(gel_name)
    t0 = STARTS[gel_name]
    tau = tau_for(gel_name, constants)
    rates, baths = given(rates, baths, tau, dimensionless)
    a0 = equilibrium(gel, t0, "swollen").stretch
    targets = tuple(float(Released(f).radius(a0)) for f in FRACTIONS)
    out = []
    for label, kind, value in heatings(tau, rates, baths):
        tr = truth_run(gel_name, kind, value, constants=constants)
        prog = program_for(kind, value, tau)
        slow_front_trajectory(gel, t0, prog, targets=targets)  # warm the tables
        w = time.process_time()
        res = slow_front_trajectory(gel, t0, prog, targets=targets)
        ms = 1e3 * (time.process_time() - w)
        model = [crossing(res, a) for a in targets]
        errs = [m / t - 1.0 for m, t in zip(model, tr["times"], strict=True)]
        out.append((label, [t * tau for t in tr["times"]], errs, ms,
                    per_tau(kind, value, tau), tr["wall"]))
    return out


def crossing(res, target: float) -> float:
    """The model's time to ``target``, inf where it never gets there (a slow bath can take
    the uniform stage past the coexistence region without a front: no shrunken core)."""
    try:
        return res.time_to_radius(target)
    except ValueError:
        return math.inf


def pct(e: float) -> str:
    """An error as a signed percentage, 'never' where the model never reaches the dose."""
    return f"{e:+.1%}" if math.isfinite(e) else "never"


def unit(label: str) -> str:
    """The solver's unit of a heating's value: K per tau for a ramp, tau for a bath."""
    return "tau" if label.startswith("bath") else "K/tau"


SIZE_HEATINGS = (("jump", 0.0), ("ramp", 5.0), ("ramp", 20.0), ("bath", 10.0), ("bath", 30.0))


def sizes(dries: list[float], gels: list[str], constants: str = "consistent",
          rates: tuple[float, ...] | None = None, baths: tuple[float, ...] | None = None,
          dimensionless: bool = False) -> None:
    """The model's error at other bead sizes (markdown: heating, then each dose): the
    SIZE_HEATINGS, or the jump and the ``rates`` and ``baths`` given (K/min and s; K per
    tau and tau if ``dimensionless``)."""
    print(f"\n| bead | gel | heating | per tau | {' | '.join(f'{f:.0%}' for f in FRACTIONS)} |")
    print("|---" * (len(FRACTIONS) + 4) + "|")
    for dry in dries:
        for g in gels:
            tau = tau_for(g, constants, dry)
            heats = list(SIZE_HEATINGS)
            if rates is not None or baths is not None:
                r, b = given(rates or (), baths or (), tau, dimensionless)
                heats = [("jump", 0.0)] + [("ramp", x) for x in r] + [("bath", x) for x in b]
            gel = gel_named(g)
            a0 = equilibrium(gel, STARTS[g], "swollen").stretch
            tg = tuple(float(Released(f).radius(a0)) for f in FRACTIONS)
            for kind, v in heats:
                tr = truth_run(g, kind, v, dry_um=dry, constants=constants)
                res = slow_front_trajectory(gel, STARTS[g], program_for(kind, v, tau),
                                            targets=tg)
                label = {"jump": "jump", "ramp": f"ramp {v:.3g} K/min",
                         "bath": f"bath {v:.3g} s"}[kind]
                label += " | " + ("" if kind == "jump" else
                                  f"{per_tau(kind, v, tau):.3g} {unit(kind)}")
                cells = [f"{t * tau:.1f} s, {pct(crossing(res, a) / t - 1.0)}"
                         for a, t in zip(tg, tr["times"], strict=True)]
                print(f"| {dry:g} um | {g} | {label} | " + " | ".join(cells) + " |")


def in_region(kind: str, fraction: float, value: float = 0.0) -> bool:
    """The planner's region (dosing/heating/reduced.py) for a table's heating: ``kind``
    its label or kind, ``value`` its ramp in K per tau or bath time constant in tau."""
    from dosing.heating.reduced import BATH_FRACTION_MIN, BATH_MAX, FRACTION_RANGE, RAMP_MIN

    bath = kind.startswith("bath")
    if bath and value > BATH_MAX or kind.startswith("ramp") and value < RAMP_MIN:
        return False
    lo = BATH_FRACTION_MIN if bath else FRACTION_RANGE[0]
    return lo <= fraction <= FRACTION_RANGE[1]


def summary(gels: list[str], constants: str = "consistent", rates: tuple[float, ...] = RATES,
            baths: tuple[float, ...] = BATHS, dimensionless: bool = False) -> None:
    """The largest |error| per heating and dose (markdown), in brackets outside the
    region.  One tau for all gels (the paper's constants): one row per heating, the
    largest over the gels.  Otherwise one row per gel and heating, ordered by the heating
    in the solver's units (ramps slowest first, baths shortest first), since the same K/min
    is a different K per tau for each gel."""
    from dosing.heating.reduced import STATED_ERROR

    per = {g: rows(g, constants, rates, baths, dimensionless) for g in gels}
    worst_in = 0.0
    if len({tau_for(g, constants) for g in gels}) == 1 and not dimensionless:
        print(f"\n| heating | {' | '.join(f'{f:.0%}' for f in FRACTIONS)} |")
        print("|---" * (len(FRACTIONS) + 1) + "|")
        first = per[gels[0]]
        for k, row in enumerate(first):
            cells = []
            for j, f in enumerate(FRACTIONS):
                e = max(abs(per[g][k][2][j]) for g in gels)
                inside = in_region(row[0], f, row[4])
                worst_in = max(worst_in, e) if inside else worst_in
                cells.append(f"{e:.1%}" if inside else f"({e:.1%})")  # e = inf prints inf%
            print(f"| {row[0]} | " + " | ".join(cells) + " |")
    else:
        print(f"\n| heating | gel | as given | {' | '.join(f'{f:.0%}' for f in FRACTIONS)} "
              "| truth CPU s |")
        print("|---" * (len(FRACTIONS) + 4) + "|")
        order = {"jump": 0, "ramp": 1, "bath": 2}
        flat = sorted(((g, r) for g in gels for r in per[g]),
                      key=lambda x: (order[x[1][0].split()[0]], x[1][4]))
        for g, (label, _, errs, _, value, cpu) in flat:
            cells = []
            for e, f in zip(errs, FRACTIONS, strict=True):
                inside = in_region(label, f, value)
                worst_in = max(worst_in, abs(e)) if inside else worst_in
                cells.append(pct(e) if inside else f"({pct(e)})")
            kind = label.split()[0]
            what = "jump" if kind == "jump" else f"{kind} {value:.3g} {unit(label)}"
            given = "" if kind == "jump" else " ".join(label.split()[1:])
            print(f"| {what} | {g} | {given} | " + " | ".join(cells) + f" | {cpu:.1f} |")
    ms = max(r[3] for g in gels for r in per[g])
    taus = ", ".join(f"{g} {tau_for(g, constants):.4g} s" for g in gels)
    print(f"\nlargest |error| inside the region {worst_in:.1%} (stated {STATED_ERROR:.0%}); "
          f"model CPU per trajectory at most {ms:.1f} ms; constants {constants} "
          f"(tau {taus})")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--gel", nargs="+", default=["ANB", "HHT", "custom"])
    p.add_argument("--markdown", action="store_true")
    p.add_argument("--summary", action="store_true")
    p.add_argument("--sizes", type=float, nargs="*", default=None)
    p.add_argument("--constants", choices=CONSTANTS, default="consistent")
    p.add_argument("--rates", type=float, nargs="*", default=None,
                   help="ramps, K/min (K per tau with --per-tau)")
    p.add_argument("--baths", type=float, nargs="*", default=None,
                   help="baths' time constants, s (tau with --per-tau)")
    p.add_argument("--per-tau", action="store_true",
                   help="--rates in K per tau and --baths in tau (the same for every gel)")
    args = p.parse_args()
    if args.sizes:
        sizes(args.sizes, args.gel if args.gel != ["ANB", "HHT", "custom"] else ["ANB", "HHT"],
              args.constants, None if args.rates is None else tuple(args.rates),
              None if args.baths is None else tuple(args.baths), args.per_tau)
        return
    rates = RATES if args.rates is None else tuple(args.rates)
    baths = BATHS if args.baths is None else tuple(args.baths)
    if args.summary:
        summary(args.gel, args.constants, rates, baths, args.per_tau)
        return
    for g in args.gel:
        tau = tau_for(g, args.constants)
        print(f"\n{g} {STARTS[g]:g} -> {T_END:g} K, {DRY_UM:g} um dry bead, tau = {tau:.4g} s "
              f"({args.constants} constants): truth s / model error")
        if args.markdown:
            print("\n| heating | per tau | " + " | ".join(f"{f:.0%}" for f in FRACTIONS)
                  + " | ms |")
            print("|---" * (len(FRACTIONS) + 3) + "|")
        for label, secs, errs, ms, value, _ in rows(g, args.constants, rates, baths,
                                                    args.per_tau):
            cells = [f"{s:.1f} s, {pct(e)}" for s, e in zip(secs, errs, strict=True)]
            per = "" if label == "jump" else f"{value:.3g} {unit(label)}"
            if args.markdown:
                print(f"| {label} | {per} | " + " | ".join(cells) + f" | {ms:.1f} |")
            else:
                print(f"{label:16s} {per:>12s} " + "  ".join(f"{c:>17s}" for c in cells)
                      + f" {ms:6.1f}")


if __name__ == "__main__":
    main()
