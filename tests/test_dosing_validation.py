"""The planner's numbers on the real solvers: the paper's (sec. Application, issue 5) with
interfacial_length 0, and the regularized truth (issue 8) by default.

Paper's front model (started from the initial equilibrium alone, no full-solver input): ANB
302->308 K, 80 %: measured 0.0950 against the paper's 0.092 (+3.2 %); HHT 304->308 K:
0.1253 against 0.123 (+1.9 %).  Both within the issue's 5 %.  The paper's dashed curves
started from the full solution and integrated a and R_f separately, which does not
conserve solid (../shared/DESIGN.md); a conservative model gives slightly later times.

Regularized truth: the limit ell -> 0 of the 80 % dose, from the ladder ell = 0.01 ...
0.000625 of docs/interfacial.md sec. 7 (each grid-converged to 1e-4): ANB 0.0777, HHT
0.0723 (bracket 0.0700-0.0779).  The sharp-interface front model gives 0.0762 / 0.0724.
"""


import json

import pytest

from api.cli import main
from dosing import DoseRequest, Planner
from dosing.runs.scenario import LADDER, PAPER
from dosing.validation import front_prior

ANB80 = {"gel": "ANB", "t_start": 302.0, "t_end": 308.0, "dose_fraction": 0.8}
HHT80 = {"gel": "HHT", "t_start": 304.0, "t_end": 308.0, "dose_fraction": 0.8}


@pytest.fixture(scope="module")
def cache_path(tmp_path_factory):
    return tmp_path_factory.mktemp("v") / "cache.sqlite"


@pytest.fixture(scope="module")
def planner(cache_path):
    from concurrent.futures import ThreadPoolExecutor

    p = Planner(cache_path=cache_path, executor=ThreadPoolExecutor(2))
    yield p
    p.close()
    p.jobs.executor.shutdown()


@pytest.mark.parametrize("kw,paper", [(ANB80, 0.092), (HHT80, 0.123)])
def test_front_model_80_percent_within_5_percent(planner, kw: dict, paper: float) -> None:
    ans = planner.dose(DoseRequest(**kw, settings=PAPER))
    assert ans.model == "front" and ans.behaviour == "front"
    assert ans.time == pytest.approx(paper, rel=0.05)
    assert ans.error_estimate == front_prior(0.8, "front") and ans.validation is None


# the limit ell -> 0 (module doc) is known to 0.2 % (ANB) and about 4 % (HHT, its bracket);
# the issue asks the sharp model within 3 % of it
@pytest.mark.parametrize("kw,limit,tol", [(ANB80, 0.0777, 0.03), (HHT80, 0.0723, 0.03)])
def test_default_answer_is_the_sharp_front_model(planner, kw: dict, limit: float,
                                                 tol: float) -> None:
    ans = planner.dose(DoseRequest(**kw, settings=LADDER))
    assert ans.model == "front-sharp" and ans.interfacial_length == 0.005
    assert ans.time == pytest.approx(limit, rel=tol)
    assert ans.error_estimate == front_prior(0.8, "front-sharp") and ans.validation is None


def test_dimensional_answer_for_a_50_um_bead_in_water(planner) -> None:
    from dosing import PhysicalConstants, timescale

    c = PhysicalConstants(viscosity_pa_s="water")
    ans = planner.dose(DoseRequest(**ANB80, dry_radius_um=50.0, constants=c))
    tau = timescale(50.0, 308.0, c, omega=100.0)  # ANB's Omega: Omega_p = Omega Omega_f
    assert ans.timescale_seconds == pytest.approx(tau.seconds, rel=1e-12)
    assert ans.seconds == pytest.approx(ans.time * tau.seconds, rel=1e-12)
    assert 1.0 < ans.seconds < 1.5  # 0.0762 x 15.89 s (eta of water at 308 K: 0.72 mPa s)
    assert ans.timescale_formula == tau.formula and "50 um" in ans.timescale_formula
    assert ans.final_radius_um == pytest.approx(50.0 * ans.final_radius, rel=1e-12)
    assert ans.expelled_volume_ul == pytest.approx(0.8 * ans.stored_volume_ul, rel=1e-12)


def _at_radius(kw: dict, radius: float) -> DoseRequest:
    """The dose whose final radius is the paper's printed one (1.47 ANB, 1.67 HHT)."""
    a0 = DoseRequest(**kw).start_radius
    return DoseRequest(**{**kw, "dose_fraction": (a0**3 - radius**3) / (a0**3 - 1.0)},
                       settings=PAPER)


# Full solver, N = 400.  The paper read its times at the printed radii 1.47 and 1.67; the
# exact 80 % radii are 1.4750 and 1.6662.  Measured (Eulerian / Lagrangian): ANB at 1.47
# 0.0892 / 0.1161, at 1.4750 0.0880 / 0.1147; HHT at 1.67 0.1354 / 0.2210, at 1.6662
# 0.1363 / 0.2222.  The issue asks 1 % (ANB) and 2 % (HHT) of the paper on its grid; the
# Lagrangian references 0.117 and 0.221 are the full-solver issue's, read at 1.47 / 1.67.
@pytest.mark.slow
@pytest.mark.parametrize("kw,radius,eulerian,tol,lagrangian", [
    (ANB80, 1.47, 0.089, 0.01, 0.117), (HHT80, 1.67, 0.137, 0.02, 0.221)])
