"""The heating-step grammar (dosing.heating.grammar): strings, structured steps, traces, errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dosing.heating.grammar import (
    Bath,
    Hold,
    Protocol,
    Ramp,
    Span,
    Trace,
    Until,
    parse_step,
    trace_from_csv,
)
from dosing.heating.program import MAX_STAIRS, staircase
from solver.errors import ParameterError

TAU = 2000.0  # s: a round timescale (a 50 um bead's is 2205 s at 308 K)


@pytest.mark.parametrize("text, want", [
    ("Heat to 308 K at 5 K/min", Ramp("heat", 308.0, 5.0 / 60.0)),
    ("heat to 35 degC at 0.5 K/s", Ramp("heat", 308.15, 0.5)),
    ("Cool to 302 K at 2 K/min", Ramp("cool", 302.0, 2.0 / 60.0)),
    ("Cool to 29 °C at 120 K/h", Ramp("cool", 302.15, 120.0 / 3600.0)),
    ("Heat to 308 K at 3 degC/min", Ramp("heat", 308.0, 3.0 / 60.0)),  # a difference, not +273
    ("Heat to 308 K at 40 K/tau", Ramp("heat", 308.0, 40.0, "K/tau")),
    ("Hold at 308 K for 2 min", Hold("hold", 308.0, Span(120.0))),
    ("Hold at 308 K for 0.05 tau", Hold("hold", 308.0, Span(0.05, "tau"))),
    ("Hold at 308 K until 30 % released", Hold("hold", 308.0, None, Until("fraction", 0.3))),
    ("Hold at 308 K until 0.3 released", Hold("hold", 308.0, None, Until("fraction", 0.3))),
    ("Hold at 308 K until 20 ug released", Hold("hold", 308.0, None, Until("mass_ug", 20.0))),
    ("Hold at 308 K until 2 nL released", Hold("hold", 308.0, None,
                                                Until("volume_ul", 0.002))),
    ("Hold at 308 K until radius 60 um", Hold("hold", 308.0, None, Until("radius_um", 60.0))),
    ("Rest at 302 K for 10 min", Hold("rest", 302.0, Span(600.0))),
    ("Rest at 302 K for 1.5 h", Hold("rest", 302.0, Span(5400.0))),
    ("Bath at 308 K with a time constant of 30 s", Bath(308.0, Span(30.0))),
    ("Bath at 308 K with time constant 0.5 min for 2 min", Bath(308.0, Span(30.0),
                                                               Span(120.0))),
    ("Bath at 308 K with a time constant of 30 s until 80 % released",
     Bath(308.0, Span(30.0), None, Until("fraction", 0.8))),
    ("  Hold   at 308 K   for 2 min ", Hold("hold", 308.0, Span(120.0))),
])
def test_step_strings(text, want):
    step = parse_step(text)
    assert step.kind == want.kind
    for name in ("to_k", "at_k", "rate", "rate_unit", "duration", "until", "time_constant"):
        if hasattr(want, name):
            got, exp = getattr(step, name), getattr(want, name)
            if isinstance(exp, float):
                assert got == pytest.approx(exp, rel=1e-12), name
            else:
                assert got == exp, name


@pytest.mark.parametrize("text", [
    "Heat to 308 K at 5 K/min", "Cool to 302 K at 2 K/min", "Hold at 308 K for 2 min",
    "Hold at 308 K until 30 % released", "Hold at 308 K until 20 ug released",
    "Hold at 308 K until radius 60 um", "Rest at 302 K for 10 min",
    "Bath at 308 K with a time constant of 30 s", "Hold at 308 K for 0.05 tau",
])
def test_text_and_dict_round_trip(text):
    """A step's text and its structured form parse back to the same step."""
    step = parse_step(text)
    assert parse_step(step.text) == step
    assert parse_step(step.to_dict()) == step


def test_structured_steps_with_units():
    """The structured JSON form takes strings with units or plain numbers (K, s, K/s)."""
    assert parse_step({"step": "heat", "to": "35 degC", "rate": "5 K/min"}) == \
        Ramp("heat", 308.15, 5.0 / 60.0)
    assert parse_step({"step": "hold", "at": 308, "for": 120}) == Hold("hold", 308.0,
                                                                        Span(120.0))
    assert parse_step({"step": "hold", "at": 308, "until": "30 % released"}).until == \
        Until("fraction", 0.3)
    assert parse_step({"step": "rest", "at": "302 K", "until": {"radius_um": "0.1 mm"}}
                      ).until == Until("radius_um", 100.0)
    assert parse_step({"step": "bath", "at": 308, "time_constant": "30 s"}) == \
        Bath(308.0, Span(30.0))


