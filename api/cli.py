"""The ``thermogel`` command line.

Each sub-command lives in its own ``api/commands/<name>.py`` module exposing
``register(subparsers)``; heavy imports (fastapi, matplotlib, scipy, numba kernels) happen
inside commands, and only the command named on the command line is imported (every one
for the top-level help), so a call pays only for what it uses.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys

from solver.errors import NotApplicableError, ParameterError, SolverError  # a leaf module

COMMANDS = ["equilibrium", "classify", "phase_map", "serve", "front", "dose", "schedule",
            "simulate", "plot", "bench", "sweep", "fit", "release", "sensitivity",
            "compare", "design"]


def build_parser(commands: list[str] | None = None) -> argparse.ArgumentParser:
    """The argument parser with the sub-commands ``commands`` (default: every one)."""
    parser = argparse.ArgumentParser(
        prog="thermogel", description="Plan drug release from thermo-responsive gel beads.")
    sub = parser.add_subparsers(dest="command", required=True)
    for name in COMMANDS if commands is None else commands:
        importlib.import_module(f"api.commands.{name}").register(sub)
    importlib.import_module("api.commands.units").accept_units(sub)  # "50 um", "29 degC"
    return parser


def chosen_commands(argv: list[str]) -> list[str] | None:
    """The module of the sub-command named on the command line (its first word that is not
    an option), or None (every command: the top-level help, or a name argparse rejects)."""
    for word in argv:
        if word.startswith("-"):
            return None  # the parser's own options (-h) come before any command
        name = word.replace("-", "_")
        return [name] if name in COMMANDS else None
    return None


def main(argv: list[str] | None = None) -> int:
    """Entry point: parse, run, and turn input errors into exit code 2 with a message."""
    parser = build_parser(chosen_commands(sys.argv[1:] if argv is None else argv))
    args = parser.parse_args(argv)
    from .commands.common import set_request
    from .commands.outfile import request_of

    set_request(request_of(args))
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
