"""The planner's direct truth (issue 12): settings, keys, the three-part uncertainty, the
missing prior of an unmeasured gel, schedules on the same truth.  Fast tests use the fake
solver (tests/dosing_fakes.py); the slow ones run the moving grid for the acceptance numbers.
"""

from __future__ import annotations

import json
import math
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
from dosing_fakes import ELL_C, ELL_ORDER, MOVING_C, FakeSolver, exact_time

from dosing import DoseRequest, Planner, ScheduleRequest
from dosing.runs.scenario import GRIDS, LADDER, PAPER, Scenario, SolverSettings
from dosing.truth import DELAYED_NS, Uncertainty, delayed_settings
from dosing.units import PhysicalConstants, radius_after_dose
from dosing.validation import NO_PRIOR_ESTIMATE, front_prior
from solver import HHT
from solver.equilibrium import nearest_stable
from solver.errors import ParameterError

SMOOTH = {"gel": "HHT", "t_start": 304.0, "t_end": 307.6}  # the classifier says smooth
FRONT = {"gel": "ANB", "t_start": 302.0, "t_end": 308.0}
CUSTOM = {"gel": {"base": "ANB", "omega": 300.0}, "t_start": 302.0, "t_end": 308.0}


@pytest.fixture
def fake() -> FakeSolver:
    return FakeSolver()


@pytest.fixture
def planner(tmp_path: Path, fake: FakeSolver):
    p = Planner(cache_path=tmp_path / "c.sqlite", executor=ThreadPoolExecutor(2), solver=fake)
    yield p
    p.close()
    p.jobs.executor.shutdown()


def test_grid_names_are_the_solver_registry() -> None:
    from solver.full.grids import GRIDS as REGISTRY

    assert GRIDS == tuple(REGISTRY)


def test_direct_settings_defaults_and_rungs() -> None:
    s = SolverSettings()
    assert (s.method, s.grid, s.n, s.rtol, s.interfacial_length) == (
        "direct", "moving", 400, 1e-5, 1e-4)
    assert s.direct and s.auto_length
    assert [(r.grid, r.n, r.interfacial_length) for r in s.rungs()] == [
        ("moving", 400, 1e-4), ("moving", 200, 1e-4)]
    # the ladder keeps issue 8's defaults; the paper's model keeps the Eulerian N = 400
    assert (LADDER.grid, LADDER.n, LADDER.interfacial_length, len(LADDER.rungs())) == (
        "lagrangian", 800, 0.005, 3)
    assert (PAPER.grid, PAPER.n, PAPER.regularized, PAPER.direct) == ("eulerian", 400, False,
                                                                      False)
    with pytest.raises(ParameterError, match="settings.method"):
        SolverSettings(method="guess")
    with pytest.raises(ParameterError, match="settings.interfacial_length"):
        SolverSettings(interfacial_length=1e-6)
    with pytest.raises(ParameterError, match="settings.n"):
        SolverSettings(n=30).rungs()  # its check would have 15 cells


def test_bead_sets_its_own_interfacial_length() -> None:
    """ell = xi_dry / a_d: 4 nm on a 50 um dry bead is 8e-5, its range 2-8 nm 4e-5-1.6e-4."""
    req = DoseRequest(**FRONT, dose_fraction=0.3, dry_radius_um=50.0)
    assert req.settings.interfacial_length == pytest.approx(8e-5, rel=1e-12)
    assert req.interfacial_range == pytest.approx((4e-5, 1.6e-4), rel=1e-12)
    bare = DoseRequest(**FRONT, dose_fraction=0.3)
    assert bare.settings.interfacial_length == 1e-4 and bare.interfacial_range is None
    other = DoseRequest(**FRONT, dose_fraction=0.3, dry_radius_um=50.0,
                        constants=PhysicalConstants(mesh_length_nm=8.0))
    assert other.settings.interfacial_length == pytest.approx(1.6e-4, rel=1e-12)
    assert other.constants.mesh_length_range_nm == (4.0, 16.0)
    ladder = DoseRequest(**FRONT, dose_fraction=0.3, dry_radius_um=50.0, settings=LADDER)
    assert ladder.settings == LADDER and ladder.interfacial_range is None
    with pytest.raises(ParameterError, match="mesh_length_range_nm"):
        PhysicalConstants(mesh_length_nm=4.0, mesh_length_range_nm=(5.0, 8.0))


