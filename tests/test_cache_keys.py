"""Stored runs survive a reorganisation of the planner (issue 35: nothing cached is lost).

A run's cache key is a digest of what defines its dimensionless answer (gel, heating,
branch, settings) and the full solver's code version (``dosing.runs.scenario.code_version``,
a digest of solver/ only).  With the code version held fixed, the keys below are the ones
the planner had before dosing/ moved into folders (commit 0ac0593): moving or folding
dosing's modules must leave them unchanged, so old cache files keep serving their runs.
A change to what a key holds is a change of the cache format and shows here.
"""

from __future__ import annotations

import pytest

from dosing.planner import request_scenarios
from dosing.question.axes import Heating
from dosing.request import DoseRequest

# computed at 0ac0593 (before the move) with code_version() -> "CODE"
JUMP_KEYS = ["05fccbc0b1c46268ec77b7c888d03439", "050dd9f809a4db8aeea594db7b611372"]
RAMP_KEY = "f1168a431fae7ba46682c93a271379ee"
# a drug run's key, with the drug code's version held fixed too (that version follows the
# solute code and the run functions' own source: dosing.runs.solute.drug_code_version; a
# cache's drug runs from before this round ran once more when it began to hash only those)
DRUG_KEY = "drug-b2632cb2d1d6874b5c288c060412724d"


@pytest.fixture
def fixed_code(monkeypatch):
    """The code version held fixed, and the planner's memoised scenarios (whose keys are
    cached on them) made afresh."""
    import dosing.planner as planner
    import dosing.runs.scenario as scenario

    monkeypatch.setattr(scenario, "code_version", lambda: "CODE")
    memos = (planner._validation_scenarios, planner._truth_scenario)
    for memo in memos:
        memo.cache_clear()
    yield
    for memo in memos:
        memo.cache_clear()


def test_a_jumps_validation_runs_keep_their_keys(fixed_code) -> None:
    req = DoseRequest(gel="ANB", t_start=302.0, t_end=308.0, dose_fraction=0.8,
                      dry_radius_um=50.0)
    assert [sc.key() for sc in request_scenarios(req)][:2] == JUMP_KEYS


def test_a_ramps_run_keeps_its_key(fixed_code) -> None:
    req = DoseRequest(gel="ANB", t_start=302.0, dose_fraction=0.8, dry_radius_um=50.0,
                      protocol=["Heat to 308 K at 5 K/min"])
    assert Heating.lattice(req, req.settings, 1.2).key() == RAMP_KEY


def test_a_drug_run_keeps_its_key(fixed_code, monkeypatch) -> None:
    import dosing.runs.solute as solute
    from solver.gel import preset
    from solver.solute import Solute

    monkeypatch.setattr(solute, "drug_code_version", lambda: "DRUG")
    sc = solute.DrugScenario(preset("ANB"), 302.0, ((0.5, 308.0),), Solute(0.1))
    assert sc.key() == DRUG_KEY


def test_the_key_check_can_fail(fixed_code) -> None:
    """Another bead size is another dimensionless ramp: another key."""
    req = DoseRequest(gel="ANB", t_start=302.0, dose_fraction=0.8, dry_radius_um=60.0,
                      protocol=["Heat to 308 K at 5 K/min"])
    assert Heating.lattice(req, req.settings, 1.2).key() != RAMP_KEY
