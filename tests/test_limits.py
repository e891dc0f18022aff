"""Each range is defined once (solver.limits): no other module writes its numbers again."""

import tokenize
from pathlib import Path

import solver.limits as limits
from api import schemas
from dosing.runs import scenario
from solver import gel
from solver.full import options

ROOT = Path(__file__).resolve().parents[1]


def test_every_layer_uses_the_one_definition() -> None:
    assert gel.T_MIN == schemas.T_MIN == limits.T_MIN and gel.T_MAX == schemas.T_MAX == limits.T_MAX
    assert options.N_RANGE == limits.SOLVER_N_RANGE and options.ELL_MAX == limits.SOLVER_ELL_MAX
    assert scenario.N_RANGE == limits.TRUTH_N_RANGE
    assert scenario.DIRECT_ELL_RANGE == schemas.DIRECT_ELL_RANGE == limits.TRUTH_DIRECT_ELL_RANGE
    assert scenario.ELL_RANGE == limits.TRUTH_LADDER_ELL_RANGE
    assert schemas.ELL_RANGE == limits.TRUTH_LADDER_START_RANGE
    assert scenario.LADDER_TOP == limits.TRUTH_LADDER_START_RANGE[1]
    from dosing.heating import grammar
    from solver import heating as program

    assert program.DURATION_MAX == grammar.TAU_MAX == limits.PROGRAM_STEP_MAX
    assert program.RATE_MAX == limits.PROGRAM_RATE_MAX
    assert program.UNTIL_LIMIT == limits.UNTIL_LIMIT
    assert program.TRACE_ROWS_MAX == limits.TRACE_ROWS_MAX


def test_no_range_is_written_twice() -> None:
    """The bounds of solver.limits appear as numbers in no other module of the three
    packages (prose, docstrings and comments may quote them)."""
    bounds = {limits.T_MIN, limits.T_MAX, float(limits.TRUTH_N_RANGE[1]),
              limits.TRUTH_LADDER_ELL_RANGE[0]}
    offenders = []
    for pkg in ("solver", "dosing", "api", "thermogel"):
        for path in (ROOT / pkg).rglob("*.py"):
            if path.name == "limits.py":
                continue
            with path.open("rb") as fh:
                for tok in tokenize.tokenize(fh.readline):
                    if tok.type == tokenize.NUMBER and float(tok.string.replace("_", "")
                                                             .rstrip("jJ") or 0) in bounds:
                        offenders.append(f"{path.relative_to(ROOT)}:{tok.start[0]}: {tok.line}")
    assert not offenders, "".join(offenders)


def test_a_time_at_start_has_one_rule() -> None:
    """A schedule's rests and a drug's wait are times at T_start: one range (REST_RANGE; a
    drug run's step at most DRUG_STEP_MAX), one parser (dosing.request.at_start), and the
    HTTP fields say the same."""
    import pytest

    from dosing.payload.release import MAX_HORIZON, DrugCase
    from dosing.request import ScheduleCase, at_start
    from dosing.units import PhysicalConstants
    from solver.errors import ParameterError

    assert ScheduleCase.rest_max == limits.REST_RANGE[1]
    assert DrugCase.rest_max == MAX_HORIZON == limits.DRUG_STEP_MAX
    rest = schemas.ScheduleRequest.model_json_schema()["properties"]["rests"]["anyOf"][0]
    assert (rest["items"]["minimum"], rest["items"]["maximum"]) == limits.REST_RANGE
    wait = schemas.DrugIn.model_json_schema()["properties"]["wait"]["anyOf"][0]
    assert (wait["minimum"], wait["maximum"]) == (limits.REST_RANGE[0], limits.DRUG_STEP_MAX)
    c = PhysicalConstants.paper()  # tau = 2205 s for 50 um at 308 K
    top = limits.REST_RANGE[1]
    assert at_start("rests", [0.0, top], None, None, 308.0, c) == (0.0, top)
    with pytest.raises(ParameterError, match="0-1000 tau") as err:
        at_start("rests", [0.5, 2 * top], None, None, 308.0, c)
    assert err.value.field == "rests[1]"
    with pytest.raises(ParameterError, match=r"0-32 tau = 0-7\.0\d+e\+04 s") as err:
        at_start("wait", None, 1e5, 50.0, 308.0, c, limits.DRUG_STEP_MAX)  # tau = 2205 s
    assert err.value.field == "wait_seconds"
