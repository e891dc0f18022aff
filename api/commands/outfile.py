"""``--out FILE``: .npz (the run's own codec), .nc (netCDF with units and provenance) or
.csv (tidy, ``name [unit]`` headers), chosen by the suffix (dosing.present.export)."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path
from typing import Any

SUFFIXES = (".npz", ".nc", ".csv")
OUT_HELP = ("save to this file: .npz, .nc (netCDF: units, long names, the code version and "
            "the request in its attributes) or .csv (tidy, 'name [unit]' headers: the series "
            "at the output times; the profiles long form in FILE.profiles.csv)")


# units of options whose names do not carry theirs (dosing.provenance.unit_of reads the rest)
ARG_UNITS = {"viscosity": "Pa s", "k0_m2": "m^2", "until": "tau", "every": "tau",
             "rests": "tau", "dt": "tau", "interfacial_length": "dry radii"}


def request_of(args: argparse.Namespace) -> dict[str, Any]:
    """The command's arguments as resolved (every option, defaults filled) with the unit of
    each physical one in ``units``: the request an export's attributes and a JSON answer
    carry (what made the result)."""
    from dosing.provenance import resolved

    plain = (str, int, float, bool, type(None), list, tuple, dict)
    out = {k: (v if isinstance(v, plain) else str(v)) for k, v in vars(args).items()
           if k not in ("func",) and not callable(v)}
    out["command"] = getattr(args, "command", None)
    res = resolved(out)
    res["units"].update({k: u for k, u in ARG_UNITS.items() if out.get(k) is not None})
    return res


class Saved(str):
    """The file written (a ``str`` of its path), the further tables' files beside it
    (a CSV export's profiles and steps) and notes on what a CSV left out."""

    files: list[Path]
    notes: list[str]

    def __new__(cls, path: Path, files: list[Path] | None = None,
                notes: list[str] | None = None) -> Saved:
        self = super().__new__(cls, str(path))
        self.files = list(files or [path])
        self.notes = list(notes or [])
        return self

    def report(self) -> list[str]:
        """The lines a command prints: every file written, then the notes."""
        return [f"wrote {f}" for f in self.files] + [f"note: {n}" for n in self.notes]


def save(path: str, save_npz: Callable[[str], Path], dataset: Callable[[], Any]) -> Saved:
    """Write ``path`` by its suffix: ``save_npz`` for .npz (and no suffix), else the
    Dataset ``dataset()`` through :mod:`dosing.present.export` (.csv: the series at ``path``, the
    profiles long form beside it, bounded; a table too large is refused naming .nc)."""
    suffix = Path(path).suffix
    if suffix == ".csv":
        from dosing.present import export
        from solver.errors import ParameterError

        try:
            files, notes = export.write_csv(dataset(), path)
        except ImportError as exc:  # xarray / pandas: the extra data
            raise ParameterError("--out", path, ".npz, or .csv / .nc with the extra data "
                                 "(xarray, pandas)", str(exc)) from None
        except export.CsvTooLarge as exc:
            raise ParameterError("--out", path, "a .nc file (or fewer outputs) for a run this "
                                 "size", str(exc)) from None
        return Saved(files[0], files, notes)
    if suffix in (".nc", ".xlsx"):
        from dosing.present import export
        from solver.errors import ParameterError

        try:
            return Saved(export.save(dataset(), path))
        except ImportError as exc:  # xarray / pandas (the extra data), openpyxl for .xlsx
            raise ParameterError("--out", path, ".npz, or .nc / .csv with the extra data "
                                 "(xarray, pandas); .xlsx also needs openpyxl",
                                 str(exc)) from None
    return Saved(save_npz(path))


FORMATS = ("png", "svg", "pdf")


def add_format_option(p: argparse.ArgumentParser) -> None:
    """``--format svg|png|pdf`` for a command that draws (default: the file's suffix)."""
    p.add_argument("--format", choices=FORMATS, default=None,
                   help="figure format: svg, png or pdf (default: the file's suffix, else png)")


def figure_path(path: str, fmt: str | None) -> str:
    """``path`` with the suffix of ``fmt`` (unchanged when ``fmt`` is None)."""
    return path if fmt is None else str(Path(path).with_suffix("." + fmt))
