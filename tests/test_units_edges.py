"""Units at the edges (issue 25): every physical field of every HTTP request model takes a
string with a unit (converted by dosing.quantity) and refuses a wrong unit naming the
field; plain numbers in the documented unit still work; the CLI takes unit strings too."""

from __future__ import annotations

import inspect

import pytest
from pydantic import BaseModel, ValidationError

from api import fit_schemas, schemas, sensitivity_schemas
from api.cli import main
from dosing.quantity import UNITS, field_kind, from_edge


def _request_models() -> list[type[BaseModel]]:
    out = []
    for mod in (schemas, fit_schemas, sensitivity_schemas):
        for _, cls in inspect.getmembers(mod, inspect.isclass):
            if (issubclass(cls, BaseModel) and cls.model_config.get("strict")
                    and cls.model_config.get("extra") == "forbid"):
                out.append(cls)
    return sorted(set(out), key=lambda c: c.__name__)


PHYSICAL = [(cls, name) for cls in _request_models() for name in cls.model_fields
            if field_kind(name) is not None]


def test_the_request_models_have_physical_fields() -> None:
    names = {n for _, n in PHYSICAL}
    assert {"t_start", "t_end", "dry_radius_um", "viscosity_pa_s", "permeability_m2"} <= names


@pytest.mark.parametrize(("model", "name"), PHYSICAL,
                         ids=[f"{c.__name__}.{n}" for c, n in PHYSICAL])
def test_every_physical_field_takes_a_unit_and_refuses_a_wrong_one(model, name) -> None:
    many = "list" in str(model.model_fields[name].annotation)

    def value(text: str):
        return [text] if many else text

    with pytest.raises(ValidationError) as e:  # a dimension no field has
        model.model_validate({name: value("3 kg*m/s^3/A")})
    errs = [x for x in e.value.errors() if x["loc"][:1] == (name,)]
    assert errs and "dimension" in errs[0]["msg"] and name in errs[0]["msg"], e.value
    unit = UNITS[field_kind(name)]
    try:  # the documented unit spelled out is converted (other fields may be missing)
        model.model_validate({name: value(f"1 {unit}")})
    except ValidationError as exc:
        mine = [x for x in exc.errors() if x["loc"][:1] == (name,)]
        assert all(x["type"] not in ("float_type", "string_type", "list_type",
                                     "value_error") for x in mine), mine


def test_dose_request_with_units_equals_the_plain_numbers() -> None:
    plain = schemas.DoseTimeRequest.model_validate(
        {"t_start": 302.15, "t_end": 308.0, "dose_fraction": 0.8, "dry_radius_um": 50.0})
    units = schemas.DoseTimeRequest.model_validate(
        {"t_start": "29 degC", "t_end": "308 K", "dose_fraction": 0.8,
         "dry_radius_um": "0.05 mm"})
    assert units.t_start == pytest.approx(plain.t_start, abs=1e-9)
    assert units.dry_radius_um == pytest.approx(50.0, rel=1e-12)
    with pytest.raises(ValidationError) as e:
        schemas.DoseTimeRequest.model_validate({"t_start": 302.0, "t_end": 308.0,
                                                "dose_fraction": 0.8, "dry_radius_um": "50 K"})
    assert e.value.errors()[0]["loc"] == ("dry_radius_um",)
    with pytest.raises(ValidationError):  # a bare number in a string is still refused
        schemas.DoseTimeRequest.model_validate({"t_start": "302", "t_end": 308.0,
                                                "dose_fraction": 0.8})


def test_from_edge_keeps_what_is_not_a_quantity() -> None:
    assert from_edge("viscosity_pa_s", "water") == "water"
    assert from_edge("dose_fraction", "0.5 um") == "0.5 um"  # not a physical field
    assert from_edge("rests_seconds", ["10 min", 5.0]) == [600.0, 5.0]


