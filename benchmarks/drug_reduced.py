"""The reduced drug model against the full solver (issue 23): the error table.

Run:  nice -n 10 .venv/bin/python -m benchmarks.drug_reduced
          (the stored error table; --table recomputes it, --region: where it answers,
           --emit: dosing.payload.reduced.MEASURED's JSON, --convergence: its own numerical error)

Full-solver reference: the planner's drug run of a 50 um bead (``dosing.payload.drug``: the
mechanics
on the truth's settings, the moving grid at the bead's own ell, N = 400, rtol 1e-5, its
heating cut at ``CUTS`` so that every decade of time from 1e-5 tau has 200 outputs, then
the solute on its 400 resampled cells, ``solver.solute.release_on_nodes``), read by the
same cubic as the reduced model.  The mechanics do not depend on the drug, so one
mechanical run per gel serves every drug: it and every drug's dose times are cached on disk
in ``benchmarks/.drug_reduced/`` (not committed); the table is kept in
``benchmarks/drug_reduced_table.json``.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

CACHE = Path(__file__).resolve().parent / ".drug_reduced"
JUMPS = {"ANB": ("ANB", 302.0, 308.0), "HHT": ("HHT", 304.0, 308.0)}
DRY_UM = 50.0
HORIZON = 2.0  # tau: the full solver's drug run covers every dose of the table
# the reference's protocol steps (tau): one heating, cut so that simulate_protocol's outputs
# (at least dosing.runs.solute.MIN_SAMPLES a step) resolve every decade of time from 1e-5 tau: a
# fast drug's small doses are out long before the planner's first output at 5e-4 tau
CUTS = (1e-5, 1e-4, 1e-3, 1e-2, 0.5, HORIZON)


def fluid_request(name: str):
    """The 50 um bead's fluid request (its settings are the drug runs' truth)."""
    from dosing import DoseRequest

    gel, t0, t1 = JUMPS[name]
    return DoseRequest(gel, t0, t1, dose_fraction=0.5, dry_radius_um=DRY_UM)


def mechanics(name: str, cache: Path = CACHE):
    """The full solver's drug mechanics for ``name`` (cached on disk)."""
    from dosing.runs.solute import drug_settings, simulate_protocol
    from solver.full import FullResult

    cache.mkdir(parents=True, exist_ok=True)
    path = cache / f"mech-{name}-{DRY_UM:g}um-{HORIZON:g}tau-early.npz"
    if path.exists():
        return FullResult.load(path)
    req = fluid_request(name)
    gel, t0, t1 = JUMPS[name]
    s = drug_settings(req.settings)
    w = time.process_time()
    steps = [(b - a, t1) for a, b in zip((0.0, *CUTS[:-1]), CUTS, strict=True)]
    res = simulate_protocol(req.gel, t0, steps, "swollen", s, budget=3600.0)
    res.diagnostics["cpu_seconds"] = time.process_time() - w
    res.save(path)
    (cache / f"mech-{name}.json").write_text(json.dumps(
        {"settings": s.to_dict() if hasattr(s, "to_dict") else str(s),
         "cpu": time.process_time() - w}))
    return res


DOSES = (0.1, 0.3, 0.5, 0.7, 0.9)
D0S = (1e-9, 3e-9, 1e-8, 3e-8, 1e-7, 3e-7, 1e-6, 3e-6, 1e-5)  # cm^2/s at 25 degC
R_S, R_F = 1.0, 1.0  # nm: a drug (r_s / xi_dry = 0.25) and the fibre radius
R_SMALL = 0.25  # nm: a small molecule (r_s / xi_dry = 1/16)
LAWS = {  # name -> DrugModel fields besides D0 (docs/drug.md; the mesh is the gel's 4 nm)
    "none": {"hindrance": "none"},
    "free-volume": {"hindrance": "free-volume", "solute_radius_nm": R_S},
    "ogston": {"hindrance": "ogston", "solute_radius_nm": R_S, "fiber_radius_nm": R_F},
    "amsden": {"hindrance": "amsden", "solute_radius_nm": R_S, "fiber_radius_nm": R_F},
    "free-volume, r_s(D0)": {"hindrance": "free-volume"},  # Stokes-Einstein radius
    "free-volume, small": {"hindrance": "free-volume", "solute_radius_nm": R_SMALL},
    "ogston, small": {"hindrance": "ogston", "solute_radius_nm": R_SMALL,
                      "fiber_radius_nm": R_F},
    "amsden, small": {"hindrance": "amsden", "solute_radius_nm": R_SMALL,
                      "fiber_radius_nm": R_F},
}
HINDERED_D0S = (1e-9, 1e-8, 1e-7, 3e-7, 1e-6, 3e-6, 1e-5)
SMALL_D0S = (1e-9, 1e-8, 1e-7, 1e-6, 1e-5)
SE_D0S = (1e-6, 3e-6, 1e-5)  # below ~5e-7 cm^2/s the Stokes-Einstein solute exceeds the mesh
REF = {"cells": 384, "per_cell": 3, "rtol": 1e-6, "hold": 200}  # the reduced model converged


