"""Planner logic on a fake full solver with a closed-form a(t): model choice, validations,
error estimates, deduplication, restarts, failures, horizon extension, schedules.

The real solver's numbers are checked in test_dosing_validation.py.
"""

import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
from dosing_fakes import FakeSolver, exact_time

from dosing import (
    DoseRequest,
    Planner,
    QueueFullError,
    ScheduleRequest,
    UnknownValidationError,
)
from dosing.runs.scenario import LADDER, PAPER
from dosing.units import expelled_volume, radius_after_dose
from dosing.validation import front_prior
from solver import HHT, equilibrium
from solver.equilibrium import nearest_stable

SMOOTH = {"gel": "HHT", "t_start": 304.0, "t_end": 307.6}  # the classifier says smooth
FRONT = {"gel": "ANB", "t_start": 302.0, "t_end": 308.0}


@pytest.fixture
def fake() -> FakeSolver:
    return FakeSolver()


def _planner(path: Path, solver: FakeSolver, workers: int = 2, **kw) -> Planner:
    return Planner(cache_path=path, executor=ThreadPoolExecutor(workers), solver=solver, **kw)


@pytest.fixture
def planner(tmp_path: Path, fake: FakeSolver):
    p = _planner(tmp_path / "c.sqlite", fake)
    yield p
    p.close()
    p.jobs.executor.shutdown()


def test_smooth_jump_is_answered_by_the_ladder_limit(planner, fake) -> None:
    """Default truth: the ladder ell = 0.005, 0.0025, 0.00125 (N = 800, 1600, 3200) on the
    Lagrangian grid, extrapolated to ell -> 0; the fake's t(ell) = t0 (1 + 200 ell^1.5)."""
    req = DoseRequest(**SMOOTH, dose_fraction=0.5, settings=LADDER)
    ans = planner.dose(req)
    a0 = req.start_radius
    af = nearest_stable(HHT, 307.6, a0).stretch
    t0 = exact_time(a0, af, radius_after_dose(a0, 0.5), "lagrangian")
    v = ans.validation
    assert ans.model == "full" and v["model"] == "regularized"
    assert ans.interfacial_length == 0.005 and "limit ell -> 0" in ans.truth
    assert [(e["grid"], e["n"], e["interfacial_length"]) for e in v["runs"]] == [
        ("lagrangian", 800, 0.005), ("lagrangian", 1600, 0.0025), ("lagrangian", 3200, 0.00125)]
    assert sorted((c["n"], c["interfacial_length"]) for c in fake.calls) == [
        (800, 0.005), (1600, 0.0025), (3200, 0.00125)]
    # each rung's read-off is exact to ~1e-5 (below); the extrapolation amplifies that by
    # 1/(2^1.5 - 1) ~ 0.55 on the last difference
    assert v["limit"]["order"] == pytest.approx(1.5, abs=0.01)
    assert ans.time == v["time"] == pytest.approx(t0, abs=2e-5)
    assert v["runs"][0]["time"] == pytest.approx(t0 * (1 + 200 * 0.005**1.5), abs=1e-5)
    assert ans.error_estimate == pytest.approx(v["error"] + 1e-5, rel=1e-9)  # + rtol
    assert v["limit"]["error"] == pytest.approx(1.25 * abs(v["time"] - v["runs"][2]["time"]))
    assert "Richardson" in ans.error_explanation


def test_smooth_jump_is_answered_by_the_full_solver_on_both_grids(planner, fake) -> None:
    req = DoseRequest(**SMOOTH, dose_fraction=0.5, settings=PAPER)
    ans = planner.dose(req)
    a0 = req.start_radius
    af = nearest_stable(HHT, 307.6, a0).stretch
    a = radius_after_dose(a0, 0.5)
    assert ans.model == "full" and ans.behaviour == "smooth"
    # 400 samples (h = 0.0025) per step, a^3 interpolated linearly: the read-off of
    # exp(-k t) is exact to (k h)^2 / (8 k) = 8e-6 for k = 10
    assert ans.time == pytest.approx(exact_time(a0, af, a), abs=1e-5)
    runs = ans.validation["runs"]
    assert [e["grid"] for e in runs] == ["eulerian", "lagrangian"]
    assert runs[1]["time"] == pytest.approx(exact_time(a0, af, a, "lagrangian"), abs=1e-5)
    assert ans.validation["grid_spread"] == pytest.approx(0.25, rel=1e-3)  # rates 10 vs 8
    assert ans.error_estimate == pytest.approx(0.25, rel=1e-3)
    assert "disagree by 25%" in ans.error_explanation
    assert len(fake.calls) == 2
    assert planner.dose(req).time == ans.time and len(fake.calls) == 2  # served by the cache


