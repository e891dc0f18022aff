"""Schedules as events (issue 37): every schedule answer, whatever its cell (fluid or drug x
one bead or a batch x a jump or a protocol) and whatever the way in (Python, CLI, HTTP),
carries ``events``: one row per step a bath controller or a lab notebook takes, built from
the corrected schedule (the hold reading only when the check is off, then marked rough) by
the one builder ``dosing.question.events.schedule_events``."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from api_support import asgi

from api.cli import main
from api.http import create_app
from dosing import PhysicalConstants
from dosing.question import Batch, Drug, Fluid, Heating, Jump, OneBead, Request, Schedule, plan
from dosing.question.cells import CELLS
from dosing.question.events import EVENT_COLUMNS, schedule_events

FAKE_CASE = {"gel": "ANB", "t_start": 302.0, "dry_radius_um": 2.0}
RAMP = ["Heat to 308 K at 5 K/min"]
CV = {"kind": "lognormal", "cv": 0.2}
CARRIED = {"diffusivity_cm2_s": 0.0}  # a drug the fluid carries: quick drug runs
SCHEDULE_CELLS = sorted(k for k in CELLS if k[3] == "schedule")


def _request(key: tuple[str, ...], **question: object) -> Request:
    payload = Drug(CARRIED) if key[0] == "drug" else Fluid()
    population = Batch(CV) if key[1] == "batch" else OneBead()
    heating = Heating(RAMP) if key[2] == "protocol" else Jump(308.0)
    q = Schedule([0.3, 0.3], rests=[0.5], **question)
    return Request(**FAKE_CASE, heating=heating, question=q, payload=payload,
                   population=population)


def _check_events(res, key: tuple[str, ...]) -> list[dict]:
    """The invariants of a corrected schedule's events."""
    ev = res.events
    assert [e["kind"] for e in ev] == ["heat", "rest", "heat"]
    assert [e["step"] for e in ev] == [1, 2, 3]
    assert set(EVENT_COLUMNS) == set(ev[0])
    tau = res.timescale_seconds
    heats = [e for e in ev if e["kind"] == "heat"]
    # the headline's corrected times are the heats' durations
    assert res.reading == "corrected"
    assert [e["duration_s"] for e in heats] == pytest.approx(res.actuation_seconds, rel=1e-12)
    assert [e["duration_tau"] for e in heats] == pytest.approx(res.actuation_times, rel=1e-12)
    assert [e["heating"] for e in ev] == [1, 0, 2]
    assert ev[1]["duration_s"] == pytest.approx(0.5 * tau, rel=1e-12)
    assert ev[1]["temperature_K"] == 302.0
    for a, b in zip(ev, ev[1:], strict=False):  # one clock, no gaps
        assert b["start_s"] == pytest.approx(a["start_s"] + a["duration_s"], rel=1e-12)
    assert ev[0]["start_s"] == 0.0
    assert all(e["reading"] == "corrected" and e["rough"] is False for e in ev)
    got = res.corrected["delivered_fractions"]
    assert [e["dose_fraction"] for e in heats] == pytest.approx(got, rel=1e-12)
    assert [e["target_fraction"] for e in heats] == [0.3, 0.3]
    assert [e["dose_error"] for e in heats] == pytest.approx(
        [g / 0.3 - 1.0 for g in got], rel=1e-9, abs=1e-12)
    assert ev[-1]["released_fraction"] == pytest.approx(
        sum(e["dose_fraction"] for e in ev), rel=1e-12)
    assert ev[-1]["released_fraction"] == pytest.approx(0.6, rel=0.02)
    if key[2] == "protocol":  # each heating: the ramp cut at its time, its end's set point
        for e in heats:
            assert e["program"].startswith("Heat to ") and e["program"].endswith("at 5 K/min")
            ramp_end = 302.0 + 5.0 / 60.0 * e["duration_s"]
            assert e["temperature_K"] == pytest.approx(min(ramp_end, 308.0), rel=1e-9)
    elif key[2] == "jump":
        assert all(e["program"] is None and e["temperature_K"] == 308.0 for e in heats)
    return ev


def _check_rough(res, key: tuple[str, ...]) -> list[dict]:
    """The invariants of a hold reading's events (the check off: rough)."""
    ev = res.events
    assert res.reading == "hold" and [e["kind"] for e in ev] == ["heat", "rest", "heat"]
    assert all(e["rough"] is True and e["reading"] == "hold" for e in ev)
    heats = [e for e in ev if e["kind"] == "heat"]
    assert [e["duration_s"] for e in heats] == pytest.approx(res.actuation_seconds, rel=1e-12)
    assert [e["dose_fraction"] for e in ev] == [0.3, 0.0, 0.3]
    assert ev[1]["duration_s"] == pytest.approx(0.5 * res.timescale_seconds, rel=1e-12)
    if key[2] == "protocol":
        for e in heats:
            assert e["program"].startswith("Heat to ") and e["program"].endswith("at 5 K/min")
            assert 302.0 < e["temperature_K"] <= 308.0
    return ev


