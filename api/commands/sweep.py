"""``thermogel sweep``: a design map over T_end x bead size x dose (and gels), front model
at once, full-solver validations for a chosen subset; CSV / JSON tables and heat maps.

Axes are comma lists (``308,309,310``) or ranges ``start:stop:num`` (evenly spaced;
``start:stop:num:log`` for geometric spacing).  ``--workers N`` runs the chunks on a process
pool, ``--dask ADDRESS`` on a Dask cluster (``tcp://scheduler:8786``), ``--dask-local N``
on a LocalCluster of N worker processes started for the run.
"""

from __future__ import annotations

import argparse
import sys
from concurrent.futures import ThreadPoolExecutor
from contextlib import ExitStack
from pathlib import Path
from typing import Any

from solver.errors import ParameterError

from .common import print_json
from .outfile import add_format_option, figure_path, request_of


def parse_axis(name: str, text: str) -> list[float]:
    """'a,b,c' or 'start:stop:num[:log]' as a list of floats (ParameterError names ``name``)."""
    import numpy as np

    from dosing.quantity import field_kind, to_unit

    kind = field_kind(name.removeprefix("--").replace("-", "_"))

    def value(v: str) -> float:
        """A number in the axis's unit, or a quantity with its own ('35 degC', '20 um')."""
        v = v.strip()
        if kind is None or not any(c.isalpha() for c in v.replace("e", "").replace("E", "")):
            return float(v)
        return to_unit(v, kind, name)

    try:
        if ":" not in text:
            return [value(v) for v in text.split(",") if v.strip()]
        parts = text.split(":")
        if len(parts) not in (3, 4) or (len(parts) == 4 and parts[3] != "log"):
            raise ValueError(text)
        lo, hi, num = value(parts[0]), value(parts[1]), int(parts[2])
        if not 1 <= num <= 1000:
            raise ValueError(text)
        if len(parts) == 4:
            if lo <= 0 or hi <= 0:
                raise ValueError(text)
            return np.geomspace(lo, hi, num).tolist()
        return np.linspace(lo, hi, num).tolist()
    except ParameterError:
        raise  # a quantity of the wrong kind, named by to_unit
    except ValueError:
        raise ParameterError(name, text, "a comma list of numbers or start:stop:num[:log] "
                             "(1 <= num <= 1000; log needs positive ends)") from None