def test_key_holds_everything_that_changes_the_run() -> None:
    from solver.gel import preset

    base = Scenario(preset("ANB"), 302.0, 308.0, settings=SolverSettings())
    keys = {base.key()}
    for s in (SolverSettings(interfacial_length=8e-5), SolverSettings(n=800),
              SolverSettings(grid="lagrangian"), SolverSettings(rtol=1e-6),
              SolverSettings(method="ladder", interfacial_length=0.005, grid="moving", n=400)):
        keys.add(Scenario(preset("ANB"), 302.0, 308.0, settings=s).key())
    assert len(keys) == 6
    assert base.key_dict()["settings"]["method"] == "direct"


def test_validated_direct_answer_states_three_parts(planner, fake) -> None:
    """Fake: t(ell, n) = t0 (1 + 200 ell^1.5)(1 + 2 / n) on the moving grid."""
    req = DoseRequest(**SMOOTH, dose_fraction=0.5, dry_radius_um=50.0)
    ans = planner.dose(req)
    a0 = req.start_radius
    af = nearest_stable(HHT, 307.6, a0).stretch
    t0 = exact_time(a0, af, radius_after_dose(a0, 0.5), "lagrangian")
    ell = 8e-5

    def fake_t(e: float, n: int) -> float:
        return t0 * (1 + ELL_C * e**ELL_ORDER) * (1 + MOVING_C / n)

    v = ans.validation
    assert ans.model == "full" and ans.method == "direct" and v["method"] == "direct"
    assert ans.interfacial_length == pytest.approx(ell) and ans.bead_dry_radius_um == 50.0
    assert [e["role"] for e in v["runs"]] == ["truth", "check", "ell_range", "ell_range",
                                              *["model_form"] * len(DELAYED_NS)]
    assert ans.time == pytest.approx(fake_t(ell, 400), rel=2e-4)
    u = ans.uncertainty
    assert isinstance(u, Uncertainty)
    want = abs(fake_t(ell, 400) - fake_t(ell, 200)) / fake_t(ell, 400)
    assert u.numerical.relative == pytest.approx(want, rel=0.05)
    assert ans.error_estimate == pytest.approx(max(u.numerical.relative, 1e-5), rel=1e-12)
    assert u.interfacial_lengths == pytest.approx([4e-5, 1.6e-4])
    worst = max(abs(fake_t(e, 200) - fake_t(ell, 400)) for e in (4e-5, 1.6e-4)) / ans.time
    assert u.interfacial_length_range.relative == pytest.approx(worst, rel=0.05)
    # the ell = 0 lattice (fake: N-independent) is the model-form alternative
    assert u.delayed_transition_ns == list(DELAYED_NS)
    assert u.delayed_transition_spread == 0.0
    assert u.delayed_transition_time == pytest.approx(t0, rel=2e-4)
    assert u.delayed_transition_ratio == pytest.approx(u.delayed_transition_time / ans.time,
                                                       rel=1e-12)
    for part, word in ((u.numerical, "numerical"), (u.interfacial_length_range,
                                                    "interfacial length"),
                       (u.model_form, "model form")):
        assert part.text.startswith(word) and part.relative is not None
    assert "bead's own interfacial length" in ans.truth and "50 um" in ans.truth
    assert "Helmers" in u.model_form.text and "delayed-transition" in ans.error_explanation
    json.dumps(ans.to_dict())  # plain data all the way down
    from api.schemas import DoseTimeResponse

    out = DoseTimeResponse.model_validate(ans.to_dict())
    assert out.uncertainty.model_form.relative == pytest.approx(u.model_form.relative)
    # the model-form runs do not depend on the bead size: a second bead reuses them
    n_calls = len(fake.calls)
    planner.dose(DoseRequest(**SMOOTH, dose_fraction=0.5, dry_radius_um=20.0))
    assert all(c["interfacial_length"] > 0 for c in fake.calls[n_calls:])


