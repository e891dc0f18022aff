"""The truth under ramps and baths, cached on disk: the full solver at the planner's truth
settings (moving grid, the bead's own interfacial length, 400 cells, rtol 1e-5, mobility
'kT' relative to T_ref = T_end), a 50 um dry bead, one run per heating stopped at the
largest dose, the dose times read from its dense record.

    python -m benchmarks.heating_truth [--gel ANB HHT custom]

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

from dosing.units import PhysicalConstants, timescale
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


def gel_named(name: str) -> Gel:
    """A preset, or 'custom': ANB's chi with Omega = 300."""
    if name == "custom":
        return Gel(300.0, ANB.a0, ANB.b0, ANB.a1, ANB.b1, name="custom")
    return preset(name)


def heatings(tau: float) -> list[tuple[str, str, float]]:
    """(label, kind, value): the jump, ramps in K/min and baths in s."""
    out = [("jump", "jump", 0.0)]
    out += [(f"ramp {r:g} K/min", "ramp", r) for r in RATES]
    out += [(f"bath {b:g} s", "bath", b) for b in BATHS]
    return out


def program_for(kind: str, value: float, tau: float) -> Program:
    """The heating as a solver Program (dimensionless: K per tau, tau)."""
    if kind == "ramp":
        return Program((Ramp(T_END, value / 60.0 * tau),), mobility=MOBILITY)
    if kind == "bath":
        return Program((Bath(T_END, value / tau, duration=50.0),), mobility=MOBILITY)
    return Program((Ramp(T_END, 1e12),), mobility=MOBILITY)


def truth(gel_name: str, kind: str, value: float, dry_um: float = DRY_UM) -> dict:
    """Dose times (tau) for FRACTIONS under one heating, from the cache or a run."""
    gel = gel_named(gel_name)
    t0 = STARTS[gel_name]
    ell = PhysicalConstants().interfacial_lengths(dry_um)[0]
    tau = timescale(dry_um, T_END).seconds
    spec = {"gel": gel_name, "t0": t0, "kind": kind, "value": value, "dry_um": dry_um,
            "ell": ell, "n": 400, "rtol": 1e-5, "mobility": MOBILITY, "v": VERSION,
            "fractions": FRACTIONS}
    key = hashlib.sha256(json.dumps(spec, sort_keys=True).encode()).hexdigest()[:16]
    path = CACHE / f"{gel_name}-{kind}-{value:g}-{key}.npz"
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
        res = simulate(gel, t0, protocol=program_for(kind, value, tau), until=50.0,
                       stop=min(targets), **opts)
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
    args = p.parse_args()
    tau = timescale(DRY_UM, T_END).seconds
    for g in args.gel:
        for label, kind, value in heatings(tau):
            r = truth(g, kind, value)
            secs = " ".join(f"{t * tau:8.1f}" for t in r["times"])
            print(f"{g:7s} {label:16s} {secs}  cpu {r['wall']:.1f} s", flush=True)


if __name__ == "__main__":
    main()
