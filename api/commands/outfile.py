"""``--out FILE``: .npz (the run's own codec), .nc (netCDF with units and provenance) or
.csv (tidy, ``name [unit]`` headers), chosen by the suffix (dosing.export)."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path
from typing import Any

SUFFIXES = (".npz", ".nc", ".csv")
OUT_HELP = ("save to this file: .npz, .nc (netCDF: units, long names, the code version and "
            "the request in its attributes) or .csv (tidy, 'name [unit]' headers)")


def request_of(args: argparse.Namespace) -> dict[str, Any]:
    """The command's arguments as the export's request (what made the result)."""
    plain = (str, int, float, bool, type(None), list, tuple, dict)
    out = {k: (v if isinstance(v, plain) else str(v)) for k, v in vars(args).items()
           if k not in ("func",) and not callable(v)}
    out["command"] = getattr(args, "command", None)
    return out


def save(path: str, save_npz: Callable[[str], Path], dataset: Callable[[], Any]) -> Path:
    """Write ``path`` by its suffix: ``save_npz`` for .npz (and no suffix), else the
    Dataset ``dataset()`` through :func:`dosing.export.save`."""
    suffix = Path(path).suffix
    if suffix in (".nc", ".csv", ".xlsx"):
        from dosing import export

        return export.save(dataset(), path)
    return save_npz(path)


FORMATS = ("png", "svg", "pdf")


def add_format_option(p: argparse.ArgumentParser) -> None:
    """``--format svg|png|pdf`` for a command that draws (default: the file's suffix)."""
    p.add_argument("--format", choices=FORMATS, default=None,
                   help="figure format: svg, png or pdf (default: the file's suffix, else png)")


def figure_path(path: str, fmt: str | None) -> str:
    """``path`` with the suffix of ``fmt`` (unchanged when ``fmt`` is None)."""
    return path if fmt is None else str(Path(path).with_suffix("." + fmt))