def test_no_bead_size_stands_for_the_limit(planner, fake) -> None:
    ans = planner.dose(DoseRequest(**SMOOTH, dose_fraction=0.5))
    u = ans.uncertainty
    assert ans.interfacial_length == 1e-4 and ans.bead_dry_radius_um is None
    assert u.interfacial_length_range.relative is None
    assert "without a bead size" in u.interfacial_length_range.text
    assert "limit ell -> 0" in ans.truth
    assert [e["role"] for e in ans.validation["runs"]].count("ell_range") == 0


def test_unvalidated_front_answer_uses_the_direct_prior(planner, fake) -> None:
    ans = planner.dose(DoseRequest(**FRONT, dose_fraction=0.8))
    assert ans.model == "front-sharp" and ans.validation is None and not fake.calls
    assert ans.error_estimate == front_prior(0.8, "front-sharp-direct")
    assert "direct truth" in ans.error_explanation


def test_custom_gel_does_not_borrow_the_prior(planner, fake) -> None:
    req = DoseRequest(**CUSTOM, dose_fraction=0.5)
    ans = planner.dose(req)
    assert ans.validation is None or ans.model == "full"
    if ans.model != "full":
        assert ans.error_estimate == NO_PRIOR_ESTIMATE
        assert "no prior for this gel" in ans.error_explanation
        assert "Ask for a validation" in ans.error_explanation
        prior = f"{100 * front_prior(0.5, 'front-sharp-direct'):.0f}%"
        assert f"within {prior}" not in ans.error_explanation
    # ANB itself keeps its prior
    assert planner.dose(DoseRequest(**FRONT, dose_fraction=0.5)).error_estimate == front_prior(
        0.5, "front-sharp-direct")


def test_schedule_runs_the_protocol_on_the_direct_truth(planner, fake) -> None:
    req = ScheduleRequest(**FRONT, doses=[0.3, 0.3], rests=[0.2], dry_radius_um=50.0)
    ans = planner.schedule(req)
    runs = [c for c in fake.calls if c["protocol"] and len(c["protocol"]) > 1]
    assert runs and all(c["grid"] == "moving" and c["n"] == 400
                        and math.isclose(c["interfacial_length"], 8e-5) for c in runs)
    assert ans.method == "direct" and ans.interfacial_length == pytest.approx(8e-5)
    assert "bead's own" in ans.truth and "same truth" in ans.note


def test_cli_dose_json_has_the_new_fields(capsys, tmp_path: Path) -> None:
    from api.cli import main

    assert main(["dose", "--gel", "ANB", "--t-start", "302", "--t-end", "308", "--fraction",
                 "0.8", "--dry-radius-um", "50", "--mesh-length-nm", "2", "--json",
                 "--cache", str(tmp_path / "c.sqlite")]) == 0
    out = json.loads(capsys.readouterr().out)
    # not validated: no truth parts, the envelope's parts only (issue 36)
    assert out["method"] == "direct" and "model_form" not in out["uncertainty"]
    assert {"reduction", "timescale", "front_law"} <= set(out["uncertainty"])
    assert out["interfacial_length"] == pytest.approx(4e-5) and out["bead_dry_radius_um"] == 50


# ---------------------------------------------------------------------- real runs (slow)

@pytest.fixture
def real_planner(tmp_path: Path):
    p = Planner(cache_path=tmp_path / "real.sqlite", executor=ThreadPoolExecutor(2))
    yield p
    p.close()