@pytest.mark.parametrize("step, field, valid_part", [
    ("Heat to 400 K at 5 K/min", "protocol[0].to", "273.15-373.15 K"),
    ("Heat to 308 K at 0 K/min", "protocol[0].rate", "0.001-1e+06 K/min"),
    ("Heat to 308 K at 5 K", "protocol[0].rate", "K/min"),
    ("Heat to 308 K at 1e7 K/min", "protocol[0].rate", "0.001-1e+06 K/min"),
    ("Hold at 308 K for -2 min", "protocol[0].for", "0 s < for"),
    ("Hold at 308 K for 2 K", "protocol[0].for", "units s, min, h or tau"),
    ("Hold at 308 K for 1e9 s", "protocol[0].for", "1e+07 s"),
    ("Hold at 308 m for 2 min", "protocol[0].at", "273.15-373.15 K"),
    ("Hold at 308 K until 130 % released", "protocol[0].until.fraction", "0 < fraction < 1"),
    ("Hold at 308 K until radius -5 um", "protocol[0].until.radius_um", "> 0"),
    ("Hold at 308 K until the cows come home", "protocol[0].until", "% released"),
    ("Bath at 308 K with a time constant of 0 s", "protocol[0].time_constant", "0.001 s"),
    ("Boil at 308 K", "protocol[0]", "Heat to 308 K at 5 K/min"),
    # pint evaluates powers exactly: 9**9**9 would never finish (a request must not hang)
    ("Hold at 308 K for 9**9**9 s", "protocol[0].for", "no powers"),
    ("Heat to 308 K at 5 K/min^9", "protocol[0].rate", "no powers"),
    ("Hold at 308 K until 9**9**9 ug released", "protocol[0].until", "no powers"),
    ("Hold at 308 K for " + "1" * 90 + " s", "protocol[0].for", "at most 80"),
])
def test_bad_steps_name_step_field_and_range(step, field, valid_part):
    with pytest.raises(ParameterError) as e:
        Protocol(302.0, [step])
    assert e.value.field == field
    assert valid_part in e.value.valid
    assert "step 0" in str(e.value) and repr(" ".join(step.split())) in str(e.value)


def test_error_names_the_right_step_index():
    with pytest.raises(ParameterError) as e:
        Protocol(302.0, ["Heat to 308 K at 5 K/min", "Hold at 308 K for 1 min",
                         "Cool to 310 K at 2 K/min"])
    assert e.value.field == "protocol[2].to"
    assert "below 308 K" in e.value.valid and "'Cool to 310 K at 2 K/min'" in str(e.value)
    with pytest.raises(ParameterError) as e:
        Protocol(302.0, ["Heat to 300 K at 5 K/min"])
    assert e.value.field == "protocol[0].to" and "above 302 K" in e.value.valid


def test_open_ended_step_only_last():
    Protocol(302.0, ["Heat to 308 K at 5 K/min", "Bath at 302 K with a time constant of 30 s"])
    with pytest.raises(ParameterError) as e:
        Protocol(302.0, ["Hold at 308 K", "Rest at 302 K for 1 min"])
    assert e.value.field == "protocol[0].for"


def test_structured_errors():
    with pytest.raises(ParameterError) as e:
        Protocol(302.0, [{"step": "heat", "to": 308}])
    assert e.value.field == "protocol[0].rate" and "required" in e.value.valid
    with pytest.raises(ParameterError) as e:
        Protocol(302.0, [{"step": "hold", "at": 308, "for": 1, "speed": 3}])
    assert e.value.field == "protocol[0].speed"
    with pytest.raises(ParameterError) as e:
        Protocol(302.0, [{"step": "melt"}])
    assert e.value.field == "protocol[0].step"
    with pytest.raises(ParameterError) as e:
        Protocol(302.0, [{"step": "hold", "at": 308, "until": {"mass_ug": "9**9**9 ug"}}])
    assert e.value.field == "protocol[0].until.mass_ug" and "no powers" in e.value.valid
    with pytest.raises(ParameterError) as e:
        Protocol(302.0, [])
    assert e.value.field == "protocol"


def test_program_converts_seconds_to_tau():
    """A 6 K ramp at 5 K/min lasts 72 s; a 2 min hold 120 s; a 0.1 tau hold stays 0.1."""
    p = Protocol(302.0, ["Heat to 308 K at 5 K/min", "Hold at 308 K for 2 min",
                         "Hold at 308 K for 0.1 tau", "Cool to 302 K at 40 K/tau"])
    prog = p.program(TAU)
    assert [x.shape for x in prog] == ["ramp", "hold", "hold", "ramp"]
    assert prog[0].duration == pytest.approx(72.0 / TAU, rel=1e-12)
    assert prog[1].duration == pytest.approx(120.0 / TAU, rel=1e-12)
    assert prog[2].duration == 0.1
    assert prog[3].duration == pytest.approx(6.0 / 40.0, rel=1e-12)
    assert p.hottest == 308.0 and p.final_temperature == 302.0
    with pytest.raises(ParameterError) as e:
        p.program(None)  # seconds without a bead size
    assert e.value.field == "dry_radius_um"