# a drug under a protocol runs its staircase of 0.05 K stairs on the fake solver (more
# outputs than a run may keep, and minutes): its cells are read with the check off here
# (the hold reading, rough); the builder is the same (test_the_builder_takes_any_answer...)
CORRECTED_CELLS = [k for k in SCHEDULE_CELLS if not (k[0] == "drug" and k[2] == "protocol")]
ROUGH_CELLS = [k for k in SCHEDULE_CELLS if k not in CORRECTED_CELLS]


@pytest.mark.parametrize("key", CORRECTED_CELLS, ids=[" ".join(k) for k in CORRECTED_CELLS])
def test_every_schedule_cell_carries_its_events(key, fake_planner) -> None:
    """The schedule cells, on the fake solver: the events are the corrected schedule (the
    answer's own, in its JSON too), and to_dataframe leads with them."""
    res = plan(_request(key), planner=fake_planner)
    ev = _check_events(res, key)
    d = res.to_dict()
    assert d["events"] == json.loads(json.dumps(ev))
    df = res.to_dataframe()
    assert list(df["kind"]) == ["heat", "rest", "heat"]
    assert list(df.columns[:5]) == ["step [1]", "kind", "start_s [s]", "duration_s [s]",
                                    "temperature_K [K]"]


@pytest.mark.parametrize("key", ROUGH_CELLS, ids=[" ".join(k) for k in ROUGH_CELLS])
def test_a_drug_under_a_protocol_carries_its_events(key, fake_planner) -> None:
    """A drug's schedule under a protocol, one bead or a batch, with the check off: its
    events are the hold reading, each heating the ramp cut at its time, marked rough."""
    res = plan(_request(key, check_protocol=False, correct=False), planner=fake_planner)
    ev = _check_rough(res, key)
    assert res.to_dict()["events"] == json.loads(json.dumps(ev))
    assert list(res.to_dataframe()["kind"]) == ["heat", "rest", "heat"]


def test_the_hold_reading_is_rough_and_a_check_alone_is_checked(fake_planner) -> None:
    """Check off: the hold reading's times, marked rough, the doses as asked; check on and no
    correction: the same times with what the full solver says they deliver."""
    key = ("fluid", "one", "jump", "schedule")
    hold = plan(_request(key, check_protocol=False, correct=False), planner=fake_planner)
    ev = hold.events
    assert all(e["rough"] and e["reading"] == "hold" for e in ev)
    assert [e["duration_tau"] for e in ev if e["kind"] == "heat"] == \
        [r.actuation_time for r in hold.hold]
    assert [e["dose_fraction"] for e in ev] == [0.3, 0.0, 0.3]
    assert ev[-1]["released_fraction"] == pytest.approx(0.6)
    assert ev[0]["dose_error"] is None
    checked = plan(_request(key, correct=False), planner=fake_planner)
    ev = checked.events
    assert all(not e["rough"] and e["reading"] == "checked" for e in ev)
    assert [e["duration_tau"] for e in ev if e["kind"] == "heat"] == \
        [r.actuation_time for r in checked.hold]
    assert [e["dose_fraction"] for e in ev if e["kind"] == "heat"] == \
        checked.protocol_check["delivered_fractions"]
    assert ev[1]["uptake_fraction"] == checked.protocol_check["rest_uptake_fractions"][0]


def test_a_drug_wait_is_a_hold_and_rests_leak(fake_planner) -> None:
    """A drug's wait at T_start before the first heating is the first event (kind 'hold'),
    every heating after it on the same clock; what a rest leaks is its dose."""
    req = Request(**FAKE_CASE, heating=Jump(308.0), payload=Drug(CARRIED, wait=0.2),
                  question=Schedule([0.3, 0.3], rests=[0.5]))
    res = plan(req, planner=fake_planner)
    ev = res.events
    assert [e["kind"] for e in ev] == ["hold", "heat", "rest", "heat"]
    assert ev[0]["duration_tau"] == pytest.approx(0.2) and ev[0]["temperature_K"] == 302.0
    assert ev[1]["start_tau"] == pytest.approx(0.2)
    c = res.corrected
    assert ev[0]["dose_fraction"] == c["leaked_before_heating"]
    assert ev[2]["dose_fraction"] == c["rest_leak_fractions"][0]


def test_the_builder_takes_any_answer_with_its_request(fake_planner) -> None:
    """One builder: the answer and its request in, the same rows as the answer carries."""
    request = _request(("fluid", "one", "protocol", "schedule"))
    res = plan(request, planner=fake_planner)
    assert schedule_events(res.answer, request.planned) == res.events


