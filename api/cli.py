"""The ``thermogel`` command line.

Each sub-command lives in its own ``api/commands/<name>.py`` module exposing
``register(subparsers)``; heavy imports (fastapi, matplotlib) happen inside commands.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys

from solver.errors import NotApplicableError, ParameterError, SolverError

COMMANDS = ["equilibrium", "classify", "phase_map", "serve", "front", "dose", "schedule",
            "simulate", "plot", "bench", "sweep", "fit", "release", "sensitivity"]


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every registered sub-command."""
    parser = argparse.ArgumentParser(
        prog="thermogel", description="Plan drug release from thermo-responsive gel beads.")
    sub = parser.add_subparsers(dest="command", required=True)
    for name in COMMANDS:
        importlib.import_module(f"api.commands.{name}").register(sub)
    importlib.import_module("api.commands.units").accept_units(sub)  # "50 um", "29 degC"
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point: parse, run, and turn input errors into exit code 2 with a message."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except (ParameterError, NotApplicableError) as exc:
        print(f"thermogel: error: {exc}", file=sys.stderr)
        return 2
    except SolverError as exc:
        print(f"thermogel: solver failed: {exc}", file=sys.stderr)
        return 3
    except BrokenPipeError:
        # the reader went away (``thermogel ... | head``): stop quietly, as a shell tool does
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 141  # 128 + SIGPIPE


if __name__ == "__main__":
    sys.exit(main())
