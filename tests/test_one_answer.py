"""One question, one answer: the same dose, schedule, drug dose and sweep point asked through
Python, the CLI and HTTP give identical numbers (the defaults are written once).

Front-model questions only (no full-solver run): the ways in must agree to the last bit.  The
page is checked against the HTTP answer in tests/test_page_browser.py.
"""

from __future__ import annotations

import json
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
from api_support import asgi

from api.cli import main
from api.http import create_app
from dosing import DoseRequest, Planner, ScheduleRequest
from dosing.payload.drug import DrugModel
from dosing.payload.release import DrugDoseRequest, plan_drug_dose
from dosing.studies.sweep import SweepGrid, run_sweep

pytestmark = pytest.mark.anyio

JUMP = {"gel": "ANB", "t_start": 302.0, "t_end": 308.0, "dry_radius_um": 50.0}
CLI_JUMP = ["--gel", "ANB", "--t-start", "302", "--t-end", "308", "--dry-radius-um", "50"]
SAME = ("model", "time", "seconds", "interfacial_length", "error_estimate", "truth")



@pytest.fixture
def planner(tmp_path: Path):
    with Planner(cache_path=str(tmp_path / "c.sqlite"), executor=ThreadPoolExecutor(1)) as p:
        yield p


def cli_json(capsys, *argv: str) -> dict:
    capsys.readouterr()
    assert main(list(argv)) == 0
    return json.loads(capsys.readouterr().out)


async def test_a_dose(planner, tmp_path, capsys) -> None:
    py = planner.dose(DoseRequest(**JUMP, dose_fraction=0.8)).to_dict()
    cli = cli_json(capsys, "dose", *CLI_JUMP, "--fraction", "0.8", "--json",
                   "--cache", str(tmp_path / "c.sqlite"))
    async with asgi(create_app(planner=planner, warm=False)) as (_, raw):
        http = (await raw.post("/v1/dose-time", json={**JUMP, "dose_fraction": 0.8})).json()
    assert py["model"] == "front-sharp" and py["interfacial_length"] == pytest.approx(8e-5)
    for key in SAME:
        assert py[key] == cli[key] == http[key], key


async def test_a_schedules_hold_reading(planner, tmp_path, capsys) -> None:
    req = ScheduleRequest(**JUMP, doses=(0.3, 0.3, 0.3), rests=(0.5, 0.5),
                          check_protocol=False, correct=False)
    py = [row["actuation_time"] for row in planner.schedule(req).to_dict()["hold"]]
    cli = cli_json(capsys, "schedule", *CLI_JUMP, "--doses", "0.3", "0.3", "0.3", "--rests",
                   "0.5", "0.5", "--no-check", "--no-correct", "--json",
                   "--cache", str(tmp_path / "c.sqlite"))
    body = {**JUMP, "doses": [0.3, 0.3, 0.3], "rests": [0.5, 0.5], "check_protocol": False,
            "correct": False}
    async with asgi(create_app(planner=planner, warm=False)) as (_, raw):
        http = (await raw.post("/v1/schedule", json=body)).json()
        checked = await raw.post("/v1/schedule", json={k: v for k, v in body.items()
                                                       if k not in ("check_protocol", "correct")})
    assert py == [row["actuation_time"] for row in cli["hold"]] == \
        [row["actuation_time"] for row in http["hold"]]
    # the default everywhere is the checked and corrected schedule (a job over HTTP)
    assert ScheduleRequest(**JUMP, doses=(0.3,)).check_protocol is True
    assert checked.status_code == 202


async def test_a_drug_dose_without_diffusion(planner, tmp_path, capsys) -> None:
    py = plan_drug_dose(planner, DrugDoseRequest("ANB", 302.0, 308.0, DrugModel(load_ug=1.0),
                                                 drug_mass_ug=0.3, dry_radius_um=50.0))
    cli = cli_json(capsys, "dose", *CLI_JUMP, "--drug-mass-ug", "0.3", "--load-ug", "1.0",
                   "--json", "--cache", str(tmp_path / "c.sqlite"))
    async with asgi(create_app(planner=planner, warm=False)) as (_, raw):
        r = await raw.post("/v1/dose-time", json={**JUMP, "drug_mass_ug": 0.3,
                                                  "drug": {"load_ug": 1.0}})
    http = r.json()
    assert r.status_code == 200, http
    assert py.time == cli["time"] == http["time"]
    assert py.seconds == cli["seconds"] == http["seconds"]


def test_a_sweep_point(planner, tmp_path, capsys) -> None:
    """A design map's point is the dose answer of that point, to the last bit, whether the
    sweep runs in Python or the CLI (the HTTP sweep job's table is run_sweep's: tested in
    tests/test_api_sweep_page.py)."""
    dose = planner.dose(DoseRequest(**JUMP, dose_fraction=0.3))
    py = run_sweep(SweepGrid(t_ends=[308.0], dry_radii_um=[50.0], doses=[0.3])).rows[0]
    out = tmp_path / "sweep.json"
    assert main(["sweep", "--gel", "ANB", "--t-start", "302", "--t-end", "308",
                 "--dry-radius-um", "50", "--dose", "0.3", "--json", str(out),
                 "--no-progress", "--cache", str(tmp_path / "c.sqlite")]) == 0
    cli = json.loads(out.read_text())["rows"][0]
    assert py["time"] == cli["time"] == dose.time
    assert py["seconds"] == cli["seconds"] == dose.seconds