@pytest.mark.anyio
async def test_http_schedule_job_answers_with_events(fake_planner) -> None:
    """The HTTP job's result carries the same events as Python's answer."""

    key = ("fluid", "batch", "jump", "schedule")
    py = plan(_request(key), planner=fake_planner)
    async with asgi(create_app(planner=fake_planner, warm=False)) as (api, raw):
        r = await raw.post("/v1/schedule", json={**FAKE_CASE, "t_end": 308.0,
                                                 "doses": [0.3, 0.3], "rests": [0.5],
                                                 "size_distribution": CV})
        assert r.status_code == 202, r.text
        v = await api.wait_validation(r.json()["validation_id"], timeout=120.0, interval=0.05)
    assert v.status == "done", v.error
    got = v.result["events"]
    assert [e["kind"] for e in got] == ["heat", "rest", "heat"]
    assert [e["duration_s"] for e in got] == pytest.approx(
        [e["duration_s"] for e in py.events], rel=1e-12)


def test_cli_acceptance_events_and_csv(tmp_path, capsys) -> None:
    """The issue's schedule (ANB 302 -> 308 K, 50 um, 3 x 30 %, rests 0.5 tau) on the real
    solver: three heats of 13.81 / 14.36 / 14.64 s and two rests of 1,102 s, in the JSON and
    leading the CSV that --out writes."""
    out = tmp_path / "sched.csv"
    args = ["schedule", "--gel", "ANB", "--t-start", "302", "--t-end", "308", "--doses", "0.3",
            "0.3", "0.3", "--rests", "0.5", "0.5", "--dry-radius-um", "50", "--viscosity",
            "1e-3", "--polymer-volume-m3", "3e-25", "--k0-m2", "8e-20",
            "--cache", str(tmp_path / "c.sqlite")]
    assert main([*args, "--json", "--out", str(out)]) == 0
    d = json.loads(capsys.readouterr().out)
    ev = d["events"]
    assert [e["kind"] for e in ev] == ["heat", "rest", "heat", "rest", "heat"]
    heats = [round(e["duration_s"], 2) for e in ev if e["kind"] == "heat"]
    assert heats == [13.81, 14.36, 14.64]
    assert [round(e["duration_s"]) for e in ev if e["kind"] == "rest"] == [1102, 1102]
    assert all(e["reading"] == "corrected" and not e["rough"] for e in ev)
    assert np.allclose([e["dose_fraction"] for e in ev if e["kind"] == "heat"], 0.3, rtol=0.01)
    lines = [x for x in out.read_text().splitlines() if not x.startswith("#")]
    rows = list(csv.DictReader(lines))
    assert list(rows[0])[:5] == ["step [1]", "kind", "start_s [s]", "duration_s [s]",
                                 "temperature_K [K]"]
    assert [r["kind"] for r in rows] == ["heat", "rest", "heat", "rest", "heat"]
    assert [round(float(r["duration_s [s]"]), 2) for r in rows[::2]] == heats
    # the text output prints them too; netCDF keeps the units
    assert main([*args, "--out", str(tmp_path / "s.nc")]) == 0
    text = capsys.readouterr().out
    assert "events (corrected times):" in text and "13.81 s" in text
    from dosing.present import export

    ds = export.open_netcdf(tmp_path / "s.nc")
    assert ds["duration_s"].attrs["units"] == "s" and list(ds["kind"].values)[:2] == [
        "heat", "rest"]
    assert main([*args, "--out", str(tmp_path / "s.txt")]) != 0
    assert "--out" in capsys.readouterr().err


def test_a_repeated_protocol_heating_is_written_out_in_its_events(fake_planner) -> None:
    """Every heating follows a protocol with a repeat ('2 x (...)'): each heat event's
    program is the protocol written out and cut at the heating's time, in the grammar's
    words, its set temperature the one at its end."""
    req = Request(**FAKE_CASE, heating=Heating(["2 x (Hold at 308 K for 0.1 s; Rest at 302 K "
                                                "for 0.2 s)", "Hold at 308 K"]),
                  question=Schedule([0.3, 0.3], rests=[0.5]),
                  constants=PhysicalConstants.paper())  # tau 3.5 s: the steps are seconds
    res = plan(req, planner=fake_planner)
    ev = _check_events(res, ("fluid", "one", "repeat"))
    for e in (x for x in ev if x["kind"] == "heat"):
        steps = e["program"].split("; ")
        assert steps[:4] == ["Hold at 308 K for 0.1 s", "Hold at 302 K for 0.2 s"] * 2
        assert steps[4].startswith("Hold at 308 K for ") and len(steps) == 5
        assert e["duration_s"] == pytest.approx(0.6 + float(steps[4].split()[-2]), rel=1e-3)
        assert e["temperature_K"] == 308.0
