"""A fuzz of the step grammar, measured traces and unit strings (issue 40, R6): whatever
the steps, traces and units, the planner's parsers raise only input errors (a 422), and
the service answers no body with a 5xx.  Quick: a few hundred examples, seconds."""

from __future__ import annotations

import json
from typing import Any

import pytest
from api_support import fake_full_solver, fake_planner
from fastapi.testclient import TestClient
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from api.http import create_app
from api.requests import http_protocol
from dosing.fits.release_steps import parse_protocol
from solver.errors import NotApplicableError, ParameterError

NUMBERS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(-10**6, 10**6).map(str),
    st.sampled_from(["0", "-0", "1e-324", "5e-324", "1e308", "1e309", "2.", ".5", "1e", "-",
                     "nan", "inf", "9" * 400, "1_000", "0x10", "1/0", "(1)", "3**3", "1e-300"]),
    st.floats(273.0, 373.0).map(lambda x: f"{x:.6g}"),
)
UNITS = st.sampled_from(["", "K", "degC", "°C", "℃", "degF", "K/min", "K/s", "K/h", "K/tau",
                         "degC/min", "s", "min", "h", "tau", "ms", "day", "%", "percent",
                         "radian", "rad", "um", "nm", "mm", "ug", "mg", "uL", "nL", "kg",
                         "m/s", "K*s", "1/K", "dimensionless", "K^2", "s**2", "foo", "µm"])
QUANTITY = st.one_of(
    st.builds(lambda n, sp, u: f"{n}{sp}{u}", NUMBERS, st.sampled_from(["", " ", "  "]),
              UNITS),
    st.text(max_size=30),
    st.floats(allow_nan=False, allow_infinity=False),
    st.integers(),
    st.none(), st.booleans(), st.lists(st.integers(), max_size=3),
    st.dictionaries(st.sampled_from(["fraction", "mass_ug", "radius_um", "x"]),
                    st.one_of(st.floats(), st.text(max_size=8)), max_size=2),
)
# valid values, often: the fuzz must reach the program and the planner, not only the parser
T_OK = st.sampled_from(["308 K", "35 degC", 310.0, "309.5K", "36 °C", "308.15 kelvin"])
RATE_OK = st.sampled_from(["5 K/min", "0.5 K/s", "2 K/tau", "1 degC/min", 0.1, "60 K/h"])
DUR_OK = st.sampled_from(["2 min", "30 s", "0.5 h", "3 tau", 60.0, "1e-3 tau"])
T = st.one_of(T_OK, T_OK, QUANTITY)
RATE = st.one_of(RATE_OK, RATE_OK, QUANTITY)
DUR = st.one_of(DUR_OK, DUR_OK, QUANTITY)
UNTIL = st.one_of(
    st.sampled_from(["30 % released", "0.5 released", "radius 60 um", "20 ug released",
                     "0.5 nL released", {"fraction": 0.3}, {"radius_um": "60 um"}]),
    st.builds(lambda q: f"{q} released", QUANTITY.filter(lambda q: isinstance(q, str))),
    st.builds(lambda q: f"radius {q}", QUANTITY.filter(lambda q: isinstance(q, str))),
    QUANTITY,
)


def _text(q: object) -> str:
    return q if isinstance(q, str) else repr(q)


STEP_TEXT = st.one_of(
    st.builds(lambda k, t, r: f"{k} to {_text(t)} at {_text(r)}",
              st.sampled_from(["Heat", "Cool", "heat up", "COOL down"]), T, RATE),
    st.builds(lambda k, t, d: f"{k} at {_text(t)} for {_text(d)}",
              st.sampled_from(["Hold", "Rest"]), T, DUR),
    st.builds(lambda t, u: f"Hold at {_text(t)} until {_text(u)}", T, UNTIL),
    st.builds(lambda t, c, d: f"Bath at {_text(t)} with a time constant of {_text(c)}{d}",
              T, DUR, st.sampled_from(["", " for 2 min", " until 30 % released"])),
    st.builds(lambda p: f"Trace from {p}", st.sampled_from(
        ["/etc/passwd", "/dev/zero", "run.csv", "", "..", "/proc/self/environ"])),
    st.text(max_size=60),
)
CELL = st.one_of(st.floats(0.0, 80.0).map(lambda x: f"{x:.3f}"), NUMBERS,
                 st.text(max_size=6), st.just(""))