def test_windows():
    p = Protocol(302.0, ["Heat to 308 K at 6 K/min", "Hold at 308 K for 1 min",
                         "Rest at 302 K for 1 min", "Hold at 308 K for 1 min"])
    w = p.windows(60.0)  # tau = 60 s: one minute is one tau
    assert w == [(0.0, pytest.approx(2.0)), (pytest.approx(3.0), None)]


def test_staircase_ramp_is_second_order_and_keeps_the_time():
    """Stairs hold the time-mean temperature: their time-integral of T equals the ramp's,
    and the total duration is kept; the tail holds at the ramp's target (not its last
    stair)."""
    p = Protocol(302.0, ["Heat to 308 K at 5 K/min"])
    prog = p.program(TAU)
    st = staircase(prog, 0.1, 0.05)
    d = np.array([s[0] for s in st])
    temps = np.array([s[1] for s in st])
    assert d.sum() == pytest.approx(72.0 / TAU + 0.1, rel=1e-12)
    assert st[-1] == (pytest.approx(0.1), 308.0)
    ramp = d[:-1]
    exact = (302.0 + 308.0) / 2.0 * 72.0 / TAU
    assert float(np.dot(ramp, temps[:-1])) == pytest.approx(exact, rel=1e-9)
    assert 110 <= len(st) <= 125  # 6 K at 0.05 K per stair
    assert np.all(np.diff(temps[:-1]) > 0.0) and np.max(np.diff(temps[:-1])) < 0.06


def test_staircase_bath_follows_the_lag():
    """A bath's stairs follow T_b + (T_0 - T_b) exp(-t / tc) until within half a stair."""
    p = Protocol(302.0, ["Bath at 308 K with a time constant of 30 s"])
    st = staircase(p.program(TAU), 0.05)
    t = np.cumsum([0.0] + [s[0] for s in st[:-1]])
    mid = t[:-1] + 0.5 * np.diff(t)
    lag = 308.0 - 6.0 * np.exp(-mid * TAU / 30.0)
    assert np.max(np.abs(np.array([s[1] for s in st[:-2]]) - lag[:-1])) < 0.05
    assert st[-1] == (pytest.approx(0.05), 308.0)


def test_staircase_caps_its_size():
    p = Protocol(273.15, ["Heat to 373.15 K at 1e-3 K/min"])
    st = staircase(p.program(1.0), 0.0)
    assert len(st) <= MAX_STAIRS


# ----------------------------------------------------------------------------- traces
CSV_C = "time (min),T (degC)\n0,29\n0.5,31\n1,33\n2,35\n"


def test_trace_in_degc_and_minutes():
    tr = trace_from_csv(CSV_C)
    assert tr.times_s == (0.0, 30.0, 60.0, 120.0)
    assert tr.temperatures_k == pytest.approx((302.15, 304.15, 306.15, 308.15))
    p = Protocol("29 degC", [tr])
    piece = p.program(60.0)[0]
    assert piece.shape == "trace" and piece.duration == pytest.approx(2.0)
    assert float(piece.temperature(np.array([0.75]))[0]) == pytest.approx(305.15)
    assert p.hottest == pytest.approx(308.15) and p.final_temperature == pytest.approx(308.15)


def test_trace_units_by_header_or_argument():
    assert trace_from_csv("time_s,T_K\n0,302\n10,305\n").times_s == (0.0, 10.0)
    tr = trace_from_csv("0,29\n60,35\n", time_unit="s", temperature_unit="degC")
    assert tr.temperatures_k == pytest.approx((302.15, 308.15))
    tr = trace_from_csv("# a comment\n5,302\n65,305\n")  # times from the first row
    assert tr.times_s == (0.0, 60.0)


def test_trace_file_step(tmp_path):
    f = tmp_path / "run.csv"
    f.write_text(CSV_C)
    step = parse_step(f"Trace from {f}")
    assert isinstance(step, Trace) and len(step.times_s) == 4
    with pytest.raises(ParameterError) as e:
        parse_step(f"Trace from {f}", files=False)  # HTTP: no file paths
    assert e.value.field == "protocol[0].trace"
    with pytest.raises(ParameterError) as e:
        parse_step(f"Trace from {tmp_path / 'missing.csv'}")
    assert "readable CSV" in e.value.valid