def solute(name: str, law: str, d0: float):
    """The dimensionless solute of the table's drug on the 50 um bead of ``name``."""
    from dosing.payload.drug import DrugModel

    req = fluid_request(name)
    drug = DrugModel(diffusivity_cm2_s=d0, **LAWS[law])
    return drug.solute(req.start_radius, req.t_end, req.constants, req.bead_dry_radius_um)


def refined(res, first: int = 8, extra: int = 12):
    """The full run's node volumes with ``extra`` samples (linear in time, as the solute
    kernels read them between samples) inserted in each of its ``first`` intervals, so the
    release is read where it grows like sqrt(t)."""
    from solver.solute import node_volumes

    t = np.asarray(res.t, dtype=float)
    s3 = node_volumes(res)
    new = [t]
    for k in range(first):
        new.append(t[k] + (t[k + 1] - t[k]) * np.geomspace(1e-3, 1.0, extra + 1)[:-1])
    tt = np.unique(np.concatenate(new))
    s3n = np.stack([np.interp(tt, t, s3[:, i]) for i in range(s3.shape[1])], axis=1)
    return tt, s3n, np.interp(tt, t, res.radius)


def dose_times(rel) -> list[float | None]:
    """The table's doses read off a release (None where not reached)."""
    from solver.front.solute import time_to_release

    out = []
    for f in DOSES:
        try:
            out.append(time_to_release(rel, f))
        except ValueError:
            out.append(None)
    return out


def full_times(name: str, law: str, d0: float, cache: Path = CACHE) -> list[float | None]:
    """The full solver's dose times of one drug (cached on disk as JSON)."""
    from solver.solute.transport import release_on_nodes

    path = cache / f"full-{name}-{law.replace(' ', '').replace(',', '_')}-{d0:g}.json"
    if path.exists():
        return json.loads(path.read_text())["times"]
    res = mechanics(name, cache)
    t, s3, radius = refined(res)
    w = time.process_time()
    for cut in (0.5, HORIZON):  # the first 0.5 tau serve most drugs (the release is causal)
        k = int(np.searchsorted(t, cut * (1 + 1e-12), side="right"))
        rel = release_on_nodes(t[:k], s3[:k], solute(name, law, d0), radius=radius[:k],
                               profiles=2, twin=False)
        times = dose_times(rel)
        if times[-1] is not None:
            break
    path.write_text(json.dumps({"times": times, "cpu": time.process_time() - w,
                                "released_end": float(rel.released_fraction[-1])}))
    return times


def reduced_times(name: str, law: str, d0: float, **grid) -> list[float | None]:
    """The reduced model's dose times (``grid``: front_release's cells, per_cell, ...)."""
    from dosing.model_choice import front_run
    from solver.front.solute import front_release

    gel, t0, t1 = JUMPS[name]
    fr = front_run(fluid_request(name).gel, t0, t1, "swollen", True)
    return dose_times(front_release(fr, solute(name, law, d0), **grid))


def cases():
    for law in LAWS:
        for d0 in (SE_D0S if law.endswith("r_s(D0)") else D0S if law == "none"
                   else SMALL_D0S if law.endswith("small") else HINDERED_D0S):
            yield law, d0


def table_rows(cache: Path = CACHE) -> list[dict]:
    """Every case: the full and reduced dose times and the reduced model's numerical ones."""
    rows = []
    for law, d0 in cases():
        row = {"law": law, "d0": d0}
        for name in JUMPS:
            row[name] = {"full": full_times(name, law, d0, cache),
                         "reduced": reduced_times(name, law, d0)}
        rows.append(row)
        print(json.dumps(row), flush=True)
    return rows


def rel_err(a, b) -> float | None:
    return None if a is None or b is None else a / b - 1.0


RESULT = Path(__file__).resolve().parent / "drug_reduced_table.json"
ERRORS = Path(__file__).resolve().parent.parent / "dosing" / "data" / "drug_reduced_errors.json"
CONVERGENCE = {"no hindrance, D0 = 1 D_gel": (1.0, {"law": "none", "convective": False}),
               "no hindrance, D0 = 30 D_gel": (30.0, {"law": "none", "convective": False}),
               "Ogston r_s/r_f = 1, sieved r_s/xi_dry = 0.3, D0 = 3 D_gel":
                   (3.0, {"law": "ogston", "fiber": 1.0, "mesh": 0.3})}


def convergence() -> None:
    """``--convergence``: the reduced model's own error (its defaults against 384 cells,
    three samples per node crossing, rtol 1e-6) and its CPU time per release."""
    from dosing.model_choice import front_run
    from solver.front.solute import front_release
    from solver.solute import Hindrance, Solute

    print("reduced model: max relative error of the 10-90 % dose times, defaults against "
          f"{REF}; CPU ms per release (median of 5)")
    for name in JUMPS:
        gel, t0, t1 = JUMPS[name]
        fr = front_run(fluid_request(name).gel, t0, t1, "swollen", True)
        for label_, (d, h) in CONVERGENCE.items():
            sol = Solute(d, Hindrance(**h))
            ref = np.array(dose_times(front_release(fr, sol, **REF)), dtype=float)
            got = np.array(dose_times(front_release(fr, sol)), dtype=float)
            cpu = []
            for _ in range(5):
                c = time.process_time()
                front_release(fr, sol)
                cpu.append(time.process_time() - c)
            print(f"  {name} {label_:<58} {np.nanmax(np.abs(got / ref - 1)):.2%}  "
                  f"{1e3 * float(np.median(cpu)):.1f} ms")


