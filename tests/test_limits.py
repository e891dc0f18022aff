"""Each range is defined once (solver.limits): no other module writes its numbers again."""

import tokenize
from pathlib import Path

import solver.limits as limits
from api import schemas
from dosing import scenario
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
