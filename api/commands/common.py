"""Options shared by sub-commands: choosing a gel, printing JSON."""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any

from solver.gel import Gel, Permeability


def add_gel_options(p: argparse.ArgumentParser) -> None:
    """--gel PRESET or a custom gel (--omega --a0 --b0 --a1 --b1); --beta: k = phi/(1-phi)^beta."""
    g = p.add_argument_group("gel")
    g.add_argument("--gel", default="ANB", help="preset gel (ANB or HHT) or a stored fitted "
                   "gel's name (thermogel fit ... --save NAME); default ANB")
    for name in ("omega", "a0", "b0", "a1", "b1"):
        g.add_argument(f"--{name}", type=float, default=None,
                       help=f"custom gel parameter {name} (overrides the preset)")
    g.add_argument("--beta", type=float, default=None,
                   help="power-law permeability k = phi/(1-phi)^beta (default: constant k = 1)")


def gel_from_args(args: argparse.Namespace) -> Gel:
    """The gel the options describe: the preset, with any custom parameter replacing its own."""
    from dosing.gel_store import lookup

    base = lookup(args.gel)
    fields = {n: getattr(args, n) for n in ("omega", "a0", "b0", "a1", "b1")}
    custom = {k: v for k, v in fields.items() if v is not None}
    perm = Permeability("power", args.beta) if args.beta is not None else base.permeability
    if not custom and args.beta is None:
        return base
    d = {n: getattr(base, n) for n in ("omega", "a0", "b0", "a1", "b1")}
    d.update(custom)
    return Gel(**d, permeability=perm, name="custom" if custom else base.name)


def _clean(obj: Any) -> Any:
    """Replace non-finite floats by None so the output is strict JSON."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if hasattr(obj, "tolist"):
        return _clean(obj.tolist())
    return obj


def print_json(obj: Any) -> None:
    """Print one strict JSON object on stdout."""
    json.dump(_clean(obj), sys.stdout, indent=None)
    sys.stdout.write("\n")
