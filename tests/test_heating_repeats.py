"""The step grammar's repeats and 'or until' (issue 37): '3 x (Heat to 308 K at 5 K/min;
Hold at 308 K for 2 min; Cool to 302 K at 5 K/min)' is written out in the one grammar, and
'Hold at 308 K for 10 min or until 30 % released' ends at whichever comes first; every
error names the step (and, in a repeat, its place and repetition)."""

from __future__ import annotations

import pytest
from api_support import asgi

from api.http import create_app
from dosing import PhysicalConstants
from dosing.heating.grammar import Hold, Protocol, Until, parse_step
from dosing.question import Dose, Heating, Request, plan
from solver.errors import ParameterError

CYCLE = "3 x (Heat to 308 K at 5 K/min; Hold at 308 K for 2 min; Cool to 302 K at 5 K/min)"
ONE = ["Heat to 308 K at 5 K/min", "Hold at 308 K for 2 min", "Cool to 302 K at 5 K/min"]


def test_a_repeat_is_written_out() -> None:
    p = Protocol(302.0, [CYCLE, "Hold at 308 K"])
    assert p.texts == ONE * 3 + ["Hold at 308 K"]
    assert p.final_temperature == 308.0 and p.hottest == 308.0
    # the spellings and the structured form are the same protocol
    for text in ("3 x(Heat to 308 K at 5 K/min;Hold at 308 K for 2 min;Cool to 302 K at "
                 "5 K/min)", "3 times (" + "; ".join(ONE) + ")",
                 "Repeat 3 x (" + "; ".join(ONE) + ")", "3 × (" + "; ".join(ONE) + ")"):
        assert Protocol(302.0, [text, "Hold at 308 K"]).steps == p.steps
    structured = {"step": "repeat", "times": 3, "steps": ONE}
    assert Protocol(302.0, [structured, "Hold at 308 K"]).steps == p.steps
    # the program: three ramps up and down, each 72 s at 5 K/min, and the holds
    prog = p.program(10.0)
    assert [x.shape for x in prog[:3]] == ["ramp", "hold", "ramp"] and len(prog) == 10
    assert prog[0].duration == pytest.approx(7.2) and prog[1].duration == pytest.approx(12.0)


@pytest.mark.parametrize("steps,field,words", [
    (["3 x (Heat to 308 K at 5 K/min; Hold at 308 K for 2 parsecs)"], "protocol[0].steps[1].for",
     "in step 1 of the repeat in step 0"),
    (["Hold at 303 K for 1 min", "0 x (Heat to 308 K at 5 K/min)"], "protocol[1].times",
     "1-100"),
    (["101 x (Heat to 308 K at 5 K/min; Cool to 302 K at 5 K/min)"], "protocol[0].times",
     "1-100"),
    (["2 x (Heat to 308 K at 5 K/min; Hold at 308 K until 30 % released)"],
     "protocol[0].steps[1].for", "bare until-condition"),
    (["2 x (Heat to 308 K at 5 K/min)"], "protocol[0].steps[0].to", "(repeat 2 of 2)"),
    (["2 x (Heat to 308 K at 5 K/min; 2 x (Cool to 302 K at 5 K/min))"],
     "protocol[0].steps[1]", "no repeat in a repeat"),
    (["2 x (Heat to 308 K at 5 K/min; )"], "protocol[0].steps", "none empty"),
    ([{"step": "repeat", "times": 2.5, "steps": ONE}], "protocol[0].times", "whole number"),
    ([{"step": "repeat", "times": 2, "steps": ONE, "then": 1}], "protocol[0].then", "steps"),
    (["Hold at 308 K for 10 min or until 130 % released"], "protocol[0].until.fraction",
     "0 < fraction < 1"),
    (["Hold at 308 K for 10 parsecs or until 30 % released"], "protocol[0].for", "units s"),
    (["400 x (Heat to 308 K at 5 K/min; Cool to 302 K at 5 K/min)"], "protocol[0].times",
     "1-100"),
    (["100 x (Heat to 308 K at 5 K/min; Hold at 308 K for 1 s; Hold at 306 K for 1 s; "
      "Hold at 305 K for 1 s; Hold at 304 K for 1 s; Cool to 302 K at 5 K/min)"] * 2,
     "protocol", "1-1000 steps"),
])
def test_errors_name_the_step(steps, field, words) -> None:
    with pytest.raises(ParameterError) as exc:
        Protocol(302.0, steps)
    assert exc.value.field == field, str(exc.value)
    assert words in str(exc.value)


