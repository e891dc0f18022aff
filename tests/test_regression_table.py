"""The planner's answers against the regression table made at commit 70c49c7, before the
dosing/ refactor "one request, one answer" (tests/data/regression_70c49c7.json, made by
``python -m benchmarks.regression_table --out tests/data/regression_70c49c7.json``).

Every entry is rebuilt from its recipe (``request.args``: the keyword arguments of its
request) through the public API, one helper per kind of combination below (after a
refactor, switch a kind to the new API in its helper alone), on its own temporary cache.
Front-model and reduced-model entries ("exact") reproduce to rel 1e-9 (abs 1e-12 for
zeros), strings equal; the validated entries ("full", slow) reproduce the full solver's
outputs named in their ``tolerance`` within it (the truth's numerical part).  An output's
key is its attribute path on the answer (``batch.time``, ``hold[1].end``).

The table was made with the paper's timescale constants, the default until issue 36 made
Omega_p = Omega Omega_f the default: every recipe runs with ``PhysicalConstants.paper()``
(tau moves a ramp's rate in K/tau and a drug's D0 / D_gel, so the default would not be the
table's dimensionless problem).
"""

from __future__ import annotations

import json
import re
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pytest

import dosing
from dosing import DoseRequest, Planner, ScheduleRequest, plan_dose, plan_schedule
from dosing.payload.release import DrugDoseRequest, plan_drug_dose
from dosing.units import PhysicalConstants

TABLE = json.loads((Path(__file__).parent / "data" / "regression_70c49c7.json").read_text())
REL, ABS = TABLE["tolerance"]["exact"]["rel"], TABLE["tolerance"]["exact"]["abs"]


class WithParts:
    """An answer with other answers beside it (``batch``): the fields of the main answer
    are read through."""

    def __init__(self, answer: Any, **parts: Any) -> None:
        self._answer = answer
        self.__dict__.update(parts)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._answer, name)


# ----------------------------------------------------------------------------- recipes
def fluid_jump_dose(args: dict[str, Any], cache: str) -> Any:
    """A fluid dose of one bead after a jump (the front model)."""
    return plan_dose(DoseRequest(**args), cache_path=cache)


def fluid_batch_dose(args: dict[str, Any], cache: str) -> Any:
    """A batch after a jump: its mean bead's answer, and the batch's own as ``batch``."""
    res = plan_dose(DoseRequest(**args), cache_path=cache)  # the batch's headline since 35
    return WithParts(res.answer, batch=res.batch)


def fluid_protocol_dose(args: dict[str, Any], cache: str) -> Any:
    """A fluid dose of one bead under a heating protocol (the reduced slow-heating model)."""
    return plan_dose(DoseRequest(**args), cache_path=cache)


def fluid_batch_protocol_dose(args: dict[str, Any], cache: str) -> Any:
    """A batch under a protocol: its mean bead's answer, and the batch's own as ``batch``."""
    res = plan_dose(DoseRequest(**args), cache_path=cache)  # the batch's headline since 35
    return WithParts(res.answer, batch=res.batch)


def drug_jump_dose(args: dict[str, Any], cache: str) -> Any:
    """A drug dose of one bead after a jump (the reduced drug model, or D0 = 0's fluid
    answer)."""
    with Planner(cache_path=cache, executor=ThreadPoolExecutor(1)) as planner:
        ans = plan_drug_dose(planner, DrugDoseRequest(**args))
        planner.jobs.executor.shutdown(wait=True)
    return ans


def fluid_jump_schedule(args: dict[str, Any], cache: str) -> Any:
    """A schedule's hold reading (no protocol check, no correction)."""
    return plan_schedule(ScheduleRequest(**args), cache_path=cache)


def fluid_validated_dose(args: dict[str, Any], cache: str) -> Any:
    """A fluid dose validated by the full solver (blocking)."""
    return plan_dose(DoseRequest(**args), validate=True, cache_path=cache)


RECIPES = {
    "fluid/one/jump/dose": fluid_jump_dose,
    "fluid/batch/jump/dose": fluid_batch_dose,
    "fluid/one/protocol/dose": fluid_protocol_dose,
    "fluid/batch/protocol/dose": fluid_batch_protocol_dose,
    "drug/one/jump/dose": drug_jump_dose,
    "fluid/one/jump/schedule": fluid_jump_schedule,
    "fluid/one/jump/dose/validated": fluid_validated_dose,
}