def test_front_answer_is_the_sharp_model_checked_against_the_ladder_limit(planner,
                                                                         fake) -> None:
    req = DoseRequest(**FRONT, dose_fraction=0.8, settings=LADDER)
    quick = planner.dose(req)
    assert quick.model == "front-sharp" and quick.validation is None and not fake.calls
    assert quick.error_estimate == front_prior(0.8, "front-sharp")
    assert "sharp-interface" in quick.error_explanation and quick.interfacial_length == 0.005
    checked = planner.dose(req, validate=True)
    v = checked.validation
    assert checked.time == quick.time and len(fake.calls) == 3
    lim = v["limit"]
    assert v["front_time_error"] == pytest.approx((quick.time - lim["time"]) / lim["time"])
    want = (abs(quick.time - lim["time"]) + lim["error"]) / quick.time
    assert checked.error_estimate == pytest.approx(want, rel=1e-12)
    assert "sharp-interface limit" in checked.error_explanation
    assert v["front_volume_error"] == v["runs"][2]["front_volume_error"]  # the finest rung


def test_front_answer_needs_no_full_solver_then_validation_adds_both_grids(planner,
                                                                           fake) -> None:
    req = DoseRequest(**FRONT, dose_fraction=0.8, settings=PAPER)
    quick = planner.dose(req)
    assert quick.model == "front" and quick.validation is None and not fake.calls
    assert quick.error_estimate == front_prior(0.8, "front") == 0.8
    assert quick.interfacial_length == 0.0 and "no interfacial energy" in quick.truth
    assert "Not yet checked" in quick.error_explanation
    checked = planner.dose(req, validate=True)
    v = checked.validation
    t_e, t_l = (e["time"] for e in v["runs"])
    assert v["time"] == t_e and v["model"] == "paper" and v["front_time"] == quick.time
    assert v["front_time_error"] == pytest.approx((quick.time - t_e) / t_e, rel=1e-12)
    a0, a = req.start_radius, quick.final_radius
    af = nearest_stable(req.gel, 308.0, a0).stretch
    a_full = ((a0**3 - af**3) * __import__("math").exp(-10.0 * quick.time) + af**3) ** (1 / 3)
    want = (expelled_volume(a0, a_full) - expelled_volume(a0, a)) / expelled_volume(a0, a)
    assert v["front_volume_error"] == pytest.approx(want, abs=1e-4)
    est = max(abs(quick.time - t_e), abs(quick.time - t_l)) / quick.time
    assert checked.error_estimate == pytest.approx(est, rel=1e-12)
    assert "on the eulerian grid" in checked.error_explanation
    assert "lagrangian" in checked.error_explanation
    again = planner.dose(req)  # a later plain answer carries the cached validation
    assert again.validation == v and len(fake.calls) == 2