def test_trace_structured():
    tr = parse_step({"step": "trace", "time": [0, 1, 2], "temperature": [29, 32, 35],
                     "time_unit": "min", "temperature_unit": "degC"})
    assert tr.times_s == (0.0, 60.0, 120.0)
    assert parse_step({"step": "trace", "csv": CSV_C}).times_s == (0.0, 30.0, 60.0, 120.0)
    assert parse_step(tr.to_dict()) == tr


@pytest.mark.parametrize("body, where, valid_part", [
    ("time (s),T (K)\n0,302\n10,305\n10,306\n", "line 4, column 1 (time)", "increasing"),
    ("time (s),T (K)\n0,302\n10,305\n5,306\n", "line 4, column 1 (time)", "increasing"),
    ("time (s),T (K)\n0,302\n10,nan\n", "line 3, column 2 (temperature)", "finite"),
    ("time (s),T (K)\n0,302\nx,303\n", "line 3, column 1 (time)", "finite"),
    ("time (s),T (K)\n0,302\n10,380\n", "line 3, column 2 (temperature)", "273.15-373.15 K"),
    ("time (s),T (degC)\n0,29\n10,-5\n", "line 3, column 2 (temperature): -5 degC",
     "273.15-373.15 K"),
    ("0,29\n10,35\n", "line 1, column 2 (temperature): 29 K", "name the unit"),
    ("time (s),T (K)\n0,302\n", "1 rows", "2-100000 rows"),
])
def test_bad_traces_name_line_and_column(body, where, valid_part):
    with pytest.raises(ParameterError) as e:
        trace_from_csv(body, name="run.csv", index=3)
    assert e.value.field == "protocol[3].trace"
    assert where in str(e.value.value)
    assert valid_part in e.value.valid
    assert "run.csv" in str(e.value)


def test_trace_over_100000_rows_refused():
    rows = "\n".join(f"{k},{302 + (k % 3)}" for k in range(100_001))
    with pytest.raises(ParameterError) as e:
        trace_from_csv(rows)
    assert e.value.value == "100001 rows" and "100000" in e.value.valid
    ok = trace_from_csv("\n".join(f"{k},{302 + (k % 3)}" for k in range(100_000)))
    assert len(ok.times_s) == 100_000


def test_bad_structured_trace():
    with pytest.raises(ParameterError) as e:
        parse_step({"step": "trace", "time": [0, 1], "temperature": [302, 303, 304]}, 2)
    assert e.value.field == "protocol[2].trace"
    with pytest.raises(ParameterError) as e:
        parse_step({"step": "trace", "time": [0, 1], "temperature": [302, 303],
                    "time_unit": "fortnight"})
    assert e.value.field == "protocol[0].trace.time_unit"
    with pytest.raises(ParameterError) as e:
        parse_step({"step": "trace", "time": [0, math.nan], "temperature": [302, 303]})
    assert "line 2, column 1" in e.value.value


@pytest.mark.parametrize("steps, field, valid_part", [
    # issue 40, R1: the grammar took these, the solver refused them inside a pool worker
    (["Bath at 308 K with a time constant of 1e6 tau"], "protocol[0].time_constant",
     "time_constant <= 25000 tau for a bath without 'for' or 'until'"),
    (["Heat to 308 K at 1e-320 K/tau"], "protocol[0].rate", "at most 1e+06 tau"),
    (["Hold at 308 K for 2 min", "Cool to 302 K at 1e-9 K/tau"], "protocol[1].rate",
     "at least 6e-06 K/tau"),
    (["Hold at 308 K for 1e7 s"], "protocol[0].for", "0 < duration <= 1e+06 (tau)"),
    (["Bath at 308 K with a time constant of 1e6 s for 1 min"], "protocol[0].time_constant",
     "0 < time_constant <= 1e+06 (tau)"),
])
def test_what_the_grammar_accepts_the_solver_accepts(steps, field, valid_part):
    """A request's protocol is checked in tau by the solver's own rules (solver.heating,
    the ranges of solver.limits) before anything is queued: a 422 naming the step."""
    from dosing.request import DoseRequest

    with pytest.raises(ParameterError) as err:
        DoseRequest(gel="ANB", t_start=302, dose_fraction=0.5, dry_radius_um=1,
                    protocol=steps)
    assert err.value.field == field, err.value
    assert valid_part in err.value.valid, err.value
    assert "as the solver runs it" in str(err.value)
    ok = DoseRequest(gel="ANB", t_start=302, dose_fraction=0.5, dry_radius_um=1,
                     protocol=["Heat to 308 K at 1e-5 K/tau", "Hold at 308 K for 1e6 tau"])
    assert ok.heating is not None