def test_validation_reports_both_grids_and_their_spread(planner, kw: dict, radius: float,
                                                        eulerian: float, tol: float,
                                                        lagrangian: float) -> None:
    ans = planner.dose(_at_radius(kw, radius), validate=True)
    assert ans.final_radius == pytest.approx(radius, rel=1e-12)
    v = ans.validation
    assert v["model"] == "paper" and [e["grid"] for e in v["runs"]] == ["eulerian", "lagrangian"]
    assert v["settings"]["n"] == 400 and v["interfacial_length"] == 0.0
    assert v["time"] == pytest.approx(eulerian, rel=tol)
    t_l = v["runs"][1]["time"]
    assert t_l == pytest.approx(lagrangian, rel=0.01)
    assert v["grid_spread"] == pytest.approx((t_l - v["time"]) / v["time"], rel=1e-12)
    assert v["grid_spread"] > 0.25  # the ill-posed front regime
    gaps = [abs(ans.time - t) / ans.time for t in (v["time"], t_l)]
    assert ans.error_estimate == pytest.approx(max(gaps), rel=1e-12)
    for words in ("disagree", "interfacial energy", "between"):
        assert words in ans.error_explanation
    # the paper: the dose volume from the front time is out by < 5 % (about 1 % for ANB)
    assert abs(v["front_volume_error"]) < 0.05
    # the exact 80 % dose reads the same runs at the slightly larger radius: earlier for
    # ANB (0.0880, 1.1 % below the paper's 0.089 read at the rounded radius)
    exact = planner.dose(DoseRequest(**kw, settings=PAPER), validate=True).validation
    assert exact["runs"][0]["scenario_key"] == v["runs"][0]["scenario_key"]
    assert exact["time"] == pytest.approx(eulerian, rel=0.015)


@pytest.mark.slow
@pytest.mark.parametrize("settings,model", [(PAPER, "front"), (LADDER, "front-sharp")])
def test_prior_covers_the_measured_front_errors(planner, settings, model: str) -> None:
    """The unvalidated estimate (validation.PRIOR_GAPS) bounds what calibrate measures."""
    for kw in (ANB80, HHT80):
        # the largest dose first: runs stop at their dose, and a run that reached 90 %
        # serves every smaller dose of the jump (one dimensionless run per jump)
        for f in (0.9, 0.7, 0.5, 0.3, 0.1):
            ans = planner.dose(DoseRequest(**{**kw, "dose_fraction": f}, settings=settings),
                               validate=True)
            assert ans.model == model
            assert ans.error_estimate <= front_prior(f, model), (kw["gel"], f)


# module doc: the limit from the finer ladder of docs/interfacial.md (ANB to 0.2 %, HHT only
# bracketed, 0.0700-0.0779); the default ladder stops at ell = 0.00125, so its limit must
# land within its own error bound of those values
@pytest.mark.slow
@pytest.mark.parametrize("kw,limit,known", [(ANB80, 0.0777, 0.0002), (HHT80, 0.0723, 0.004)])
def test_ladder_limit_matches_the_convergence_study(planner, kw: dict, limit: float,
                                                    known: float) -> None:
    v = planner.dose(DoseRequest(**kw, settings=LADDER), validate=True).validation
    assert v["model"] == "regularized" and "nucleates" in v["limit"]["method"]
    assert [e["n"] for e in v["runs"]] == [800, 1600, 3200]
    assert abs(v["time"] - limit) <= v["limit"]["error"] + known


@pytest.mark.slow
def test_cli_validate_json_has_the_full_solver_time(planner, cache_path, capsys) -> None:
    want = planner.dose(DoseRequest(**ANB80, settings=LADDER), validate=True).validation["time"]
    assert main(["dose", "--gel", "ANB", "--t-start", "302", "--t-end", "308", "--fraction",
                 "0.8", "--validate", "--json", "--validation-method", "ladder",
                 "--cache", str(cache_path)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["model"] == "front-sharp" and out["validation"]["time"] == want
    assert out["interfacial_length"] == 0.005 and "limit ell -> 0" in out["truth"]
    assert {"time", "seconds", "final_radius"} <= set(out)


@pytest.mark.slow
def test_smooth_jump_is_answered_by_the_full_solver(planner) -> None:
    req = DoseRequest("HHT", 304.0, 307.6, dose_fraction=0.5, settings=PAPER)
    ans = planner.dose(req)
    assert ans.model == "full" and ans.behaviour == "smooth"
    assert ans.validation["time"] == ans.time
    # smooth cases: the two grids agree to ~1e-5 (issue 3: 3e-5), so does the estimate
    assert ans.validation["grid_spread"] < 1e-4 and ans.error_estimate < 1e-4
    assert "agree" in ans.error_explanation
    # the regularized truth: the term changes a(t) by 9e-4 at ell = 0.005 (order 1.7,
    # docs/interfacial.md sec. 7), so its limit is the paper's model's time to ~1e-4
    reg = planner.dose(DoseRequest("HHT", 304.0, 307.6, dose_fraction=0.5, settings=LADDER))
    assert reg.model == "full" and reg.validation["model"] == "regularized"
    assert reg.time == pytest.approx(ans.time, rel=3e-4)
    assert reg.error_estimate < 1e-3