def test_cli_takes_unit_strings_and_refuses_a_wrong_unit(capsys) -> None:
    args = ["dose", "--gel", "ANB", "--t-start", "29 degC", "--t-end", "35 degC",
            "--fraction", "0.8", "--dry-radius-um", "50 um", "--json"]
    assert main(args) == 0
    import json

    out = json.loads(capsys.readouterr().out)
    assert out["bead_dry_radius_um"] == pytest.approx(50.0)
    bad = ["dose", "--t-start", "302", "--t-end", "308", "--fraction", "0.8",
           "--dry-radius-um", "50 K"]
    with pytest.raises(SystemExit) as e:
        main(bad)
    assert e.value.code == 2 and "--dry-radius-um" in capsys.readouterr().err


def test_python_requests_take_strings_and_pint_quantities() -> None:
    from dosing import DoseRequest, ScheduleRequest
    from dosing.quantity import registry

    q = registry().Quantity
    plain = DoseRequest("ANB", 302.15, 308.0, dose_fraction=0.8, dry_radius_um=50.0)
    req = DoseRequest("ANB", "29 degC", q(308.0, "K"), dose_fraction=0.8,
                      dry_radius_um=q(0.05, "mm"))
    assert req.t_start == pytest.approx(plain.t_start, abs=1e-9)
    assert req.bead_dry_radius_um == pytest.approx(50.0, rel=1e-12)
    sch = ScheduleRequest("ANB", 302.0, 308.0, doses=[0.3, 0.3], rests_seconds=["1 min"],
                          dry_radius_um="50 um")
    ref = ScheduleRequest("ANB", 302.0, 308.0, doses=[0.3, 0.3], rests_seconds=[60.0],
                          dry_radius_um=50.0)
    assert sch.rests == pytest.approx(ref.rests, rel=1e-12)
    from solver.errors import ParameterError

    with pytest.raises(ParameterError) as e:
        DoseRequest("ANB", 302.0, 308.0, dose_fraction=0.8, dry_radius_um="50 K")
    assert e.value.field == "dry_radius_um"


def _cli_physical_actions() -> list[tuple[str, object]]:
    import argparse

    from api.cli import build_parser

    out = []

    def walk(parser: argparse.ArgumentParser, path: str) -> None:
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, child in action.choices.items():
                    walk(child, f"{path} {name}".strip())
            elif (action.option_strings and field_kind(action.dest) is not None
                  and action.nargs != 0 and callable(action.type)):
                out.append((f"{path} {action.option_strings[0]}", action))

    walk(build_parser(), "")
    return out


def test_every_float_cli_option_named_by_its_unit_takes_units() -> None:
    import argparse

    actions = _cli_physical_actions()
    names = {n for n, _ in actions}
    assert {"dose --dry-radius-um", "simulate --t-start", "release --k0-m2",
            "schedule --rests-seconds"} <= names, names
    for name, action in actions:
        if getattr(action.type, "__qualname__", "").startswith("_converter"):
            unit = UNITS[field_kind(action.dest)]
            assert action.type(f"1 {unit}") == pytest.approx(1.0), name
            assert action.type("2.5") == 2.5, name  # plain numbers as before
            with pytest.raises(argparse.ArgumentTypeError, match="dimension"):
                action.type("3 kg*m/s^3/A")
        else:  # options read as text are converted by their command (sweep axes, plot)
            assert action.type is not float, name


def test_sweep_axes_and_viscosity_take_units() -> None:
    """The CLI's sweep axes and --viscosity read quantities too; a wrong kind names the
    option."""
    from api.commands.constants_options import viscosity as _viscosity
    from api.commands.sweep import parse_axis
    from solver.errors import ParameterError

    assert parse_axis("--t-end", "34 degC:36 degC:3") == pytest.approx([307.15, 308.15, 309.15])
    assert parse_axis("--dry-radius-um", "20 um, 0.05 mm") == pytest.approx([20.0, 50.0])
    assert parse_axis("--t-end", "306:308:3") == [306.0, 307.0, 308.0]
    assert _viscosity("1 mPa s") == pytest.approx(1e-3) and _viscosity("water") == "water"
    with pytest.raises(ParameterError) as err:
        parse_axis("--dry-radius-um", "50 K, 3")
    assert err.value.field == "--dry-radius-um" and "dimension" in str(err.value)
    with pytest.raises(ParameterError):
        _viscosity("2 um")
