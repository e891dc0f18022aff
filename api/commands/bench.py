"""``thermogel bench``: the work-precision report and the stability matrix (issue 7).

The report's library is the source tree's ``benchmarks`` package (work_precision.py,
stability_matrix.py, which reuse full_solver.py and front_model.py), installed with the
project from a source checkout (``pip install -e .``).
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Callable
from pathlib import Path
from types import ModuleType


def load_benchmarks() -> tuple[ModuleType, ModuleType]:
    """The ``benchmarks.work_precision`` and ``benchmarks.stability_matrix`` modules."""
    try:
        return (importlib.import_module("benchmarks.work_precision"),
                importlib.import_module("benchmarks.stability_matrix"))
    except ModuleNotFoundError as exc:
        if exc.name not in ("benchmarks", "benchmarks.work_precision",
                            "benchmarks.stability_matrix"):
            raise
        raise SystemExit("thermogel bench: error: the benchmarks package is not installed "
                         "(it ships with the source tree: pip install -e . in a checkout)"
                         ) from None


def register(sub: argparse._SubParsersAction) -> None:
    """Add the sub-command."""
    p = sub.add_parser("bench", help="work-precision report and stability matrix of the solvers")
    mode = p.add_mutually_exclusive_group()
    mode.add_argument("--smoke", action="store_true",
                      help="the reduced subset run in CI, about a minute (default)")
    mode.add_argument("--full", action="store_true",
                      help="every case, N = 50-1600, rtol 1e-3-1e-8 (about 15 min on 2 cores)")
    p.add_argument("--out", type=Path, default=Path("bench-out"),
                   help="directory for the CSV, Markdown, PNG and log files (default bench-out)")
    p.add_argument("--interfacial-length", type=float, default=None, metavar="ELL",
                   help="interfacial length of the front cases, when the full solver has the "
                        "term (default 0.01 then; 0: the paper's model)")
    p.set_defaults(func=run)


def _logger(path: Path) -> Callable[[str], None]:
    """Progress to stderr and to ``path``."""
    path.write_text("")

    def log(message: str) -> None:
        print(message, file=sys.stderr, flush=True)
        with path.open("a") as fh:
            fh.write(message + "\n")

    return log


def run(args: argparse.Namespace) -> int:
    """Measure, write the files, print the tables; exit 1 if a run gave NaN, crashed or hit the
    wall-clock guard."""
    from api.plots.work_precision import draw_work_precision

    wp, sm = load_benchmarks()
    plan = wp.PLANS["full" if args.full else "smoke"]
    ell = wp.report_ell(args.interfacial_length)
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    log = _logger(out / "bench.log")
    runner = wp.Runner(plan, log)
    report = wp.work_precision(plan, ell, log, runner)
    matrix = sm.stability_matrix(plan, log, runner)
    files = list(wp.save(report, out).values())
    files.append(wp.write_csv(out / "stability_matrix.csv", matrix, sm.COLUMNS))
    (out / "stability_matrix.md").write_text(sm.matrix_markdown(matrix))
    files.append(out / "stability_matrix.md")
    for metric in ("err_a", "err_t80"):
        files.append(draw_work_precision(report.rows, out / f"work_precision_{metric}.png",
                                         metric))
    print(wp.report_markdown(report))
    print(sm.matrix_markdown(matrix))
    for path in files:
        print(f"wrote {path}")
    bad = [r for r in [*report.rows, *matrix] if r["status"] in ("bug", "guard")]
    for r in bad:
        print(f"thermogel bench: {r['status']}: {r.get('stress') or r.get('method')} "
              f"{r.get('case') or r.get('jump')}: {r.get('message') or r.get('note')}",
              file=sys.stderr)
    return 1 if bad else 0
