"""Unit strings on the command line: every option whose name states a physical unit
(``--t-start``, ``--dry-radius-um``, ``--k0-m2``, ...) also takes a quantity with a unit
("29 degC", "50 um", "10 min"), converted to the documented unit by dosing.quantity; a
wrong unit exits 2 naming the option.  Plain numbers are read as before."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any


def _converter(dest: str, plain: Callable[[str], Any]) -> Callable[[str], Any]:
    def convert(text: str) -> Any:
        try:
            return plain(text)
        except (TypeError, ValueError):
            pass
        from dosing.quantity import UNITS, field_kind, from_edge
        from solver.errors import ParameterError

        try:
            value = from_edge(dest, text)
        except ParameterError as exc:
            raise argparse.ArgumentTypeError(f"{text!r}: {exc.valid}") from None
        if isinstance(value, str):
            raise argparse.ArgumentTypeError(
                f"{text!r}: a number in {UNITS[field_kind(dest) or '']} or a quantity with a "
                "unit") from None
        return value

    convert.__name__ = getattr(plain, "__name__", "float")  # argparse's 'invalid X value'
    return convert


def accept_units(sub: argparse._SubParsersAction) -> None:
    """Let every physical option of every sub-command (and nested sub-command) take unit
    strings: its ``type`` (float) is wrapped by the converter."""
    from dosing.quantity import field_kind

    seen: set[int] = set()

    def walk(parser: argparse.ArgumentParser) -> None:
        if id(parser) in seen:
            return
        seen.add(id(parser))
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for child in action.choices.values():
                    walk(child)
            elif (isinstance(action, (argparse._StoreAction, argparse._AppendAction))
                  and action.type is float and field_kind(action.dest) is not None):
                action.type = _converter(action.dest, float)

    for child in sub.choices.values():
        walk(child)
