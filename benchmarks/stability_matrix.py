"""Stability matrix: the full solver on stiff and extreme inputs (issue 7, issue 3's list).

Run:  .venv/bin/python benchmarks/stability_matrix.py [--smoke | --full] [--out DIR]

Cases: Omega = 1e4, jumps 290 <-> 320 K, starts 0.01 K past a fold (critical slowing down),
the spinodal start ANB 302 -> 312 K, t up to 10, power-law permeability beta = 1.5 and 2,
N = 50 and 1600.  For each: the status ('ok': integrated, finite, solid conserved to 1e-10;
'flagged': finished but not a converged answer, with the solver's message, e.g. a spinodal
collapse; 'failed': SolverError with its message; 'guard': stopped by the wall-clock guard;
'bug': NaN or a crash), steps, rejected steps, max solid-volume error, the final radius against
the equilibrium at T_end, and the wall time (one run).  Runs use the solver's step budget, and
a wall-clock guard behind it so nothing can hang.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.work_precision import (
    FULL,
    SMOKE,
    Log,
    Plan,
    Runner,
    gel_label,
    markdown,
    quiet,
    warm_up,
    write_csv,
)
from solver.equilibrium import folds
from solver.gel import ANB, HHT, Gel
from solver.phase import classify_jump

FOLD_OFFSET = 0.01  # K past a fold
COLUMNS = ("stress", "gel", "jump", "behaviour", "grid", "n", "until", "status", "steps",
           "rejected", "solid_error", "a_end", "a_eq_gap", "wall_s", "message")


@dataclass(frozen=True)
class Stress:
    """One matrix entry: what it stresses, the gel and jump, run length and grid."""

    stress: str
    gel: Gel
    t_start: float
    t_end: float
    until: float
    grid: str = "eulerian"
    n: int = 400


def past_fold(gel: Gel, kind: str) -> float:
    """FOLD_OFFSET kelvin past the gel's fold of ``kind`` ('shrink': above it, where the
    swollen branch has gone; 'swell': below it, where the shrunken branch has gone)."""
    fold = next(f for f in folds(gel) if f.kind == kind)
    return round(fold.temperature + (FOLD_OFFSET if kind == "shrink" else -FOLD_OFFSET), 3)


def both(stress: Stress) -> list[Stress]:
    """The entry on both grids."""
    return [stress, replace(stress, grid="lagrangian")]


def full_matrix() -> list[Stress]:
    """Every stiff and extreme input of issue 3, at N = 400 unless N is the stress."""
    stiff = replace(ANB, omega=1e4)
    return [
        *both(Stress("Omega = 1e4 (front)", stiff, 302, 308, 0.3)),
        *both(Stress("Omega = 1e4 (swelling)", stiff, 308, 302, 1.0)),
        *both(Stress("jump 290 -> 320 K", ANB, 290, 320, 0.3)),
        *both(Stress("jump 320 -> 290 K", ANB, 320, 290, 2.0)),
        Stress("0.01 K past the shrink fold", ANB, 302, past_fold(ANB, "shrink"), 10.0),
        Stress("0.01 K past the swell fold", ANB, 308, past_fold(ANB, "swell"), 10.0),
        *both(Stress("0.01 K past the shrink fold", HHT, 304, past_fold(HHT, "shrink"), 10.0)),
        Stress("0.01 K past the swell fold", HHT, 308, past_fold(HHT, "swell"), 10.0),
        *both(Stress("spinodal start", ANB, 302, 312, 0.3)),
        *both(Stress("t = 10", ANB, 308, 302, 10.0)),
        Stress("beta = 1.5", ANB.with_permeability("power", 1.5), 302, 308, 0.3),
        Stress("beta = 2", ANB.with_permeability("power", 2.0), 302, 308, 0.3),
        *both(Stress("N = 50", ANB, 302, 308, 0.3, n=50)),
        *both(Stress("N = 1600", ANB, 302, 308, 0.3, n=1600)),
    ]


def smoke_matrix() -> list[Stress]:
    """One short, coarse run per kind of stress (CI)."""
    return [
        Stress("Omega = 1e4 (front)", replace(ANB, omega=1e4), 302, 308, 0.02, n=60),
        Stress("jump 290 -> 320 K", ANB, 290, 320, 0.05, n=60),
        Stress("jump 320 -> 290 K", ANB, 320, 290, 0.5, n=60),
        Stress("0.01 K past the shrink fold, t = 10", HHT, 304, past_fold(HHT, "shrink"), 10.0,
               n=60),
        Stress("spinodal start", ANB, 302, 312, 0.05, n=60),
        Stress("beta = 1.5", ANB.with_permeability("power", 1.5), 302, 308, 0.05, n=60),
        Stress("beta = 2", ANB.with_permeability("power", 2.0), 302, 308, 0.05, n=60),
        Stress("N = 1600", HHT, 308, 304, 0.05, n=1600),
    ]


MATRICES = {"full": full_matrix, "smoke": smoke_matrix}


def matrix_row(stress: Stress, runner: Runner) -> dict[str, Any]:
    """Run one entry (no repeats) and describe its outcome."""
    gel = stress.gel
    jump = classify_jump(gel, stress.t_start, stress.t_end)
    out = runner.run(gel, stress.t_start, stress.t_end, stress.until, grid=stress.grid,
                     n=stress.n, timing=False)
    res = out.result
    row: dict[str, Any] = dict.fromkeys(COLUMNS)
    row.update(stress=stress.stress, gel=gel_label(gel),
               jump=f"{stress.t_start:g} -> {stress.t_end:g} K", behaviour=jump.behaviour,
               grid=stress.grid, n=stress.n, until=stress.until, status=out.status,
               message=out.message, wall_s=out.wall, steps=out.diagnostics.get("steps"),
               rejected=out.diagnostics.get("rejected"))
    if res is not None:
        row["solid_error"] = float(np.max(res.solid_error))
        row["a_end"] = float(res.radius[-1])
        row["a_eq_gap"] = abs(row["a_end"] / jump.final_stretch - 1.0)
    return row


def stability_matrix(plan: Plan, log: Log = quiet, runner: Runner | None = None,
                     entries: list[Stress] | None = None) -> list[dict[str, Any]]:
    """The matrix of ``plan`` (its label picks the entries), sharing ``runner``'s runs."""
    runner = runner or Runner(plan, log)
    rows = []
    for stress in entries if entries is not None else MATRICES[plan.label]():
        log(f"matrix: {stress.stress}, {stress.gel.name} {stress.t_start:g}->"
            f"{stress.t_end:g} {stress.grid} N={stress.n}")
        rows.append(matrix_row(stress, runner))
    return rows


def matrix_markdown(rows: list[dict[str, Any]]) -> str:
    """The matrix as a Markdown section."""
    return "\n".join([
        "## Stability matrix", "",
        "status: ok = integrated, finite, solid conserved to 1e-10; flagged = finished but "
        "not a converged answer (message); failed = SolverError (message); a_eq_gap = "
        "|a_end / a_eq(T_end) - 1| (small once the run has settled).", "",
        markdown(rows, COLUMNS), ""])


def main(argv: list[str] | None = None) -> int:
    """Run the matrix and print it."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    mode = ap.add_mutually_exclusive_group()
    mode.add_argument("--smoke", action="store_true", help="the reduced CI subset (default)")
    mode.add_argument("--full", action="store_true", help="every entry")
    ap.add_argument("--out", type=Path, default=None, help="also write CSV and Markdown here")
    args = ap.parse_args(argv)
    plan = FULL if args.full else SMOKE
    warm_up()
    rows = stability_matrix(plan, log=lambda m: print(m, file=sys.stderr, flush=True))
    text = matrix_markdown(rows)
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        write_csv(args.out / "stability_matrix.csv", rows, COLUMNS)
        (args.out / "stability_matrix.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
