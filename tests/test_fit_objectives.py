"""Swelling fits with a stated objective and noise model (issue 27, item 3).

SYNTHETIC STAND-IN, NOT THE PUBLISHED DATA: the Hirotsu et al. 1987 points (the paper's
fig. 3b) are not recoverable from /work/shared/paper (the figure's data file
Figs/Fig3b_Eql_Hirotsu is not shipped) and this machine has no network beyond package
registries, so no test here uses them and none claims to.  Every Hirotsu acceptance check
runs on synthetic data from the paper's HHT gel (35 points, 1% size noise, 0.05 K
temperature noise, dry radius 41.27 in an arbitrary unit), which has the same trouble: the
collapsed branch sits at lambda = 1.0007-1.003, so 1% noise puts points below the dry size.
The checks: the 2 % dry-size rule (test_default_fit_keeps_every_point_within_two_noise_
widths_of_dry), the temperature objective's rms within 1.05x of the generating parameters'
(test_temperature_objective_reaches_its_minimum), the 304 -> 308 K, 80 % dose time under
both objectives with the disagreement flagged (test_dose_time_under_both_objectives).
"""

from __future__ import annotations

import numpy as np
import pytest

from dosing.fits.gel import compare_chi_models, dose_under_objectives, fit_swelling
from dosing.fits.uncertainty import dose_time
from solver.fit.equilibrium import judge
from solver.fit.synthetic import synthetic_swelling
from solver.gel import HHT

SCALE = 41.27


@pytest.fixture(scope="module")
def data():
    return synthetic_swelling(HHT, n=35, scale=SCALE, seed=5)


@pytest.fixture(scope="module")
def orth(data):
    return fit_swelling(data, profile=("scale",))


@pytest.fixture(scope="module")
def temp(data):
    return fit_swelling(data, objective="temperature")


def test_default_fit_keeps_every_point_within_two_noise_widths_of_dry(orth) -> None:
    x = orth.extra
    assert x["objective"] == "orthogonal"
    assert x["max_below_dry_relative"] <= 0.02 + 1e-9  # 2 x the stated 1% size noise
    assert orth.parameters["scale"] <= x["dry_size_bound"]["upper"] * (1 + 1e-9)
    # named for what it is: an orthogonal misfit, not a temperature residual
    assert "rms_residual_K" not in x and x["rms_orthogonal_K"] < 0.1
    assert x["rms_temperature_residual_K"] > 0.5  # the paper's residual is far larger
    # judged by chi-square under the stated noise: consistent with it (p > 1%)
    assert x["chi2_p_value"] > 0.01 and x["aic"] == pytest.approx(x["chi2"] + 12.0)


def test_profile_interval_beside_the_linearised_one(orth) -> None:
    prof = orth.extra["profile_intervals"]["scale"]
    lo, hi = prof["interval"]
    llo, lhi = orth.intervals["scale"]
    assert lo < orth.parameters["scale"] < hi
    # same order as the linearised width (a quadratic profile gives the same interval)
    assert 0.5 < (hi - lo) / (lhi - llo) < 2.0
    assert "own implementation" in prof["method"]


def test_temperature_objective_reaches_its_minimum(data, temp) -> None:
    """The paper's objective: every point above the dry size, and a temperature rms no
    worse than 1.05x the true gel's at the largest dry size the objective allows."""
    x = temp.extra
    assert x["objective"] == "temperature" and x["points_below_dry"] == 0
    truth = judge(data, (HHT, float(data.size.min()) * (1 - 1e-6)), 0.05, 0.01, 6)
    assert x["rms_temperature_residual_K"] <= 1.05 * truth["rms_temperature_residual_K"]


def test_dose_time_under_both_objectives(data, orth, temp) -> None:
    """Hirotsu acceptance, on the synthetic stand-in: the HHT 304 -> 308 K, 80 % dose time is
    reported under both objectives and their disagreement is flagged.  The orthogonal fit's
    interval covers the true dose time; the paper's objective leaves the collapsed branch
    to a gel whose 308 K equilibrium holds 45 % of the fluid, so under it the dose is never
    reached: a disagreement no interval of either fit states."""
    out = dose_under_objectives(data, 304.0, 308.0, 0.8,
                                fits={"orthogonal": orth, "temperature": temp})
    true_t = dose_time(HHT, 304.0, 308.0, "swollen", 0.8, True)
    lo, hi = out["orthogonal"]["interval"]
    assert lo < true_t < hi and out["orthogonal"]["model"] == "front-sharp"
    t = out["temperature"]
    assert t["reached"] is False and t["time"] is None and 0.3 < t["max_fraction"] < 0.8
    assert str(round(t["max_fraction"], 3))[:4] in t["note"]
    assert out["disagree"] is True and "disagree" in out["note"] and "never" in out["note"]


def test_a_smooth_jump_gets_the_full_solvers_time_and_a_one_sided_flag(data, orth,
                                                                        temp) -> None:
    """Where the front model does not apply (the temperature objective's gel crosses no
    coexistence on 304 -> 308 K), a reachable dose (30 %) gets the full solver's time,
    without an interval; the flag compares it with the orthogonal fit's interval."""
    out = dose_under_objectives(data, 304.0, 308.0, 0.3,
                                fits={"orthogonal": orth, "temperature": temp})
    t, o = out["temperature"], out["orthogonal"]
    assert t["model"] == "full" and t["time"] > 0 and t["interval"] is None
    assert "front model does not apply" in t["note"]
    lo, hi = o["interval"]
    assert out["disagree"] is (not lo <= t["time"] <= hi)
    assert out["ratio"] == pytest.approx(o["time"] / t["time"])