CSV = st.builds(
    lambda head, rows, sep, end: (head + end if head else "")
    + end.join(sep.join(r) for r in rows),
    st.sampled_from(["", "time (s),T (K)", "time_min,T_C", "t [h],T [degC]", "a,b,c",
                     "time (fortnight),T (F)"]),
    st.one_of(st.lists(st.lists(CELL, min_size=0, max_size=3), max_size=12),
              st.integers(2, 40).map(lambda n: [[str(10 * k), f"{302 + k % 7}"]
                                                for k in range(n)])),
    st.sampled_from([",", ";", "\t"]), st.sampled_from(["\n", "\r\n", "\r", "\n\n"]),
)
TRACE = st.one_of(
    st.fixed_dictionaries({"step": st.just("trace"), "csv": CSV},
                          optional={"time_unit": QUANTITY, "temperature_unit": QUANTITY,
                                    "name": QUANTITY}),
    st.fixed_dictionaries({"step": st.just("trace"),
                           "time": st.lists(st.one_of(st.floats(), st.text(max_size=3)),
                                            max_size=6),
                           "temperature": st.lists(st.floats(), max_size=6)},
                          optional={"time_unit": QUANTITY, "temperature_unit": QUANTITY}),
)
STEP_DICT = st.fixed_dictionaries(
    {"step": st.sampled_from(["heat", "cool", "hold", "rest", "bath", "trace", "jump", ""])},
    optional={"to": T, "at": T, "rate": RATE, "for": DUR, "until": UNTIL,
              "time_constant": DUR, "csv": CSV})
STEP = st.one_of(STEP_TEXT, STEP_TEXT, STEP_DICT, TRACE)
STEPS = st.one_of(st.lists(STEP, min_size=1, max_size=3),
                  st.lists(STEP, max_size=2).map(lambda rest: ["Heat to 306 K at 5 K/min",
                                                               *rest]),
                  st.lists(STEP, max_size=2).map(lambda rest: [*rest, "Hold at 309 K"]))


@settings(max_examples=600, deadline=None, suppress_health_check=list(HealthCheck))
@given(steps=STEPS, tau=st.sampled_from([None, 1.0, 1e-3, 37.5, 1e4]))
def test_the_parsers_raise_only_input_errors(steps, tau) -> None:
    """Steps, traces and units of any shape: a protocol, or a ParameterError naming the
    step; its program in tau too (no other exception: each would be a 500)."""
    try:
        prot = http_protocol(302.0, steps)
        if not prot.until_steps:
            parse_protocol(302.0, prot)  # POST /v1/fit/release's check
        prot.program(tau)
        prot.windows(tau)
        _ = prot.texts, prot.hottest, prot.to_dict()
    except (ParameterError, NotApplicableError) as exc:
        assert str(exc)


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    with fake_full_solver(delay=0.0) as fake, \
            fake_planner(tmp_path_factory.mktemp("fuzz") / "c.sqlite", fake,
                         max_pending=1000) as planner, \
            TestClient(create_app(planner=planner, warm=False)) as c:
        yield c


BODIES = st.fixed_dictionaries(
    {"gel": st.just("ANB"), "t_start": st.just(302.0), "protocol": STEPS},
    optional={"dose_fraction": st.sampled_from([0.3, 0.8, 1e-9]),
              "dry_radius_um": st.sampled_from([50.0, 1e-3, 1e5])})


@settings(max_examples=100, deadline=None, suppress_health_check=list(HealthCheck))
@given(body=BODIES)
def test_no_protocol_body_is_a_server_error(client, body) -> None:
    """The same fuzz through POST /v1/dose-time: never a 5xx (POST /v1/fit/release parses
    with the same http_protocol and parse_protocol, fuzzed above without its jobs' real
    full-solver runs)."""
    r = _post(client, "/v1/dose-time", {"dose_fraction": 0.5, **body})
    assert r.status_code < 500, (body, r.text[:300])


def _post(client: TestClient, path: str, body: dict) -> Any:
    """POST ``body`` as JSON, NaN and Infinity written as such (the service refuses them)."""
    return client.post(path, content=json.dumps(body),
                       headers={"Content-Type": "application/json"})