def fmt(e: float | None) -> str:
    """A relative error in % (n/a: a dose one of the two does not reach)."""
    if e is None:
        return "n/a"
    return f"{100 * e:+.1f}" if abs(e) < 10.0 else (">+1000" if e > 0 else "<-1000")


def label(variant: str) -> str:
    """The table's name of a drug: its law and radius."""
    law = LAWS[variant]["hindrance"]
    if variant.endswith("r_s(D0)"):
        return f"{law}, r_s(D0)"
    r = LAWS[variant].get("solute_radius_nm")
    return law if r is None else f"{law}, r_s {r:g} nm"


def markdown(rows: list[dict]) -> str:
    """The error table: (reduced - full) / full of the dose time, %, ANB / HHT."""
    head = "| law | D0 (cm^2/s, 25 degC) | " + " | ".join(f"{int(100 * f)} %" for f in DOSES)
    lines = [head + " |", "|---|---|" + "---|" * len(DOSES)]
    for row in rows:
        cells = []
        for i in range(len(DOSES)):
            cells.append(" / ".join(fmt(rel_err(row[n]["reduced"][i], row[n]["full"][i]))
                                    for n in JUMPS))
        lines.append(f"| {label(row['law'])} | {row['d0']:g} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def measured(rows: list[dict]) -> dict:
    """``dosing.payload.reduced.MEASURED``: law -> [((r_s / xi_dry, r_s / r_f), D0 / D_gel of
    its rows, the largest |error| of both gels per dose; None where a dose is not reached
    by both)] (the Stokes-Einstein rows, whose ratios change with D0, are left out)."""
    out: dict[str, list] = {}
    for variant in LAWS:
        if variant.endswith("r_s(D0)"):
            continue
        ds, errs, ratios = [], [], None
        for row in rows:
            if row["law"] != variant:
                continue
            sol = solute("ANB", variant, row["d0"])
            ratios = (float(f"{sol.hindrance.mesh_ratio:.6g}"),
                      float(f"{sol.hindrance.fiber_ratio:.6g}"))
            ds.append(float(f"{sol.diffusivity:.12g}"))
            es = []
            for i in range(len(DOSES)):
                e = [rel_err(row[n]["reduced"][i], row[n]["full"][i]) for n in JUMPS]
                es.append(None if any(x is None for x in e) else
                          float(f"{max(abs(x) for x in e):.4f}"))
            errs.append(tuple(es))
        if ds:
            law = LAWS[variant]["hindrance"]
            out.setdefault(law, []).append((ratios, tuple(ds), tuple(errs)))
    return out


def region(rows: list[dict], limit: float = 0.05) -> str:
    """Where the reduced model answers (dosing.payload.reduced.stated_error), per law: the
    doses answered at each measured D0 (a cell needs all its corners within ``limit``)."""
    import dosing.payload.reduced as dr

    table = measured(rows)
    lines = ["| law | D0 (cm^2/s) | " + " | ".join(f"{int(100 * f)} %" for f in DOSES)
             + " |", "|---|---|" + "---|" * len(DOSES)]
    for law in LAWS:
        for row in rows:
            if row["law"] != law:
                continue
            sol = solute("ANB", law, row["d0"])
            cells = []
            for f in DOSES:
                e = dr.stated_error(sol, f, table)
                cells.append("full" if e is None else f"{100 * e:.1f}")
            if any(c != "full" for c in cells):
                lines.append(f"| {label(law)} | {row['d0']:g} | " + " | ".join(cells)
                             + " |")
    return "\n".join(lines)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--mechanics", action="store_true", help="only compute the cached runs")
    p.add_argument("--table", action="store_true", help="compute (cached) and print the table")
    p.add_argument("--convergence", action="store_true",
                   help="the reduced model's own numerical error and cost")
    p.add_argument("--emit", action="store_true",
                   help="write dosing.payload.reduced.MEASURED (its JSON) from the stored table")
    p.add_argument("--region", action="store_true",
                   help="print where the reduced model answers and its stated error")
    args = p.parse_args()
    if args.mechanics:
        for name in JUMPS:
            w = time.process_time()
            res = mechanics(name)
            print(name, res.t.size, res.t[-1], f"{time.process_time() - w:.1f} s", flush=True)
        return
    if args.convergence:
        convergence()
        return
    if args.table:
        rows = table_rows()
        RESULT.write_text(json.dumps(rows, indent=1))
    else:
        rows = json.loads(RESULT.read_text())
    if args.emit:
        ERRORS.write_text(json.dumps(measured(rows), indent=1))
        print(f"wrote {ERRORS}")
    elif args.region:
        print(region(rows))
    else:
        print(markdown(rows))


if __name__ == "__main__":
    main()