@pytest.mark.parametrize(("a", "b", "flag"), [
    ((1.0, [0.9, 1.1]), (1.3, [1.2, 1.4]), True),    # intervals apart
    ((1.0, [0.9, 1.1]), (1.05, [1.0, 1.2]), False),  # overlapping
    ((1.0, [0.9, 1.1]), (1.3, None), True),          # one-sided: outside
    ((1.0, [0.9, 1.1]), (1.05, None), False),        # one-sided: inside
    ((1.0, None), (1.3, None), None),                # no interval: not decided
    # the review's real Hirotsu points (honest-answers.md sec. 4): a 3.0x gap is not
    # made to agree by the temperature objective's useless interval
    ((0.0249, [0.0203, 0.0306]), (0.0747, [0.0033, 1.70]), True),
])
def test_disagreement_rule(a, b, flag) -> None:
    from dosing.fits.gel import _disagreement

    out = _disagreement({"time": a[0], "interval": a[1]}, {"time": b[0], "interval": b[1]})
    assert out["disagree"] is flag
    assert ("disagree (" in out["note"]) == bool(flag)


def test_not_pinned_names_the_timescale_and_a_dry_size_at_its_bound(orth) -> None:
    words = " ".join(orth.extra["not_pinned"])
    assert "timescale" in words and "kinetics fit" in words
    if orth.extra["dry_size_bound"]["at_bound"]:
        assert "dry size" in words


def test_a_given_dry_size_is_kept(data) -> None:
    res = fit_swelling(data, dry_size=SCALE, fixed={"omega": 720.0})
    assert res.parameters["scale"] == pytest.approx(SCALE, rel=1e-12)
    assert res.intervals["scale"] is None


def test_aic_bic_of_nested_chi_models(data) -> None:
    """HHT's chi depends on the polymer fraction (A1, B1 != 0): dropping chi1 must cost."""
    cmp = compare_chi_models(data, fixed={"omega": 720.0})
    m = cmp["models"]
    assert m["full"]["k"] == 5 and m["a1=b1=0"]["k"] == 3
    assert m["a1=b1=0"]["chi2"] > m["full"]["chi2"]
    assert cmp["best_aic"] in ("full", "b1=0")
    assert m["a1=b1=0"]["delta_aic"] > 2.0


@pytest.mark.slow
def test_dose_time_interval_coverage_over_50_seeds() -> None:
    """95% dose-time intervals (delta method from the orthogonal fit, front-sharp model) of
    HHT 304 -> 308 K, 80%, cover the true dose time in 90-99% of 50 noise seeds.  Each seed
    is one local fit warm-started at the generating parameters (the global search's optimum,
    checked on seed 0; a tenth of its cost); all 50 seeds kept (binomial argument in
    tests/test_fit_equilibrium.py)."""
    from dosing.fits.uncertainty import dose_time_interval
    from solver.fit import fit_gel

    true_t = dose_time(HHT, 304.0, 308.0, "swollen", 0.8, True)
    truth = {"omega": HHT.omega, "a0": HHT.a0, "b0": HHT.b0, "a1": HHT.a1, "b1": HHT.b1,
             "scale": SCALE}
    hits, n = 0, 0
    for seed in range(50):
        d = synthetic_swelling(HHT, n=35, scale=SCALE, seed=100 + seed)
        res = fit_swelling(d, start=truth)  # warm: one local fit (the scale clipped to
        if seed == 0:                       # its data bound), the global search's optimum
            glob = fit_swelling(d, n_starts=3)
            assert glob.extra["chi2"] == pytest.approx(res.extra["chi2"], rel=1e-6)
        iv = dose_time_interval({"swelling": {"fit": res.to_dict()}}, fit_gel(res), 304.0,
                                308.0, "swollen", 0.8, True)
        n += 1
        if iv.get("time") is not None and iv["time"][0] <= true_t <= iv["time"][1]:
            hits += 1
    # measured 50/50 on these seeds; over 200 seeds 195/200 = 0.975, inside the issue's
    # 90-99% (`python benchmarks/fit.py --coverage 200`, z-scores sd 0.86): at a true 97.5%
    # coverage 50/50 has probability 0.975^50 = 28%, so the upper bound is not asserted on
    # 50 seeds (it would fail a calibrated interval that often); the lower bound is
    assert hits / n >= 0.90, hits
    assert np.isfinite(true_t)


def test_http_swelling_fit_states_the_dose_under_both_objectives(data, tmp_path,
                                                                  monkeypatch) -> None:
    from api.fit_schemas import SwellingFitRequest
    from api.routers.fit import _swelling

    monkeypatch.setenv("THERMOGEL_GELS", str(tmp_path / "gels"))
    body = SwellingFitRequest(temperature_K=data.temperature.tolist(),
                              radius=data.size.tolist(), dose_jump=[304.0, 308.0],
                              objective="orthogonal", n_starts=2)  # both objectives' fits
    rep = _swelling(None, body)
    dj = rep["dose_time_by_objective"]
    assert dj["orthogonal"]["time"] > 0 and "temperature" in dj and "disagree" in dj
    assert rep["objective"] == "orthogonal" and rep["not_pinned"]


def test_a_disagreement_widens_a_saved_gels_interval() -> None:
    """Issue 36: a gel saved from a fit whose objectives disagreed carries the spread."""
    import math

    from dosing.fits.uncertainty import objective_spread

    rec = {"swelling": {"fit": {"dose_time_by_objective": {"disagree": True, "ratio": 1 / 3}}}}
    assert objective_spread(rec) == pytest.approx(math.log(3.0))
    rec["swelling"]["fit"]["dose_time_by_objective"]["disagree"] = False
    assert objective_spread(rec) == 0.0 and objective_spread({}) == 0.0