# ----------------------------------------------------------------------------- checks
def read(answer: Any, path: str) -> Any:
    """The output at an attribute path ('batch.time', 'hold[1].end'); None through a None."""
    obj = answer
    for part in path.split("."):
        name, index = re.fullmatch(r"([^\[]+)(?:\[(\d+)\])?", part).groups()
        if obj is None:
            return None
        obj = obj[name] if isinstance(obj, dict) else getattr(obj, name)
        if index is not None:
            obj = obj[int(index)]
    return obj


def check(key: str, got: Any, want: Any, tolerance: dict[str, float] | None) -> str | None:
    """None when ``got`` matches ``want``, else why not."""
    if want is None or isinstance(want, str):
        return None if got == want else f"{key}: {got!r} != {want!r}"
    if got is None:
        return f"{key}: None != {want!r}"
    tol = tolerance or {"rel": REL, "abs": ABS}
    ok = float(got) == pytest.approx(want, rel=tol.get("rel", 0.0), abs=tol.get("abs", 0.0))
    return None if ok else f"{key}: {float(got)!r} != {want!r} (tolerance {tol})"


# Answers a later physics correction moved on purpose, with the issue that moved them and
# their new values (every other output of the entry is still the table's)
OGSTON = ("issue 36: Ogston's partition taken per pore volume (it counted the polymer's "
          "excluded volume twice): this drug's partition rises, its 90 % dose comes earlier")
CORRECTED: dict[str, tuple[str, dict[str, float]]] = {
    "drug/one/jump/dose:ANB:302->308:f=0.9:dry=50:diffusivity_cm2_s=1e-08,hindrance=ogston,"
    "solute_radius_nm=1.0,fiber_radius_nm=1.0": (OGSTON, {
        "time": 1.6631825926470132, "seconds": 3666.7154468343597}),
    "drug/one/jump/dose:HHT:304->308:f=0.9:dry=50:diffusivity_cm2_s=1e-08,hindrance=ogston,"
    "solute_radius_nm=1.0,fiber_radius_nm=1.0": (OGSTON, {
        "time": 1.6022017232609669, "seconds": 3532.2747085006704}),
}


def _params() -> list[Any]:
    return [pytest.param(e, id=e["id"],
                         marks=[pytest.mark.slow] if e["check"] == "full" else [])
            for e in TABLE["entries"]]


@pytest.mark.parametrize("entry", _params())
def test_answer_reproduces_the_table(entry: dict[str, Any], tmp_path: Path) -> None:
    recipe = entry["request"]
    args = {**recipe["args"], "constants": PhysicalConstants.from_dict(
        {**(recipe["args"].get("constants") or {}), "paper": True})}
    answer = RECIPES[entry["kind"]](args, str(tmp_path / "cache.sqlite"))
    tolerance = entry.get("tolerance", {}) if entry["check"] == "full" else {}
    outputs = {**entry["outputs"], **CORRECTED.get(entry["id"], ("", {}))[1]}
    bad = [why for key, want in outputs.items()
           if (why := check(key, read(answer, key), want, tolerance.get(key))) is not None]
    assert not bad, bad


def test_every_correction_names_a_moved_entry() -> None:
    ids = {e["id"]: e for e in TABLE["entries"]}
    for key, (why, new) in CORRECTED.items():
        assert key in ids and why.startswith("issue ")
        assert all(ids[key]["outputs"][k] != v for k, v in new.items())


def test_the_table_covers_every_kind() -> None:
    kinds = {e["kind"] for e in TABLE["entries"]}
    assert kinds == set(RECIPES), kinds ^ set(RECIPES)
    assert TABLE["commit"] == "70c49c7" and "regression_table" in TABLE["command"]
    ids = [e["id"] for e in TABLE["entries"]]
    assert len(ids) == len(set(ids))
    assert all(e["check"] in ("exact", "full") for e in TABLE["entries"])
    assert all(e["tolerance"] for e in TABLE["entries"] if e["check"] == "full")
    assert {"DoseRequest", "ScheduleRequest", "Planner", "plan_dose",
            "plan_schedule"} <= set(dosing.__all__)
