"""Options shared by sub-commands: choosing a gel, printing JSON."""

from __future__ import annotations

import argparse
import json
import sys
import textwrap
from typing import Any

from solver.errors import ParameterError
from solver.gel import Gel
from solver.json_safe import json_safe


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
    """The gel the options describe: a preset or stored gel, with any custom parameter
    replacing its own (bounded as the HTTP service bounds them; one rule for HTTP, CLI and
    Python: ``dosing.request.gel_with``)."""
    from dosing.request import gel_with

    spec = gel_bounds(args)
    if spec:
        from api.schemas import GelParameters

        check_bounds(GelParameters, spec)
    custom = {n: getattr(args, n) for n in ("omega", "a0", "b0", "a1", "b1")}
    return gel_with(args.gel, custom, "power" if args.beta is not None else None, args.beta)


def add_at_start_options(p: argparse.ArgumentParser, name: str, what: str,
                         many: bool = False, drug_only: bool = False) -> None:
    """A time at T_start (a schedule's rests, a drug's wait): ``--NAME`` in tau or
    ``--NAME-seconds``, one of them; its range is solver.limits' (REST_RANGE; a drug run's
    step at most DRUG_STEP_MAX), checked by the one parser dosing.request.at_start."""
    from solver.limits import DRUG_STEP_MAX, REST_RANGE

    top = (f"{DRUG_STEP_MAX:g}" if drug_only
           else f"{REST_RANGE[1]:g}, with a drug {DRUG_STEP_MAX:g}")
    g = p.add_mutually_exclusive_group()
    more = {"nargs": "*"} if many else {}
    g.add_argument(f"--{name}", type=float, default=None, **more,
                   help=f"{what}, dimensionless (units of tau, {REST_RANGE[0]:g}-{top})")
    g.add_argument(f"--{name}-seconds", type=float, default=None, **more,
                   help="the same in seconds (needs a bead size)")


_REQUEST: list[dict[str, Any] | None] = [None]  # the command line being answered


def set_request(request: dict[str, Any] | None) -> None:
    """The resolved request (``outfile.request_of(args)``) every JSON answer carries."""
    _REQUEST[0] = request


def print_json(obj: Any) -> None:
    """Print one strict JSON object on stdout, with ``request`` (the command's options as
    resolved, with units) and ``version`` (dosing.provenance)."""
    if isinstance(obj, dict):
        from dosing.provenance import stamp

        obj = stamp(dict(obj), _REQUEST[0])
    json.dump(json_safe(obj), sys.stdout, indent=None)
    sys.stdout.write("\n")


# ----------------------------------------------------------------------------- bounds

# CLI flag of each request field whose name differs ("--" + the name with dashes otherwise)
FLAGS = {"dose_fraction": "--fraction", "dose_volume_ul": "--volume-ul",
         "viscosity_pa_s": "--viscosity", "permeability_m2": "--k0-m2"}


def _flag(loc: tuple[Any, ...]) -> str:
    names = [p for p in loc if isinstance(p, str) and p not in ("body", "custom", "preset")]
    name = names[-1] if names else "input"
    return FLAGS.get(name, "--" + name.replace("_", "-"))


def check_bounds(model: Any, values: dict[str, Any], partial: bool = False) -> None:
    """Validate CLI values with the HTTP request model (:mod:`api.schemas`: one definition
    of every bound); the first violation is a ParameterError naming the CLI flag.
    ``partial``: check only the values given (a required field the CLI fills another way,
    e.g. ``--doses-ug`` for ``doses``, is not an error here)."""
    from pydantic import ValidationError

    try:
        model.model_validate({k: v for k, v in values.items() if v is not None})
    except ValidationError as exc:
        errors = [e for e in exc.errors() if not (partial and e.get("type") == "missing")]
        if not errors:
            return
        err = errors[0]
        msg = str(err.get("msg", "invalid"))
        value = err.get("input")
        if isinstance(value, (list, tuple)) and len(value) > 8:
            value = f"{len(value)} values"
        loc = tuple(err.get("loc", ()))
        field = ".".join(str(p) for p in loc if p not in ("custom", "preset"))
        raise ParameterError(_flag(loc), value, msg[0].lower() + msg[1:],
                             f"the HTTP service's bound on {field}") from None


def gel_bounds(args: argparse.Namespace) -> dict[str, Any] | None:
    """The custom gel options as the HTTP gel object (None: no custom parameter)."""
    spec = {n: getattr(args, n) for n in ("omega", "a0", "b0", "a1", "b1")}
    spec = {k: v for k, v in spec.items() if v is not None}
    if args.beta is not None:
        spec.update(permeability="power", beta=args.beta)
    return spec or None


def checked_cache(path: str | None) -> str | None:
    """``path`` if the validation cache can be opened there (a ParameterError naming
    ``--cache`` otherwise: a directory, a read-only file, not a database)."""
    from dosing.runs.cache import ValidationCache, default_path

    try:
        ValidationCache(path).close()
    except ParameterError as exc:
        raise ParameterError("--cache", path or str(default_path()), exc.valid,
                             getattr(exc, "reason", "")) from None
    return path


def wrap(text: str) -> str:
    """A paragraph of the CLI's output, indented by two spaces, 96 columns."""
    return textwrap.fill(text, width=96, initial_indent="  ", subsequent_indent="  ")


def print_uncertainty(u: Any, what: str = "the truth") -> None:
    """The three parts of an answer's uncertainty (dosing.truth.Uncertainty, or a mapping
    of its parts, dosing.truth.Part, by name), in words."""
    if u is None:
        return
    print(f"  uncertainty of {what}, in three parts:")
    for name in ("numerical", "interfacial_length_range", "model_form"):
        part = u[name] if isinstance(u, dict) else getattr(u, name)
        print(wrap(f"- {part.text}"))


def table_row(label: str, values: list[float], fmt: str = "{:.4g}") -> str:
    """One labelled row of numbers, as the schedule commands print them."""
    return f"  {label:<34}" + "  ".join(fmt.format(v) for v in values)