def test_for_or_until_parses_both_ends() -> None:
    st = parse_step("Hold at 308 K for 10 min or until 30 % released")
    assert isinstance(st, Hold) and st.duration.value == 600.0
    assert st.until == Until("fraction", 0.3)
    assert st.text == "Hold at 308 K for 10 min or until 30 % released"
    assert parse_step(st.to_dict()) == st  # the structured form has both
    assert parse_step(st.text) == st
    bath = parse_step("Bath at 35 degC with a time constant of 30 s for 5 min or until radius "
                      "60 um")
    assert bath.duration.value == 300.0 and bath.until == Until("radius_um", 60.0)
    # an until-step like any other: the planner resolves it (and it may come mid-protocol)
    p = Protocol(302.0, ["Hold at 308 K for 10 min or until 30 % released",
                         "Rest at 302 K for 1 min", "Hold at 308 K"])
    assert p.until_steps == [0]


def _dose(planner, first: str):
    req = Request("ANB", 302.0, Heating([first, "Rest at 302 K for 5 s", "Hold at 308 K"]),
                  Dose(0.5), dry_radius_um=2.0,
                  constants=PhysicalConstants.paper())  # tau 3.5 s: the steps are seconds
    return plan(req, planner=planner).to_dict()


def test_for_or_until_ends_at_whichever_comes_first(fake_planner) -> None:
    """On the fake solver: the condition first (30 % out at 0.17 s, within 1 s) is the
    until-step's answer; the duration first (0.1 s) is the timed step's."""
    until = _dose(fake_planner, "Hold at 308 K until 30 % released")
    hit = until["until_steps"][0]["end_seconds"]
    assert 0.1 < hit < 1.0
    first = _dose(fake_planner, "Hold at 308 K for 1 s or until 30 % released")
    assert first["until_steps"][0]["ended_by"] == "until"
    assert first["until_steps"][0]["end_seconds"] == pytest.approx(hit, rel=1e-3)
    assert first["seconds"] == pytest.approx(until["seconds"], rel=1e-4)
    timed = _dose(fake_planner, "Hold at 308 K for 0.1 s")
    short = _dose(fake_planner, "Hold at 308 K for 0.1 s or until 30 % released")
    assert short["until_steps"][0]["ended_by"] == "duration"
    assert short["until_steps"][0]["end_seconds"] == pytest.approx(0.1, rel=1e-9)
    assert short["seconds"] == pytest.approx(timed["seconds"], rel=1e-9)
    assert short["seconds"] != pytest.approx(until["seconds"], rel=1e-3)


@pytest.mark.anyio
async def test_http_takes_repeats_and_names_a_bad_step(fake_planner) -> None:
    """The same grammar over HTTP: a repeat answered, a bad step in it a 422 naming it."""
    body = {"gel": "ANB", "t_start": 302.0, "dry_radius_um": 2.0, "dose_fraction": 0.3,
            "protocol": ["2 x (Hold at 308 K for 0.05 s; Rest at 302 K for 1 s)",
                         "Hold at 308 K"]}
    async with asgi(create_app(planner=fake_planner, warm=False)) as (_, raw):
        bad = await raw.post("/v1/dose-time", json={
            **body, "protocol": ["2 x (Hold at 308 K for 0.05 s; Rest at 302 K for 1 parsec)"]})
        assert bad.status_code == 422
        assert "protocol[0].steps[1].for" in bad.text and "parsec" in bad.text
        r = await raw.post("/v1/dose-time", json=body)
        assert r.status_code in (200, 202), r.text
        if r.status_code == 200:
            assert r.json()["protocol"][:2] == ["Hold at 308 K for 0.05 s",
                                                "Rest at 302 K for 1 s"]