@pytest.mark.slow
def test_hht_small_doses_have_a_numerical_bound_below_10_percent(real_planner) -> None:
    """Issue 12: HHT 10/20/30 % of a 50 um bead, validated: numerical bound <= 10 % each
    (measured 0.08-0.10 %, benchmarks/planner_truth.py --section small), the ell-range and
    model-form parts stated separately.  The runs are shared: ~1 min in all."""
    for f in (0.3, 0.2, 0.1):
        ans = real_planner.dose(DoseRequest("HHT", 304.0, 308.0, dose_fraction=f,
                                            dry_radius_um=50.0), validate=True)
        u = ans.uncertainty
        assert ans.interfacial_length == pytest.approx(8e-5)
        assert u.numerical.relative <= 0.10, (f, u.numerical.text)
        # the ell range matters for small doses: the time grows with ell (nucleation delay)
        lo, hi = u.interfacial_length_times
        assert lo < ans.validation["time"] < hi and u.interfacial_length_range.relative > 0
        # the delayed transition comes later (6-9x at these doses) and its N-spread is stated
        # (N-independent at large doses: 1.5 % at 80 %, docs/moving_mesh.md; up to ~9 % here)
        assert u.delayed_transition_ratio > 1.0 and u.delayed_transition_spread is not None
        assert u.delayed_transition_ns == list(DELAYED_NS)


def test_sweep_keeps_the_bead_ell_unresolved() -> None:
    from dosing.studies.sweep import SweepGrid

    grid = SweepGrid(t_ends=[308.0], dry_radii_um=[50.0], doses=[0.3], gels=["ANB"],
                     t_start=302.0, settings=SolverSettings())
    assert grid.settings["interfacial_length"] is None
    req = DoseRequest(**FRONT, dose_fraction=0.3, dry_radius_um=50.0, settings=grid.settings)
    assert req.settings.interfacial_length == pytest.approx(8e-5)


@pytest.mark.slow
@pytest.mark.parametrize("gel,t_start", [("ANB", 302.0), ("HHT", 304.0)])
def test_schedule_first_dose_is_the_single_dose_truth(real_planner, gel, t_start) -> None:
    """Issue 12 (one truth): the schedule's protocol check and shooting run the single dose's
    own model, so the corrected first actuation of [0.3, 0.3, 0.3] with rests [0.5, 0.5]
    equals the validated 30 % dose's truth within that truth's numerical bound (at ell =
    1e-3 to keep it short: measured 2e-6 (ANB) and 2e-5 (HHT) apart, bounds 4.9e-4 and
    2.3e-4; the bead's own ell: benchmarks/planner_truth.py --section schedule)."""
    settings = SolverSettings(interfacial_length=1e-3)
    single = real_planner.dose(DoseRequest(gel, t_start, 308.0, dose_fraction=0.3,
                                           dry_radius_um=50.0, settings=settings),
                               validate=True)
    ans = real_planner.schedule(ScheduleRequest(gel, t_start, 308.0, doses=(0.3, 0.3, 0.3),
                                                rests=(0.5, 0.5), dry_radius_um=50.0,
                                                settings=settings, check_protocol=True,
                                                correct=True))
    first = ans.corrected["actuation_times"][0]
    truth = single.validation.time
    num = single.uncertainty.numerical.relative
    assert num is not None, [r for r in single.validation.runs if "error" in r]
    assert abs(first / truth - 1.0) <= num, (first, truth)


def test_model_form_runs_are_recognised_and_nothing_else() -> None:
    """The planner starts these runs at a short horizon (dosing.planner.MODEL_FORM_REACH)."""
    from dosing.truth import is_model_form_run

    assert all(is_model_form_run(s) for s in delayed_settings(SolverSettings()))
    paper_lattice = SolverSettings(grid="lagrangian", n=400, interfacial_length=0.0)
    assert not any(is_model_form_run(s) for s in (SolverSettings(), PAPER, LADDER,
                                                   paper_lattice))