def test_submit_validation_returns_at_once_dedups_and_survives_restart(tmp_path: Path,
                                                                      fake) -> None:
    fake.gate = threading.Event()
    path = tmp_path / "c.sqlite"
    p = _planner(path, fake, workers=4)
    t0 = time.perf_counter()
    vid = p.submit_validation(DoseRequest(**FRONT, dose_fraction=0.8, settings=LADDER))
    vid2 = p.submit_validation(DoseRequest(**FRONT, dose_fraction=0.5, settings=LADDER))
    assert time.perf_counter() - t0 < 1.0 and vid != vid2
    assert p.submit_validation(DoseRequest(**FRONT, dose_fraction=0.8, settings=LADDER)) == vid
    assert p.validation(vid).status in ("pending", "running")
    fake.gate.set()
    st = p.wait_validation(vid, 20.0, 0.02)
    assert st.status == "done" and st.result["time"] > 0
    assert [e["interfacial_length"] for e in st.result["runs"]] == [0.005, 0.0025, 0.00125]
    assert st.result["front_time_error"] is not None
    assert st.result["front_volume_error"] is not None
    assert p.wait_validation(vid2, 20.0, 0.02).status == "done"
    assert len(fake.calls) == 3  # one run per rung served both doses
    p.close()
    p.jobs.executor.shutdown()
    again = _planner(path, fake)  # a restart: same file, new planner
    assert again.validation(vid).result == st.result and len(fake.calls) == 3
    with pytest.raises(UnknownValidationError):
        again.validation("nope")
    again.close()
    again.jobs.executor.shutdown()


def test_failed_validation_reports_the_error(planner, fake) -> None:
    fake.fail = "boom: step budget exhausted"
    vid = planner.submit_validation(DoseRequest(**FRONT, dose_fraction=0.3))
    st = planner.wait_validation(vid, 20.0, 0.02)
    assert st.status == "failed" and "boom" in st.error


def test_queue_is_bounded(tmp_path: Path, fake) -> None:
    fake.gate = threading.Event()
    p = _planner(tmp_path / "c.sqlite", fake, max_pending=1)
    first = DoseRequest(**FRONT, dose_fraction=0.3, settings=LADDER)
    p.submit_validation(first)  # one validation: all three rungs admitted
    assert [p.jobs.state(sc.key()) is not None for sc in p.scenarios(first)] == [True] * 3
    other = DoseRequest(**{**FRONT, "t_start": 301.0}, dose_fraction=0.3, settings=LADDER)
    with pytest.raises(QueueFullError) as err:
        p.submit_validation(other)  # room for one validation: refused whole
    assert err.value.retry_after > 0
    assert all(p.jobs.state(sc.key()) is None for sc in p.scenarios(other))
    fake.gate.set()
    p.close()
    p.jobs.executor.shutdown()


def test_long_doses_extend_the_run_under_one_key(tmp_path: Path) -> None:
    slow = FakeSolver(rate_scale=0.05)  # 60 % takes t = 2.7: beyond the first horizon 1
    p = _planner(tmp_path / "c.sqlite", slow)
    req = DoseRequest(**SMOOTH, dose_fraction=0.6, settings=LADDER)
    ans = p.dose(req)
    a0 = req.start_radius
    af = nearest_stable(HHT, 307.6, a0).stretch
    assert ans.time == pytest.approx(exact_time(a0, af, ans.final_radius, "lagrangian", 0.05),
                                     rel=1e-4)
    assert ans.time > 1.0
    meta = p.cache.meta(ans.scenario_key)
    assert meta["runs"] == 2 and meta["horizon"] == pytest.approx(4.0)
    assert len(p.cache) == 3  # one row per scenario (rung), extended in place
    p.close()
    p.jobs.executor.shutdown()


def test_schedule_on_the_fake_solver(planner, fake) -> None:
    req = ScheduleRequest(**SMOOTH, doses=[0.2, 0.2, 0.2], rests=[0.1, 0.1],
                          dry_radius_um=50.0, settings=PAPER)  # hold and protocol: one grid
    ans = planner.schedule(req)
    a0 = equilibrium(HHT, 304.0).stretch
    af = nearest_stable(HHT, 307.6, a0).stretch
    ends = [exact_time(a0, af, radius_after_dose(a0, f)) for f in (0.2, 0.4, 0.6)]
    assert [h["end"] for h in ans.hold] == pytest.approx(ends, abs=1e-5)  # (kh)^2/(8k) = 8e-6
    chk = ans.protocol_check
    assert chk["relative_errors"][0] == pytest.approx(0.0, abs=1e-4)  # no rest before dose 1
    assert all(u > 0.01 for u in chk["rest_uptake_fractions"])  # it re-swells at rest
    assert chk["delivered_fractions"][1] > 0.2  # restarting from a larger radius: faster
    cor = ans.corrected
    assert cor["met"] and max(abs(e) for e in cor["relative_errors"]) <= 0.01
    assert cor["actuation_seconds"][0] == pytest.approx(cor["actuation_times"][0]
                                                        * ans.timescale_seconds)
    assert "2205" not in ans.timescale_formula  # T_end = 307.6 K here


