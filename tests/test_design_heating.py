"""thermogel design heating (issue 39): the heating at which a dose is out at an asked time."""

from __future__ import annotations

import json
from concurrent.futures import ThreadPoolExecutor

import pytest

from api.cli import main
from dosing import PhysicalConstants, Planner
from dosing.design import HeatingTarget, design_heating
from solver.errors import ParameterError


@pytest.fixture(scope="module")
def planner(tmp_path_factory):
    path = tmp_path_factory.mktemp("design") / "c.sqlite"
    p = Planner(cache_path=str(path), executor=ThreadPoolExecutor(1))
    p.path = str(path)
    yield p
    p.close()
    p.jobs.executor.shutdown(wait=True)

PAPER = PhysicalConstants.paper()  # these targets were set for tau = 2205 s (50 um ANB)
BEAD = {"dry_radius_um": 50.0, "constants": PAPER}


def test_the_jump_that_delivers_half_at_60_s_is_validated(planner, capsys) -> None:
    """ANB from 302 K, 50 um dry, the paper's constants: 50 % at 60 s.  The jump found on the
    front model (brentq) is validated by the full solver within 3 % (one validation, ~8 s);
    the CLI's JSON gives the same T_end, the envelope there and the range keeping 60 s
    inside it."""
    out = design_heating(HeatingTarget("ANB", 302.0, 60.0, fraction=0.5, **BEAD,
                                       validate=True), planner)
    assert 307.0 < out.value < 308.0
    assert abs(out.seconds / 60.0 - 1.0) < 1e-4
    assert abs(out.validated_seconds / 60.0 - 1.0) <= 0.03
    d = out.to_dict()
    lo, hi = d["envelope_seconds"]
    assert lo < 60.0 < hi and d["dominant_uncertainty"]["name"] == "timescale"
    r = d["inside_envelope"]
    assert r["low"] <= out.value <= r["high"]
    assert main(["design", "heating", "--gel", "ANB", "--t-start", "302", "--fraction", "0.5",
                 "--at", "60 s", "--dry-radius-um", "50", "--paper-constants", "--validate",
                 "--cache", planner.path, "--json"]) == 0
    cli = json.loads(capsys.readouterr().out)
    assert cli["t_end_K"] == pytest.approx(out.value, abs=1e-3)
    assert abs(cli["validated_seconds"] / 60.0 - 1.0) <= 0.03


def test_confidence_heats_harder_than_the_point(planner) -> None:
    """With P = 0.9 the jump is colder than the point answer's only if the parts lean
    faster: the paper's constants are the slowest reading, so every timescale candidate is
    faster and a 90 % heating is colder (a longer point time)."""
    out = design_heating(HeatingTarget("ANB", 302.0, 60.0, fraction=0.5, **BEAD,
                                       confidence=0.9, full=False), planner)
    c = out.confidence
    assert c["value"] is not None and c["value"] < out.value and c["seconds"] > 60.0
    assert "log-uniform" in c["reading"]


def test_unreachable_targets_are_refused_naming_the_field(planner, capsys) -> None:
    """Too fast for any jump in the range: 'at', with the nearest reachable time; a dose no
    jump delivers: 'fraction'; a ramp without its T_end: 't_end'."""
    with pytest.raises(ParameterError) as e:
        design_heating(HeatingTarget("ANB", 302.0, 1.0, fraction=0.5, **BEAD,
                                     full=False), planner)
    assert e.value.field == "at" and "nearest reachable time" in str(e.value)
    assert "at least" in str(e.value)
    with pytest.raises(ParameterError) as e:
        design_heating(HeatingTarget("ANB", 302.0, 60.0, fraction=0.99, **BEAD,
                                     full=False), planner)
    assert e.value.field == "fraction"
    with pytest.raises(ParameterError) as e:
        HeatingTarget("ANB", 302.0, 60.0, fraction=0.5, **BEAD, mode="ramp")
    assert e.value.field == "t_end"
    assert main(["design", "heating", "--t-start", "302", "--fraction", "0.5", "--at", "1 s",
                 "--dry-radius-um", "50", "--paper-constants", "--no-full", "--cache",
                 planner.path]) == 2
    assert "at=1" in capsys.readouterr().err


def test_a_ramp_rate_and_a_bath_set_point(planner) -> None:
    """The ramp's rate and the bath's set point found on the reduced slow-heating model
    (milliseconds per probe), in the step grammar."""
    ramp = design_heating(HeatingTarget("ANB", 302.0, 300.0, fraction=0.8, **BEAD,
                                        mode="ramp", t_end=308.0, full=False), planner)
    assert abs(ramp.seconds / 300.0 - 1.0) < 1e-3
    assert ramp.heating.startswith("Heat to 308 K at ") and 0.5 < ramp.value < 20.0
    bath = design_heating(HeatingTarget("ANB", 302.0, 300.0, fraction=0.8, **BEAD,
                                        mode="bath", full=False), planner)
    assert abs(bath.seconds / 300.0 - 1.0) < 1e-3
    assert bath.heating.startswith("Bath at ") and 304.0 < bath.value < 312.0
