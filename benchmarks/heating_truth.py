"""The truth under ramps and baths, cached on disk: the full solver at the planner's truth
settings (moving grid, the bead's own interfacial length, 400 cells, rtol 1e-5, mobility
'kT' relative to T_ref = T_end), a 50 um dry bead, one run per heating stopped at the
largest dose, the dose times read from its dense record.

    python -m benchmarks.heating_truth [--gel ANB HHT custom] [--constants consistent|paper]
                                       [--rates 0.5 1 ...] [--baths 1 10 ...]

The heatings are given in K/min and s; tau (eq. timescale, dosing/units.py) turns them into
the solver's K per tau and tau.  ``--constants consistent`` (the default): Omega_p = Omega
Omega_f with water's Omega_f (dosing.units.WATER_MOLECULAR_VOLUME_M3), eta = 1e-3 Pa s,
k0 = 8e-20 m^2, so tau depends on the gel (50 um at 308 K: ANB 22.05 s, HHT 158.8 s, the
custom gel 66.2 s); ``paper``: Omega_p = 3e-25 m^3 (tau = 2205 s for every gel), the
constants of the first table.  The same K/min is 100x fewer K per tau for ANB at the
consistent tau: a slower heating for the solver, so a different truth run.

Each run is stored as ``benchmarks/.heating_truth/<key>.npz`` (ignored by git), so the
error table of benchmarks/heating_reduced.py reruns in seconds.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import time
from pathlib import Path

import numpy as np

from dosing.units import WATER_MOLECULAR_VOLUME_M3, PhysicalConstants, timescale
from solver.equilibrium import equilibrium
from solver.full import simulate
from solver.gel import ANB, Gel, preset
from solver.heating import Bath, Program, Ramp, Released

STARTS = {"ANB": 302.0, "HHT": 304.0, "custom": 302.0}
T_END = 308.0
DRY_UM = 50.0
FRACTIONS = (0.1, 0.3, 0.5, 0.8, 0.9)
RATES = (0.5, 1.0, 5.0, 20.0, 100.0)  # K/min
BATHS = (1.0, 10.0, 30.0, 100.0, 300.0)  # s
MOBILITY = "kT"
CACHE = Path(__file__).parent / ".heating_truth"
VERSION = 1
CONSTANTS = ("consistent", "paper")
HORIZON = 50.0  # tau after the heating (the table's first runs: 50 tau in all)


def gel_named(name: str) -> Gel:
    """A preset, or 'custom': ANB's chi with Omega = 300."""
    if name == "custom":
        return Gel(300.0, ANB.a0, ANB.b0, ANB.a1, ANB.b1, name="custom")
    return preset(name)


def constants_for(gel_name: str, which: str = "consistent") -> PhysicalConstants:
    """eq. timescale's constants: 'consistent' (Omega_p = Omega Omega_f) or 'paper'."""
    if which == "paper":
        return PhysicalConstants()
    if which == "consistent":
        return PhysicalConstants(
            polymer_volume_m3=gel_named(gel_name).omega * WATER_MOLECULAR_VOLUME_M3)
    raise ValueError(f"constants {which!r}: one of {CONSTANTS}")


def tau_for(gel_name: str, which: str = "consistent", dry_um: float = DRY_UM) -> float:
    """tau (s) of a dry bead at T_END under the constants ``which``."""
    return timescale(dry_um, T_END, constants_for(gel_name, which)).seconds


def heatings(tau: float, rates: tuple[float, ...] = RATES,
             baths: tuple[float, ...] = BATHS) -> list[tuple[str, str, float]]:
    """(label, kind, value): the jump, ramps in K/min and baths in s."""
    out = [("jump", "jump", 0.0)]
    out += [(f"ramp {r:.4g} K/min", "ramp", r) for r in rates]
    out += [(f"bath {b:.4g} s", "bath", b) for b in baths]
    return out