def test_regularized_schedule_runs_the_protocol_at_the_coarsest_rung(planner, fake) -> None:
    req = ScheduleRequest(**FRONT, doses=[0.3, 0.3], rests=[0.2], settings=LADDER)
    ans = planner.schedule(req)
    assert ans.model == "front-sharp"
    protocol_runs = [c for c in fake.calls if len(c["protocol"]) > 1]
    assert protocol_runs and {(c["grid"], c["n"], c["interfacial_length"])
                              for c in protocol_runs} == {("lagrangian", 800, 0.005)}
    assert "interfacial length 0.005" in ans.note and "nucleate" in ans.note
    assert ans.corrected["met"]


@pytest.mark.parametrize("settings", [None, LADDER, PAPER])
@pytest.mark.parametrize("dry", [None, 50.0])
def test_front_answer_keys_the_truth_run_of_the_validation(settings, dry) -> None:
    """A sweep point's scenario key (built alone, without the other validation runs) is
    the first validation run's: /v1/validations and the cache find the same row."""
    from dosing.model_choice import front_answer
    from dosing.planner import request_scenarios

    kw = {} if settings is None else {"settings": settings}
    req = DoseRequest(**FRONT, dose_fraction=0.5, dry_radius_um=dry, **kw)
    assert front_answer(req).scenario_key == request_scenarios(req)[0].key()


def test_typed_answers_keep_their_json(planner, fake) -> None:
    """The answer's validation is a ValidationReport and its hold rows HoldRows; their
    JSON is the plain dicts the HTTP answers always had (same keys, same order)."""
    import json

    from dosing import ValidationReport

    ans = planner.dose(DoseRequest(**SMOOTH, dose_fraction=0.5, settings=LADDER))
    assert isinstance(ans.validation, ValidationReport)
    d = ans.to_dict()["validation"]
    assert type(d) is dict and list(d) == [
        "model", "method", "interfacial_length", "settings", "runs", "time", "error", "limit",
        "grid_spread", "front_time", "front_time_error", "front_volume_error", "uncertainty"]
    assert d == ans.validation.to_dict() and d["time"] == ans.validation.time
    json.dumps(ans.to_dict(), allow_nan=False)
    sch = planner.schedule(ScheduleRequest(**FRONT, doses=(0.3, 0.3), rests=(0.0,)))
    rows = sch.to_dict()["hold"]
    assert [type(r) for r in rows] == [dict, dict] and list(rows[0]) == [
        "dose_fraction", "cumulative_fraction", "start", "end", "actuation_time",
        "actuation_seconds", "error_estimate"]
    assert rows[1]["end"] == sch.hold[1].end == sch.hold[1]["end"]


def test_a_run_short_of_the_dose_radius_is_reported_not_raised() -> None:
    # a stored run that never reaches the asked radius is that run's error in the report
    # (the validation poll raised it before: a 500 on GET /v1/validations/{id})
    from dosing.runs.scenario import Scenario
    from dosing.validation import failure, validation_report
    from solver.full import simulate
    from solver.gel import preset

    run = simulate("ANB", 302.0, 308.0, until=1e-3, grid="lagrangian", n=20)
    scs = [Scenario(preset("ANB"), 302.0, 308.0, settings=s) for s in PAPER.rungs()]
    rep = validation_report(scs, [run, run], float(run.radius[0]), 1.0, None)
    assert all("never reaches 1" in e["error"] and "time" not in e for e in rep.runs)
    assert rep.time is None and "never reaches 1" in failure(rep)
