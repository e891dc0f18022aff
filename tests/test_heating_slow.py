"""The front model under slow heating (solver/front/slow.py) and the planner's use of it
(dosing/heating/reduced.py): limits, numerics, applicability and the answer."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from types import SimpleNamespace

import numpy as np
import pytest

import solver.front.slow as slow
from dosing.planner import Planner
from dosing.request import DoseRequest
from dosing.units import PhysicalConstants
from solver.equilibrium import equilibrium
from solver.errors import NotApplicableError
from solver.front.sharp import sharp_front_trajectory
from solver.gel import preset
from solver.heating import Bath, Hold, Program, Ramp, Released

FRACTIONS = (0.3, 0.5, 0.8, 0.9)
TAU_50UM = 2205.0  # s: tau of a 50 um dry bead at 308 K


def _targets(gel, t0):
    a0 = equilibrium(gel, t0, "swollen").stretch
    return tuple(Released(f).radius(a0) for f in FRACTIONS)


@pytest.mark.parametrize("name,t0", [("ANB", 302.0), ("HHT", 304.0)])
def test_a_jump_is_the_sharp_front_model(name, t0):
    """With T jumping to 308 K (a ramp of 1e12 K per tau) the bead nucleates at once and the
    front stage is eq. FrontEvolve with the sharp front condition: the step answer's model
    to 1e-5 (the thin-shell start at 1e-4 of the radius)."""
    gel = preset(name)
    tg = _targets(gel, t0)
    res = slow.slow_front_trajectory(gel, t0, Program((Ramp(308.0, 1e12),)), targets=tg)
    ref = sharp_front_trajectory(gel, t0, 308.0)
    for a in tg:
        assert res.hits[a] == pytest.approx(ref.time_to_radius(a), rel=1e-5)
    assert res.t_nucleation < 1e-10


@pytest.mark.parametrize("prog", [
    Program((Ramp(308.0, 0.5 / 60 * TAU_50UM),), mobility="kT"),
    Program((Bath(308.0, 30.0 / TAU_50UM, 50.0),), mobility="kT")])
def test_numerical_error_is_below_its_stated_bound(prog, monkeypatch):
    """The answer's numerical part (dosing.heating.reduced.NUMERICAL = 1e-5): rtol 1e-8 ->
    1e-10, the thin-shell start 1e-4 -> 1e-5, the level tables' degree 12 -> 20 and the
    nucleation curve's 24 -> 48 and 200 -> 800 stretches each move HHT's dose times by at
    most 2.4e-6
    (measured), so the stated bound holds twice over."""
    from dosing.heating.reduced import NUMERICAL

    gel = preset("HHT")
    tg = _targets(gel, 304.0)
    base = slow.slow_front_trajectory(gel, 304.0, prog, targets=tg)
    runs = [slow.slow_front_trajectory(gel, 304.0, prog, targets=tg, rtol=1e-10)]
    monkeypatch.setattr(slow, "THIN_SHELL", 1e-5)
    runs.append(slow.slow_front_trajectory(gel, 304.0, prog, targets=tg))
    monkeypatch.setattr(slow, "THIN_SHELL", 1e-4)
    monkeypatch.setattr(slow, "LEVEL_DEGREE", 20)
    runs.append(slow.slow_front_trajectory(gel, 304.0, prog, targets=tg))
    monkeypatch.setattr(slow, "LEVEL_DEGREE", 12)
    monkeypatch.setattr(slow, "NUCLEATION_GRID", 48)
    monkeypatch.setattr(slow, "EDGE_GRID", 800)
    slow.nucleation_curve.cache_clear()
    runs.append(slow.slow_front_trajectory(gel, 304.0, prog, targets=tg))
    monkeypatch.setattr(slow, "NUCLEATION_GRID", 24)
    monkeypatch.setattr(slow, "EDGE_GRID", 200)
    slow.nucleation_curve.cache_clear()
    for r in runs:
        gaps = [abs(r.hits[a] / base.hits[a] - 1.0) for a in tg]
        assert max(gaps) < 0.5 * NUMERICAL


def test_slower_heating_releases_later_and_the_front_forms_nearer_the_onset():
    """Slower ramps reach each dose later and nucleate at a lower temperature (the bead has
    shrunk on the way, and a smaller stretch enters the coexistence region sooner)."""
    gel = preset("ANB")
    tg = _targets(gel, 302.0)
    runs = [slow.slow_front_trajectory(gel, 302.0, Program((Ramp(308.0, r / 60 * TAU_50UM),)),
                                       targets=tg) for r in (0.5, 5.0, 100.0)]
    for a in tg:
        times = [r.hits[a] for r in runs]
        assert times == sorted(times, reverse=True)
    temps = [r.temperature_nucleation for r in runs]
    assert temps == sorted(temps)
    assert all(r.diagnostics["a_nucleation"] < r.a0 for r in runs)


def test_below_the_transition_the_bead_follows_its_equilibrium():
    """ANB 296 -> 300 K at 0.01 K/min (one phase, no front): the uniform stage's lag stays
    within 0.5 % of the equilibrium radius for a 50 um bead (the full solver: 0.68 %)."""
    gel = preset("ANB")
    rate = 0.01 / 60 * TAU_50UM
    res = slow.slow_front_trajectory(gel, 296.0, Program((Ramp(300.0, rate),)), horizon=0.0)
    assert res.t_nucleation is None
    temps = 296.0 + rate * res.t
    eq = np.array([equilibrium(gel, float(x), "swollen").stretch for x in temps[::20]])
    assert np.max(np.abs(res.radius[::20] / eq - 1.0)) < 5e-3


def test_cooling_is_not_applicable():
    gel = preset("ANB")
    with pytest.raises(NotApplicableError):
        slow.slow_front_trajectory(gel, 302.0, Program((Hold(308.0, 0.01), Hold(302.0, 0.1))))


def test_until_steps_end_on_the_models_own_crossing():
    """'Hold until 30 % released' after a ramp ends when this model's run of the ramp alone
    reaches the 30 % radius."""
    gel = preset("ANB")
    a30 = _targets(gel, 302.0)[0]
    ramp = Ramp(308.0, 5.0 / 60 * TAU_50UM)
    alone = slow.slow_front_trajectory(gel, 302.0, Program((ramp,)), targets=(a30,))
    res = slow.slow_front_trajectory(gel, 302.0, Program((ramp, Hold(308.0, until=Released(0.3)),
                                                          Hold(308.0, 0.1))), targets=(a30,))
    assert res.ends[1] == pytest.approx(alone.hits[a30], rel=1e-6)  # the step sizes differ


# ----------------------------------------------------------------------------- the planner
# the paper's constants: tau = 2205 s, the table's (benchmarks/heating_reduced.py) 5 K/min
BEAD = {"gel": "ANB", "t_start": 302.0, "dry_radius_um": 50.0,
        "constants": PhysicalConstants.paper()}


@pytest.fixture(scope="module")
def real_planner(tmp_path_factory):
    with Planner(cache_path=tmp_path_factory.mktemp("p") / "c.sqlite",
                 executor=ThreadPoolExecutor(1)) as p:
        yield p


def test_a_ramp_dose_in_the_region_answers_from_the_reduced_model(real_planner):
    """No 202: the answer now, saying which model and why, with its error parts."""
    from dosing.answers import Answered

    req = DoseRequest(**BEAD, protocol=["Heat to 308 K at 5 K/min"], dose_fraction=0.8)
    out = real_planner.answer(req)
    assert isinstance(out, Answered)
    ans = out.answer
    assert ans.model == "front-slow-sharp"
    assert "inside the region" in ans.model_reason
    assert ans.uncertainty["model_form"].relative == 0.05
    # the truth (benchmarks/heating_reduced.py) is 231.4 s: the model's 226.6 s is 2.1 % early
    assert ans.seconds == pytest.approx(231.4, rel=0.05)
    assert ans.curve["released_fraction"][-1] > 0.79


@pytest.mark.parametrize("protocol,fraction,why", [
    (["Heat to 308 K at 5 K/min"], 0.1, "outside 30%-90%"),
    (["Bath at 308 K with a time constant of 30 s"], 0.3, "outside 50%-90%"),
    (["Heat to 308 K at 0.2 K/min"], 0.5, "slower than the measured"),
    (["Bath at 308 K with a time constant of 20 min"], 0.8, "longer than the measured"),
    (["Heat to 308 K at 5 K/min", "Hold at 308 K for 1 min", "Cool to 304 K at 5 K/min"], 0.8,
     "not one ramp or bath"),
    (["Heat to 306 K at 5 K/min", "Hold at 306 K for 30 min", "Heat to 308 K at 5 K/min"], 0.8,
     "not one ramp or bath"),
    ([{"step": "trace", "csv": "time (s),T (K)\n0,302\n72,308\n"}], 0.8, "measured trace"),
])
def test_outside_the_region_the_full_solver_answers(protocol, fraction, why):
    from dosing.heating.reduced import choose

    req = DoseRequest(**BEAD, protocol=protocol, dose_fraction=fraction)
    choice = choose(req, req.heating.program(2204.6), False)
    assert not choice.applies and why in choice.why


def test_holds_after_the_heating_stay_in_the_region():
    from dosing.heating.reduced import choose

    req = DoseRequest(**BEAD, protocol=["Bath at 308 K with a time constant of 30 s for 2 min",
                                        "Hold at 308 K until 80 % released"], dose_fraction=0.8)
    assert choose(req, req.heating.program(2204.6), False).applies


def test_the_region_edges_in_k_per_tau_and_tau():
    """The region measured at both timescales (benchmarks/heating_reduced.py, paper and
    gel-consistent constants): ramps from 10 K per tau (ANB's 30 % dose 4.9 % early at 9,
    8.1 % at 7.35), baths up to 0.17 tau (HHT's 90 % dose 4.6 %; 5.1 % at 0.19)."""
    from dosing.heating.reduced import BATH_MAX, RAMP_MIN, choose

    assert RAMP_MIN == 10.0 and BATH_MAX == 0.17
    for protocol, fraction, inside in (
            (["Heat to 308 K at 10.5 K/tau"], 0.3, True),
            (["Heat to 308 K at 9 K/tau"], 0.8, False),
            (["Bath at 308 K with a time constant of 0.165 tau"], 0.9, True),
            (["Bath at 308 K with a time constant of 0.19 tau"], 0.5, False)):
        req = DoseRequest(**BEAD, protocol=protocol, dose_fraction=fraction)
        choice = choose(req, req.heating.program(2204.6), False)
        assert choice.applies is inside, (protocol, choice.why)
        if not inside:  # the bead's own K/min or seconds beside the tau units
            unit = "K/min for this bead" if "Heat" in protocol[0] else "s for this bead"
            assert unit in choice.why, choice.why


def test_beads_under_50_um_and_no_bead_size_go_to_the_full_solver():
    from dosing.heating.reduced import choose

    for fields in ({**BEAD, "dry_radius_um": 20.0}, {"gel": "ANB", "t_start": 302.0}):
        req = DoseRequest(**fields, protocol=["Heat to 308 K at 500 K/tau"], dose_fraction=0.8)
        choice = choose(req, req.heating.program(None if "dry_radius_um" not in fields
                                                 else 353.0), False)
        assert not choice.applies and "interfacial length" in choice.why
    big = DoseRequest(**{**BEAD, "dry_radius_um": 100.0}, protocol=["Heat to 308 K at 5 K/min"],
                      dose_fraction=0.8)
    assert choose(big, big.heating.program(8818.0), False).applies


def test_validate_asks_for_the_full_solver():
    from dosing.heating.reduced import choose

    req = DoseRequest(**BEAD, protocol=["Heat to 308 K at 5 K/min"], dose_fraction=0.8)
    assert choose(req, req.heating.program(2204.6), False).applies
    assert not choose(req, req.heating.program(2204.6), True).applies


def test_until_hold_after_a_ramp_ends_at_the_reduced_dose_time(real_planner):
    """The issue's check on the reduced path: 'Hold at 308 K until 30 % released' after the
    ramp ends at the 30 % dose answer for the ramp alone, to every printed digit."""
    ramp = real_planner.dose(DoseRequest(**BEAD, protocol=["Heat to 308 K at 5 K/min"],
                                         dose_fraction=0.3))
    then = real_planner.dose(DoseRequest(**BEAD, protocol=[
        "Heat to 308 K at 5 K/min", "Hold at 308 K until 30 % released",
        "Hold at 308 K for 1 min"], dose_fraction=0.8))
    assert ramp.model == then.model == "front-slow-sharp"
    assert then.until_steps[0].end == ramp.time


def test_a_reduced_model_failure_falls_back_to_the_full_solver(monkeypatch):
    import dosing.heating.response as pdose
    from dosing.answers import Verdict
    from solver.errors import SolverError

    def boom(*a, **k):
        raise SolverError("the shell levels did not converge", {})

    monkeypatch.setattr(pdose, "reduced_dose", boom)
    monkeypatch.setattr(pdose, "_choice", lambda *a: Verdict(True, "inside"))
    req = DoseRequest(**BEAD, protocol=["Heat to 308 K at 5 K/min"], dose_fraction=0.8)
    fast, _, why = pdose._reduced_or_why(SimpleNamespace(solver=None), req, False, "auto")
    assert fast is None and "could not answer" in why


def test_wide_heatings_of_other_gels_answer():
    """Robustness beyond the table: HHT 300 -> 312 K at 18.4 K per tau (the Maxwell pair's
    continuation over 12 K falls back to exact pairs) and a power-law permeability."""
    from solver.gel import ANB, Gel, Permeability

    hht = preset("HHT")
    tg = _targets(hht, 300.0)
    res = slow.slow_front_trajectory(hht, 300.0, Program((Ramp(312.0, 18.4),)), targets=tg)
    times = [res.hits[a] for a in tg]
    assert all(np.isfinite(times)) and times == sorted(times)
    pw = Gel(300.0, ANB.a0, ANB.b0, ANB.a1, ANB.b1, permeability=Permeability("power", 2.0))
    tg = _targets(pw, 302.0)
    res = slow.slow_front_trajectory(pw, 302.0, Program((Ramp(308.0, 100.0),)), targets=tg)
    assert all(np.isfinite([res.hits[a] for a in tg]))
