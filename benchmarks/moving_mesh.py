"""The moving Lagrangian grid (solver/full/moving.py, ale.py) against the uniform grid, direct
runs at small interfacial lengths, a stiff gel, the delayed-transition bound and speed.

    .venv/bin/python benchmarks/moving_mesh.py                      # everything (~15 min)
    .venv/bin/python benchmarks/moving_mesh.py --section reproduce  # one section

Sections (issue 12's acceptance):
  reproduce  dose times 10%..90% of ANB 302->308 K and HHT 304->308 K at ell = 0.005,
             0.0025, 0.00125: uniform Lagrangian grid (4/ell cells, the planner's rungs)
             against the moving grid with a quarter of the cells; largest relative gap,
             largest solid error, wall times.
  direct     HHT at ell = 3.125e-4 and 1e-4, ANB at 1e-4 on the moving grid (400 cells),
             against the ell -> 0 limits of docs/interfacial.md (ANB 0.0777, HHT 0.0746).
  stiff      Omega = 1e4 (ANB otherwise), 302->308 K, ell = 1e-3: the 50% dose at 400 and
             800 cells, and the cells across the steepest part of the interface.
  delayed    the ell = 0 Lagrangian lattice (uniform grid): ANB and HHT 80% at N = 200,
             400, 800 (the delayed-transition bound, 0.116 and 0.221).
  speed      ell = 2e-4 on the moving grid to the 90% dose: wall time, steps; the custom
             gel (Omega = 300, ANB's chi) to its 50% dose at ell = 1e-4 and 8e-5.
  thin       steps at thin fronts (issue 23): ANB and HHT at ell = 1e-3, 1e-4, 3e-5, the
             planner's direct run (400 cells, and its 200-cell check: the numerical bound)
             to t = 0.1; attempted and rejected steps, the accepted ones through the
             nucleation (to 3x the time the edge cell's porosity falls half way) and after,
             t50 / t80, the attempted steps at each ell relative to ell = 1e-3 (target:
             at most 1.5x at 3e-5), and the 400-cell run's accepted steps per window of
             time (docs/moving_mesh.md sec. 7.3).
  options    issue 23's own figure (benchmarks.speed --only moving: ANB, 400 cells, rtol
             1e-5, to t = 0.08, no outputs) at ell = 1e-3 and 3e-5 with the mesh options
             moved one or two at a time: attempted steps, their ratio, t80 (sec. 7.4).
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import replace

import numpy as np

from solver.equilibrium import equilibrium
from solver.front.result import fraction_radius
from solver.full import simulate
from solver.full.moving import MeshOptions
from solver.gel import preset

CASES = {"ANB": (302.0, 308.0), "HHT": (304.0, 308.0)}
FRACTIONS = np.arange(1, 10) / 10.0
RTOL = 1e-5
UNTIL = {"ANB": 0.15, "HHT": 0.22}  # past the 90% dose at every ell below 0.005
LIMITS = {"ANB": 0.0777, "HHT": 0.0746}  # t80 as ell -> 0 (docs/interfacial.md, sec. 7)


def run(gel: object, t_start: float, until: float, grid: str, n: int, ell: float,
        fractions: np.ndarray = FRACTIONS) -> tuple[np.ndarray, float, object]:
    """(dose times, wall s, result) of one run."""
    g = preset(gel) if isinstance(gel, str) else gel
    a0 = equilibrium(g, t_start).stretch
    started = time.perf_counter()
    res = simulate(g, t_start, 308.0, until=until, grid=grid, n=n, interfacial_length=ell,
                   rtol=RTOL, every=until / 400)
    wall = time.perf_counter() - started
    times = []
    for a in fraction_radius(a0, fractions):
        try:
            times.append(res.time_to_radius(a))
        except ValueError:
            times.append(math.nan)
    return np.array(times), wall, res


def _fmt(v: np.ndarray) -> str:
    return " ".join(f"{x:.6f}" for x in v)


def steep_cells(res: object) -> str:
    """Cells across the steepest part of the interface (where |dphi/drho| between adjacent
    cells is at least half its peak), min / median over the outputs whose front is inside
    the bead (R_f < 0.95 a)."""
    counts = []
    n = res.phi.shape[1]  # type: ignore[attr-defined]
    for i in range(res.t.size):  # type: ignore[attr-defined]
        if not res.front[i] < 0.95 * res.radius[i]:  # type: ignore[attr-defined]
            continue
        x = res.nodes[i] if res.nodes.size else np.arange(n + 1) / n  # type: ignore[attr-defined]
        c = 0.5 * (x[1:] + x[:-1])
        g = np.abs(np.diff(res.phi[i]) / np.diff(c))  # type: ignore[attr-defined]
        counts.append(int(np.count_nonzero(g >= 0.5 * g.max())))
    return f"{min(counts)} / {int(np.median(counts))}" if counts else "-"


def section_reproduce(gels: list[str]) -> None:
    print("== moving grid (1/ell cells) against the uniform grid (4/ell cells): dose times "
          "10%..90% ==")
    for gel in gels:
        t_start, _ = CASES[gel]
        for ell in (0.005, 0.0025, 0.00125):
            until = UNTIL[gel] if ell < 0.004 else {"ANB": 0.15, "HHT": 0.25}[gel]
            n = int(round(4 / ell))
            tu, wu, _ = run(gel, t_start, until, "lagrangian", n, ell)
            tm, wm, rm = run(gel, t_start, until, "moving", n // 4, ell)
            gap = np.nanmax(np.abs(tm - tu) / tu)
            print(f"{gel} ell={ell:<8} uniform N={n:5d} {_fmt(tu)} ({wu:.1f} s)")
            print(f"{gel} ell={ell:<8} moving  N={n // 4:5d} {_fmt(tm)} ({wm:.1f} s, "
                  f"{rm.diagnostics['steps']} steps, {rm.diagnostics['remaps']} remaps)")
            print(f"   largest gap {100 * gap:.3f}%, solid error {rm.solid_error.max():.1e}, "
                  f"cells across the steepest part (min / median) {steep_cells(rm)}", flush=True)


def section_direct(gels: list[str]) -> None:
    print("== direct runs on the moving grid (400 cells) against the ell -> 0 limit ==")
    for gel, ell in (("HHT", 3.125e-4), ("HHT", 1e-4), ("ANB", 1e-4)):
        if gel not in gels:
            continue
        t_start, _ = CASES[gel]
        t, wall, res = run(gel, t_start, 0.1, "moving", 400, ell, np.array([0.5, 0.8]))
        print(f"{gel} ell={ell:<9} t50 {t[0]:.6f}  t80 {t[1]:.6f}  limit {LIMITS[gel]}  "
              f"off {100 * (t[1] / LIMITS[gel] - 1):+.2f}%  ({wall:.1f} s, "
              f"{res.diagnostics['steps']} steps, cells across the steepest part "
              f"{steep_cells(res)})",
              flush=True)


def section_stiff() -> None:
    print("== Omega = 1e4 (ANB otherwise), 302 -> 308 K, ell = 1e-3: the 50% dose ==")
    gel = replace(preset("ANB"), omega=1e4, name="ANB-stiff")
    values = []
    for n in (400, 800):
        t, wall, res = run(gel, 302.0, 0.2, "moving", n, 1e-3, np.array([0.5]))
        values.append(t[0])
        print(f"N={n}: t50 {t[0]:.6f} ({wall:.1f} s, {res.diagnostics['steps']} steps, cells "
              f"across the steepest part {steep_cells(res)})", flush=True)
    print(f"   change on doubling: {100 * abs(values[1] - values[0]) / values[1]:.3f}%")


def section_delayed(gels: list[str]) -> None:
    print("== ell = 0 Lagrangian lattice (uniform): the delayed-transition bound, t80 ==")
    for gel in gels:
        t_start, _ = CASES[gel]
        row = []
        for n in (200, 400, 800):
            t, wall, _ = run(gel, t_start, 0.35, "lagrangian", n, 0.0, np.array([0.8]))
            row.append(t[0])
            print(f"{gel} N={n}: t80 {t[0]:.5f} ({wall:.1f} s)", flush=True)
        print(f"   {gel} spread {100 * (max(row) - min(row)) / min(row):.2f}%")


def section_speed(gels: list[str]) -> None:
    print("== speed: ell = 2e-4 on the moving grid (400 cells) to the 90% dose; the custom gel "
          "(Omega = 300, ANB's chi) at ell = 1e-4 and 8e-5 to its 50% dose and to t = 0.1 "
          "(the planner's first horizon), 400 and 200 cells ==")
    runs = [(gel, preset(gel), CASES[gel][0], 2e-4, 400, 0.9,
             {"ANB": 0.128, "HHT": 0.127}[gel]) for gel in gels]
    custom = replace(preset("ANB"), omega=300.0, name="custom")
    runs += [("custom", custom, 302.0, ell, n, 0.5, until) for ell in (1e-4, 8e-5)
             for until in (0.02, 0.1) for n in (400, 200)]
    simulate("ANB", 302.0, 308.0, until=1e-3, grid="moving", n=20, interfacial_length=0.05)
    for name, g, t_start, ell, n, frac, until in runs:  # (after the kernels' warm-up)
        a_f = fraction_radius(equilibrium(g, t_start).stretch, frac)
        started = time.perf_counter()
        res = simulate(g, t_start, 308.0, until=until, grid="moving", n=n,
                       interfacial_length=ell, rtol=RTOL, every=until / 50)
        wall = time.perf_counter() - started
        try:
            tf = f"{res.time_to_radius(a_f):.6f}"
        except ValueError:
            tf = f"not reached by t = {until}"
        print(f"{name} ell={ell:g} n={n} until {until}: t{round(100 * frac)} {tf}, {wall:.1f} s, "
              f"{res.diagnostics['steps']} steps ({res.diagnostics['rejected']} rejected), "
              f"{res.diagnostics['remaps']} remaps", flush=True)


THIN_ELLS = (1e-3, 1e-4, 3e-5)
# the time windows of the accepted-step count (docs/moving_mesh.md sec. 7.3)
THIN_WINDOWS = (0.0, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 0.02, 0.05, 0.1)


def section_thin(gels: list[str], mesh: MeshOptions | None = None) -> None:
    print("== thin fronts: the planner's direct run (400 cells, check 200; outputs every "
          f"t = 0.002) to t = 0.1, rtol 1e-5, {mesh or MeshOptions()} ==")
    simulate("ANB", 302.0, 308.0, until=1e-3, grid="moving", n=20, interfacial_length=0.05)
    for gel in gels:
        t_start, _ = CASES[gel]
        base = None
        for ell in THIN_ELLS:
            row = {}
            for n in (400, 200):
                started = time.process_time()
                res = simulate(gel, t_start, 308.0, until=0.1, grid="moving", n=n,
                               interfacial_length=ell, rtol=RTOL, every=0.1 / 50, mesh=mesh)
                cpu = time.process_time() - started
                t = np.array([res.time_to_radius(a) for a in fraction_radius(
                    equilibrium(preset(gel), t_start).stretch, np.array([0.5, 0.8]))])
                d = res.diagnostics
                attempted = d["steps"] + d["rejected"]
                row[n] = t
                edge = res.step_edge
                t_n = res.nucleation_time(0.5 * (float(edge[0]) + float(edge.min())))
                burst = int(np.count_nonzero(res.step_t[1:] < 3.0 * t_n)) if t_n else 0
                print(f"{gel} ell={ell:<7g} n={n}: t50 {t[0]:.6f} t80 {t[1]:.6f}  "
                      f"{attempted} attempted ({d['rejected']} rejected; accepted {burst} "
                      f"through the nucleation at t = {t_n or math.nan:.3g}, "
                      f"{d['steps'] - burst} after), {d['remaps']} remaps / "
                      f"{d['mesh_checks']} checks, {cpu:.2f} s CPU", flush=True)
                if n == 400:
                    base = attempted if base is None else base
                    ratio = attempted / base
                    per = np.histogram(res.step_t[1:], bins=THIN_WINDOWS)[0]
                    print("   accepted steps per window of t (" + ", ".join(
                        f"{lo:g}-{hi:g} {k}" for lo, hi, k in zip(
                            THIN_WINDOWS[:-1], THIN_WINDOWS[1:], per, strict=True)) + ")",
                          flush=True)
            bound = np.abs(row[400] - row[200]) / row[400]
            print(f"   {gel} ell={ell:g}: attempted {ratio:.2f}x those at ell = 1e-3; numerical "
                  f"bound (400 vs 200) t50 {100 * bound[0]:.3f}% t80 {100 * bound[1]:.3f}%",
                  flush=True)


# the mesh options tried on issue 23's figure (docs/moving_mesh.md sec. 7.4)
OPTION_VARIANTS: tuple[dict[str, float], ...] = (
    {}, {"check_every": 1}, {"check_every": 3}, {"tolerance": 2.0}, {"bulk": 8.0},
    {"edge_cells": 2.0}, {"edge_cells": 1.0}, {"grading": 0.2}, {"resolution": 0.15},
    {"resolution": 0.07}, {"edge_cells": 2.0, "resolution": 0.15},
    {"edge_cells": 2.0, "tolerance": 2.0}, {"edge_cells": 2.0, "bulk": 6.0},
    {"edge_cells": 2.0, "finest": 20.0}, {"edge_cells": 2.0, "check_every": 1})


def section_options() -> None:
    print("== mesh options on issue 23's figure: ANB 302 -> 308 K, 400 cells, rtol 1e-5, to "
          "t = 0.08, ell = 1e-3 and 3e-5 (attempted = accepted + rejected) ==")
    simulate("ANB", 302.0, 308.0, until=1e-3, grid="moving", n=20, interfacial_length=0.05)
    a80 = float(fraction_radius(equilibrium(preset("ANB"), 302.0).stretch, 0.8))
    for variant in OPTION_VARIANTS:
        row = []
        for ell in (1e-3, 3e-5):
            res = simulate("ANB", 302.0, 308.0, until=0.08, grid="moving", n=400,
                           interfacial_length=ell, rtol=RTOL, mesh=MeshOptions(**variant))
            d = res.diagnostics
            row.append((d["steps"] + d["rejected"], d["rejected"], res.time_to_radius(a80)))
        (a, ra, ta), (b, rb, tb) = row
        print(f"{variant or 'defaults'}: {a} ({ra} rejected) / {b} ({rb} rejected) attempted, "
              f"{b / a:.2f}x; t80 {ta:.7f} / {tb:.7f}", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--section", choices=("reproduce", "direct", "stiff", "delayed",
                                              "speed", "thin", "options"),
                        action="append")
    parser.add_argument("--gel", choices=tuple(CASES), action="append")
    parser.add_argument("--no-front", action="store_true",
                        help="thin: the band does not move with the front (MeshOptions.front)")
    parser.add_argument("--tolerance", type=float, help="thin: MeshOptions.tolerance")
    args = parser.parse_args()
    sections = args.section or ["reproduce", "direct", "stiff", "delayed", "speed"]
    gels = args.gel or list(CASES)
    for s in sections:
        if s == "reproduce":
            section_reproduce(gels)
        elif s == "direct":
            section_direct(gels)
        elif s == "stiff":
            section_stiff()
        elif s == "delayed":
            section_delayed(gels)
        elif s == "options":
            section_options()
        elif s == "thin":
            kw = {"front": False} if args.no_front else {}
            if args.tolerance is not None:
                kw["tolerance"] = args.tolerance
            section_thin(gels, MeshOptions(**kw))
        else:
            section_speed(gels)


if __name__ == "__main__":
    main()