def _validate_arg(text: str | None) -> Any:
    if text is None:
        return ()
    if text in ("all", "needs-full"):
        return text
    try:
        return [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise ParameterError("--validate", text, "'all', 'needs-full' or point indices "
                             "'0,5,17'") from None


def gels_from_args(presets: list[str] | None, vary: list[str] | None) -> list[Any]:
    """The grid's gels: each preset, or each preset along the --vary axes."""
    from dosing.studies.sweep import vary_gel

    names = presets or ["ANB"]
    if not vary:
        return list(names)
    axes: dict[str, list[float]] = {}
    for item in vary:
        param, sep, text = item.partition("=")
        if not sep:
            raise ParameterError("--vary", item, "PARAM=AXIS, e.g. omega=50:200:4")
        axes[param.strip()] = parse_axis(f"--vary {param.strip()}", text)
    return [g for name in names for g in vary_gel(name, **axes)]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the sub-command."""
    p = sub.add_parser("sweep", help="design map: actuation times over T_end x bead size x "
                                     "dose with the front model (CSV, JSON, heat maps)")
    p.add_argument("--gel", action="append", default=None,
                   help="preset gel, repeat for several (default ANB)")
    p.add_argument("--vary", action="append", default=None, metavar="PARAM=AXIS",
                   help="vary a gel parameter (omega, a0, b0, a1, b1) of each --gel over a "
                        "list or range, e.g. omega=50:200:4; repeat for a product")
    p.add_argument("--t-start", type=float, default=302.0, help="start temperature in K")
    p.add_argument("--t-end", required=True, help="heating temperatures in K: list or range")
    p.add_argument("--dry-radius-um", required=True, help="dry bead radii in um: list or range")
    p.add_argument("--dose", required=True, help="doses, fractions of the stored fluid")
    p.add_argument("--size-cv", default=None, metavar="AXIS",
                   help="a fifth axis: batches of beads, the CV of a number-weighted lognormal "
                        "whose mean is each dry radius (list or range, 0-2); time and seconds "
                        "are the batch's, --plot draws the CV x dose map (docs/batch.md)")
    p.add_argument("--branch", choices=["swollen", "shrunken"], default=None)
    p.add_argument("--interfacial-length", type=float, default=None, metavar="L",
                   help="truth's interfacial length (default: each point's bead's own, "
                        "xi_dry / a_d, as in `thermogel dose`; 0 = the paper's model, "
                        "answered by the paper's front model)")
    p.add_argument("--validate", default=None, metavar="WHICH",
                   help="queue full-solver validations: 'needs-full', 'all' or indices "
                        "'0,5,17'; waits for them and fills truth_time / front_time_error")
    ex = p.add_mutually_exclusive_group()
    ex.add_argument("--workers", type=int, default=None,
                    help="run the chunks on a process pool of this many workers")
    ex.add_argument("--dask", default=None, metavar="ADDRESS",
                    help="run on a Dask cluster: its scheduler address")
    ex.add_argument("--dask-local", type=int, default=None, metavar="N",
                    help="run on a Dask LocalCluster of N worker processes")
    p.add_argument("--csv", default=None, metavar="FILE", help="write the table as CSV "
                                                              "('-': stdout)")
    p.add_argument("--json", default=None, metavar="FILE", help="write the table as JSON "
                                                               "('-': stdout)")
    p.add_argument("--plot", default=None, metavar="FILE",
                   help="heat maps of time and error (PNG, PDF or SVG)")
    add_format_option(p)
    p.add_argument("--out", default=None, metavar="FILE.nc",
                   help="write the map as netCDF (.nc: gel x t_end x dry_radius_um x "
                        "dose_fraction, units and provenance) or tidy CSV (.csv)")
    p.add_argument("--plot-gel", type=int, default=0, metavar="I",
                   help="which gel of the grid to plot (default 0, the first)")
    p.add_argument("--cache", default=None, help="validation cache file")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.set_defaults(func=run)


def _executor(args: argparse.Namespace, stack: ExitStack) -> Any:
    if args.workers is not None:
        if args.workers < 1:
            raise ParameterError("--workers", args.workers, "an integer >= 1")
        from dosing.runs.jobs import default_executor

        return stack.enter_context(default_executor(args.workers))
    if args.dask is None and args.dask_local is None:
        return None
    try:
        import distributed
    except ImportError:
        raise ParameterError("--dask", args.dask, "needs dask[distributed] installed "
                             "(pip install 'thermogel[dask]')") from None
    if args.dask_local is not None:
        if args.dask_local < 1:
            raise ParameterError("--dask-local", args.dask_local, "an integer >= 1")
        cluster = stack.enter_context(distributed.LocalCluster(
            n_workers=args.dask_local, threads_per_worker=1, dashboard_address=None))
        client = stack.enter_context(distributed.Client(cluster))
    else:
        client = stack.enter_context(distributed.Client(args.dask))
    return client.get_executor()


def _write(text: str, target: str) -> None:
    if target == "-":
        sys.stdout.write(text if text.endswith("\n") else text + "\n")
    else:
        Path(target).write_text(text)
        print(f"wrote {target}", file=sys.stderr)


def _wait(planner: Any, result: Any, quiet: bool) -> None:
    """Poll the queued validations with a progress bar until every one has finished."""
    import time

    from tqdm import tqdm

    from dosing.studies.sweep import fill_validations

    total = sum(1 for r in result.rows if r["validation_id"])
    with tqdm(total=total, desc="validations", unit="run", disable=quiet,
              file=sys.stderr) as bar:
        while (left := fill_validations(result, planner)) > 0:
            bar.update(total - left - bar.n)
            time.sleep(0.5)
        bar.update(total - bar.n)


def run(args: argparse.Namespace) -> int:
    """Run the sweep; print a summary (and the tables where asked)."""
    from tqdm import tqdm

    from dosing import Planner, SolverSettings
    from dosing.studies.sweep import SweepGrid, run_sweep

    settings = (None if args.interfacial_length is None
                else SolverSettings(interfacial_length=args.interfacial_length))
    grid = SweepGrid(t_ends=parse_axis("--t-end", args.t_end),
                     dry_radii_um=parse_axis("--dry-radius-um", args.dry_radius_um),
                     doses=parse_axis("--dose", args.dose),
                     gels=gels_from_args(args.gel, args.vary),
                     t_start=args.t_start, branch=args.branch, settings=settings,
                     size_cvs=None if args.size_cv is None
                     else parse_axis("--size-cv", args.size_cv))
    if grid.size_cvs is not None and args.out:
        raise ParameterError("--out", args.out, "absent with --size-cv (the netCDF export "
                             "has the four single-bead axes; use --csv or --json)")
    validate = _validate_arg(args.validate)
    with ExitStack() as stack:
        executor = _executor(args, stack)
        planner = None
        if validate:  # full-solver runs on the sweep's executor, or on threads of this process
            runs = executor or stack.enter_context(ThreadPoolExecutor(2))
            planner = stack.enter_context(Planner(cache_path=args.cache, executor=runs))
        with tqdm(total=grid.size, desc="sweep", unit="point", disable=args.no_progress,
                  file=sys.stderr) as bar:
            result = run_sweep(grid, executor=executor, planner=planner, validate=validate,
                               progress=bar.update)
        if planner is not None:
            _wait(planner, result, args.no_progress)
    table = result.to_dict()
    if args.out:
        from dosing.present import export

        print(f"wrote {export.save(result.to_xarray(request=request_of(args)), args.out)}",
              file=sys.stderr)
    if args.csv:
        _write(result.to_csv(), args.csv)
    if args.json == "-":
        print_json(table)
    elif args.json:
        _write(result.to_json(), args.json)
    if args.plot:
        from api.plots.sweep import draw_sweep

        if not 0 <= args.plot_gel < grid.shape[0]:
            raise ParameterError("--plot-gel", args.plot_gel, f"0-{grid.shape[0] - 1}")
        if grid.size_cvs is not None:  # the CV x dose map (issue 26)
            from api.plots.batch import draw_cv_map as draw_sweep
        print(f"wrote {draw_sweep(table, figure_path(args.plot, args.format), args.plot_gel)}",
              file=sys.stderr)
    counts = ", ".join(f"{v} {k}" for k, v in result.counts.items())
    print(f"{grid.size} points ({' x '.join(map(str, grid.shape))} gels x T_end x radius x "
          f"dose{'' if grid.size_cvs is None else ' x CV'}) in {result.seconds:.3f} s: "
          f"{counts}", file=sys.stderr)
    return 0