def given(rates: tuple[float, ...], baths: tuple[float, ...], tau: float,
          dimensionless: bool) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Rates in K/min and baths in s; ``dimensionless``: the inputs are K per tau and tau
    (``--per-tau``, the same solver heating for every gel), turned into K/min and s."""
    if not dimensionless:
        return tuple(rates), tuple(baths)
    return tuple(r * 60.0 / tau for r in rates), tuple(b * tau for b in baths)


def per_tau(kind: str, value: float, tau: float) -> float:
    """The heating in the solver's units: a ramp in K per tau, a bath's time constant in
    tau (the jump 0)."""
    if kind == "ramp":
        return value / 60.0 * tau
    if kind == "bath":
        return value / tau
    return 0.0


def horizon(kind: str, value: float, tau: float) -> float:
    """How long (tau) the truth may run: HORIZON, what the first table ran, or HORIZON
    after a long heating (12 K at the ramp's rate; 10 bath time constants) over 5 tau."""
    v = per_tau(kind, value, tau)
    heat = 12.0 / v if kind == "ramp" else 10.0 * v if kind == "bath" else 0.0
    return heat + HORIZON if heat > 5.0 else HORIZON


def program_for(kind: str, value: float, tau: float) -> Program:
    """The heating as a solver Program (dimensionless: K per tau, tau)."""
    if kind == "ramp":
        return Program((Ramp(T_END, per_tau(kind, value, tau)),), mobility=MOBILITY)
    if kind == "bath":
        return Program((Bath(T_END, per_tau(kind, value, tau),
                             duration=horizon(kind, value, tau)),), mobility=MOBILITY)
    return Program((Ramp(T_END, 1e12),), mobility=MOBILITY)


def truth(gel_name: str, kind: str, value: float, dry_um: float = DRY_UM,
          constants: str = "consistent") -> dict:
    """Dose times (tau) for FRACTIONS under one heating, from the cache or a run."""
    gel = gel_named(gel_name)
    t0 = STARTS[gel_name]
    ell = PhysicalConstants().interfacial_lengths(dry_um)[0]
    tau = tau_for(gel_name, constants, dry_um)
    spec = {"gel": gel_name, "t0": t0, "kind": kind, "value": value, "dry_um": dry_um,
            "ell": ell, "n": 400, "rtol": 1e-5, "mobility": MOBILITY, "v": VERSION,
            "fractions": FRACTIONS, "constants": constants, "tau": tau}
    key = hashlib.sha256(json.dumps(spec, sort_keys=True).encode()).hexdigest()[:16]
    path = CACHE / f"{gel_name}-{constants}-{kind}-{value:g}-{key}.npz"
    if path.exists():
        d = np.load(path)
        return {"times": d["times"].tolist(), "wall": float(d["wall"]), "tau": tau,
                "t": d["t"], "radius": d["radius"]}
    a0 = equilibrium(gel, t0, "swollen").stretch
    targets = [float(Released(f).radius(a0)) for f in FRACTIONS]
    opts = {"grid": "moving", "n": 400, "interfacial_length": ell, "rtol": 1e-5}
    w = time.process_time()
    if kind == "jump":
        res = simulate(gel, t0, T_END, until=2.0, stop=min(targets), **opts)
    else:
        res = simulate(gel, t0, protocol=program_for(kind, value, tau),
                       until=horizon(kind, value, tau), stop=min(targets), **opts)
    wall = time.process_time() - w
    times = [res.time_to_radius(a) for a in targets]
    CACHE.mkdir(exist_ok=True)
    np.savez(path, times=np.array(times), wall=wall, t=np.asarray(res.t),
             radius=np.asarray(res.radius))
    return {"times": times, "wall": wall, "tau": tau, "t": np.asarray(res.t),
            "radius": np.asarray(res.radius)}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--gel", nargs="+", default=["ANB", "HHT", "custom"])
    p.add_argument("--constants", choices=CONSTANTS, default="consistent")
    p.add_argument("--rates", type=float, nargs="*", default=list(RATES),
                   help="ramps, K/min (K per tau with --per-tau)")
    p.add_argument("--baths", type=float, nargs="*", default=list(BATHS),
                   help="baths' time constants, s (tau with --per-tau)")
    p.add_argument("--per-tau", action="store_true",
                   help="--rates in K per tau and --baths in tau (the same for every gel)")
    p.add_argument("--no-jump", action="store_true")
    args = p.parse_args()
    for g in args.gel:
        tau = tau_for(g, args.constants)
        for label, kind, value in heatings(tau, *given(args.rates, args.baths, tau,
                                                       args.per_tau)):
            if args.no_jump and kind == "jump":
                continue
            r = truth(g, kind, value, constants=args.constants)
            secs = " ".join(f"{t * tau:8.1f}" for t in r["times"])
            unit = "tau" if kind == "bath" else "K/tau"
            print(f"{g:7s} {label:16s} ({per_tau(kind, value, tau):8.4g} {unit:5s}) "
                  f"{secs}  cpu {r['wall']:.1f} s", flush=True)


if __name__ == "__main__":
    main()
