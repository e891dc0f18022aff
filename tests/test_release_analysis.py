"""Release data as a pharmaceutics lab analyses it (issue 38): the empirical model zoo, f1/f2
with the FDA rules and Shah's bootstrap, measured against predicted; every way in."""

from __future__ import annotations

import asyncio
import json
import math
import time
from pathlib import Path

import httpx
import numpy as np
import pytest

from api.cli import main
from api.http import create_app
from dosing.analysis import MODELS, fit_empirical, from_arrays, read_profile
from dosing.analysis.similarity import (
    bootstrap_draws,
    compare,
    f2_value,
    fda_f2,
    measured_against_predicted,
    points_used,
)
from solver.errors import ParameterError
from solver.solute.crank import crank_sphere

DATA = Path(__file__).parent / "data" / "release"
SHAH = {k: DATA / f"shah1998_{k}.csv" for k in ("ref", "test1", "test4", "test5")}
WEIBULL_T = np.array([5, 10, 15, 20, 30, 45, 60, 90, 120, 150, 180, 240.0])  # min


def weibull_profile(seed: int, td: float = 30.0, b: float = 0.75, noise: float = 1.0):
    """A synthetic Weibull release (percent, minutes) with ``noise`` points of noise."""
    rng = np.random.default_rng(seed)
    f = 100.0 * (1.0 - np.exp(-((WEIBULL_T / td) ** b))) + noise * rng.standard_normal(
        WEIBULL_T.size)
    return from_arrays(WEIBULL_T, f, time_unit="min", released_unit="percent")


# ------------------------------------------------------------------ the empirical models
@pytest.mark.parametrize("seed", range(5))
def test_weibull_curve_is_picked_by_aic_and_recovered(seed: int) -> None:
    """Acceptance: Td 30 min, b 0.75, 1 point of noise: Weibull is the best by AIC, Td within
    5 %, b within 0.04; every model has aic and r2_adjusted."""
    res = fit_empirical(weibull_profile(seed))
    assert res.best == "weibull", res.ranked
    w = res.fits["weibull"]
    assert w.parameters["Td"] == pytest.approx(30.0, rel=0.05)
    assert abs(w.parameters["b"] - 0.75) < 0.04
    assert w.units == {"Td": "min", "b": "1", "Ti": "min"}
    lo, hi = w.intervals["Td"]
    assert lo < w.parameters["Td"] < hi
    assert set(res.fits) == set(MODELS) and not res.errors
    for f in res.fits.values():
        assert math.isfinite(f.aic) and math.isfinite(f.r2_adjusted) and math.isfinite(f.msc)
        assert len(f.residuals) == f.n_points
    rep = res.to_dict()
    assert rep["best"] == "weibull" and rep["models"]["weibull"]["delta_aic"] == 0.0
    assert json.dumps(rep)  # plain data


def test_crank_sphere_gives_the_fickian_exponent_over_the_first_60_percent() -> None:
    """Acceptance: Crank's series for Fickian release from a sphere (eq. 6.20): the
    Korsmeyer-Peppas exponent over the first 60 % is 0.43 +- 0.05 (Ritger & Peppas 1987),
    read as Fickian for a sphere."""
    t = np.linspace(0.0, 0.3, 61)[1:]  # in a^2 / D
    p = from_arrays(t, crank_sphere(t, 1.0, 1.0), time_unit="h")
    kp = fit_empirical(p, ["korsmeyer_peppas"]).fits["korsmeyer_peppas"]
    assert kp.n_points < t.size and max(kp.observed) <= 60.0
    assert kp.parameters["n"] == pytest.approx(0.43, abs=0.05)
    assert kp.interpretation["mechanism"] == "Fickian diffusion"
    assert not kp.warnings
    wide = fit_empirical(p, ["korsmeyer_peppas"], kp_window=95.0).fits["korsmeyer_peppas"]
    assert any("beyond 60 %" in w for w in wide.warnings)
    assert wide.interpretation["beyond_60_percent"]


def test_exact_curves_are_fitted_exactly_and_ranked_first() -> None:
    t = np.array([1, 2, 4, 6, 8, 12, 16, 24.0])
    exact = {"zero_order": 3.0 * t, "higuchi": 17.0 * np.sqrt(t),
             "first_order": 100 * (1 - np.exp(-0.15 * t))}
    for name, f in exact.items():
        res = fit_empirical(from_arrays(t, f, time_unit="h", released_unit="percent"),
                            ["zero_order", "first_order", "higuchi", "hixson_crowell"])
        assert res.best == name
        assert max(abs(r) for r in res.fits[name].residuals) < 1e-4
    k = res.fits["first_order"]
    assert k.parameters["k1"] == pytest.approx(0.15, rel=1e-6) and k.units["k1"] == "1/h"


def test_korsmeyer_peppas_mechanism_bounds_for_a_sphere() -> None:
    from dosing.analysis.empirical import kp_mechanism

    assert kp_mechanism(0.40)["mechanism"] == "Fickian diffusion"
    assert kp_mechanism(0.60)["mechanism"].startswith("anomalous")
    assert kp_mechanism(0.90)["mechanism"].startswith("case II")
    assert kp_mechanism(0.44, [0.42, 0.46])["mechanism"] == "Fickian diffusion"


def test_lag_time_is_fitted_where_the_model_has_one() -> None:
    t = np.array([2, 5, 8, 10, 15, 20, 30, 45, 60, 90, 120.0])
    f = 100 * (1 - np.exp(-((np.maximum(t - 6.0, 0) / 25.0) ** 1.2)))
    res = fit_empirical(from_arrays(t, f, time_unit="min", released_unit="percent"),
                        ["weibull", "first_order", "peppas_sahlin"], lag=True)
    w = res.fits["weibull"]
    assert w.parameters["Ti"] == pytest.approx(6.0, abs=0.05)
    assert w.parameters["Td"] == pytest.approx(25.0, rel=1e-3)
    assert "tlag" in res.fits["first_order"].parameters
    assert "tlag" not in res.fits["peppas_sahlin"].parameters  # no lag in that model


def test_replicate_units_are_averaged_and_weighted_by_their_spread(tmp_path) -> None:
    rng = np.random.default_rng(3)
    clean = 100 * (1 - np.exp(-((WEIBULL_T / 30.0) ** 0.75)))
    units = clean[:, None] + rng.normal(0, 1 + 0.03 * clean[:, None], (WEIBULL_T.size, 6))
    csv = tmp_path / "six.csv"
    csv.write_text("time (min);" + ";".join(f"vessel {k} [%]" for k in range(1, 7)) + "\n"
                   + "".join(f"{t:g};" + ";".join(f"{v:.4f}".replace(".", ",") for v in row)
                             + "\n" for t, row in zip(WEIBULL_T, units, strict=True)))
    p = read_profile(csv)
    assert p.n_units == 6 and p.time_unit == "min"
    assert np.allclose(p.mean, units.mean(axis=1), atol=1e-4)
    res = fit_empirical(p, ["weibull", "first_order"])
    assert res.weighted and res.best == "weibull"
    df = res.to_dataframe()
    assert set(df["model"]) == {"weibull", "first_order"} and "aic" in df.columns


@pytest.mark.parametrize("header", [
    "time_h,released_1 (%),released_2 (%)", "t [h],unit01 (%),unit02 (%)",
    "time (h),released (%),released (%)", "time_h,R1 (%),R2 (%)"])
def test_replicate_headers(tmp_path, header: str) -> None:
    p = tmp_path / "r.csv"
    p.write_text(header + "\n1,10,12\n2,20,22\n4,40,42\n")
    prof = read_profile(p)
    assert prof.n_units == 2 and prof.time_unit == "h"
    assert prof.mean.tolist() == [11.0, 21.0, 41.0] and prof.time_s[-1] == 4 * 3600


def test_mass_and_fraction_columns(tmp_path) -> None:
    p = tmp_path / "m.csv"
    p.write_text("time_s,released_ug\n10,5\n20,10\n40,15\n")
    assert read_profile(p, loaded_ug=20.0).mean.tolist() == [25.0, 50.0, 75.0]
    with pytest.raises(ParameterError, match="loaded_ug"):
        read_profile(p)
    p.write_text("time_s,released\n10,0.25\n20,0.5\n40,0.75\n")
    assert read_profile(p).mean.tolist() == [25.0, 50.0, 75.0]


def test_fitting_and_comparing_import_neither_matplotlib_nor_fastapi() -> None:
    """The layer rule (docs/architecture.md) holds while the analyses run, not only at import:
    the fits are scipy's least squares (lmfit would import matplotlib and pandas)."""
    import subprocess
    import sys

    code = ("import sys; from dosing.analysis import fit_empirical, from_arrays; "
            "from dosing.analysis.similarity import compare; "
            "p = from_arrays([1, 2, 3, 4], units=[[10, 20, 30, 40], [12, 21, 33, 41]], "
            "released_unit='percent'); fit_empirical(p); compare(p, p); "
            "print([m for m in ('fastapi', 'matplotlib', 'lmfit') if m in sys.modules])")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0 and done.stdout.strip() == "[]", done.stdout + done.stderr


# ------------------------------------------------------------------------ bad files
BAD = {
    "non_monotone": ("time_min,unit 1 (%),unit 2 (%)\n5,10,11\n10,20,21\n8,30,31\n20,40,41\n",
                     "line 4, column 1 (time_min)"),
    "over_105": ("time_min,unit 1 (%),unit 2 (%)\n5,10,11\n10,20,21\n15,30,107.5\n",
                 "line 4, column 3 (unit 2 (%))"),
    "too_few": ("time_min,released (%)\n5,10\n10,20\n", "lines 2-3, column 1 (time_min)"),
    "not_a_number": ("time_min,released (%)\n5,10\n10,abc\n15,30\n",
                     "line 3, column 2 (released (%))"),
    "unknown_column": ("time_min,colour\n5,10\n10,20\n15,30\n", "line 1, column 2"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_files_are_refused_naming_line_and_column(tmp_path, capsys, case: str) -> None:
    text, where = BAD[case]
    p = tmp_path / f"{case}.csv"
    p.write_text(text)
    with pytest.raises(ParameterError) as err:
        read_profile(p)
    assert err.value.field == f"{case}.csv: {where}"
    assert main(["fit", "empirical", str(p), "--json"]) == 2
    assert where in capsys.readouterr().err
    good = tmp_path / "good.csv"
    good.write_text("time_min,released (%)\n5,10\n10,20\n15,30\n20,40\n")
    assert main(["compare", str(good), str(p), "--json"]) == 2
    assert where in capsys.readouterr().err


def test_unequal_time_grids_are_refused_for_compare(tmp_path, capsys) -> None:
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    a.write_text("time_min,released (%)\n5,10\n10,20\n15,30\n20,40\n")
    b.write_text("time_min,released (%)\n5,10\n10,20\n16,30\n20,40\n")
    with pytest.raises(ParameterError, match="unequal time grids") as err:
        compare(read_profile(a), read_profile(b))
    assert err.value.field == "b.csv: line 4, column 1 (time_min)"
    assert main(["compare", str(a), str(b)]) == 2
    assert "b.csv: line 4, column 1 (time_min)" in capsys.readouterr().err
    b.write_text("time_min,released (%)\n5,10\n10,20\n15,30\n")
    with pytest.raises(ParameterError, match="unequal time grids") as err:
        compare(read_profile(a), read_profile(b))
    assert err.value.field == "a.csv: line 5, column 1 (time_min)"


def test_arrays_are_refused_naming_the_index() -> None:
    with pytest.raises(ParameterError) as err:
        from_arrays([1, 2, 3], units=[[1, 2, 3], [1, 2, 300]], released_unit="percent",
                    label="test")
    assert err.value.field == "test.units[1][2]"
    with pytest.raises(ParameterError) as err:
        from_arrays([1, 3, 2], [0.1, 0.2, 0.3])
    assert err.value.field == "time[2]"


# ------------------------------------------------------------------------ f1, f2
# Shah VP, Tsong Y, Sathe P, Liu JP, Pharm Res 15(6):889-896 (1998), Table 4: 12 tablets of a
# reference and five test batches at 30, 60, 90, 180 min (the per-tablet data as the bootf2 R
# package ships them, data/shah1998.rda; tests/data/release/shah1998_*.csv); the printed f2.
SHAH_PRINTED = {"test1": 60.03, "test4": 50.07, "test5": 48.05}


@pytest.mark.parametrize("batch", sorted(SHAH_PRINTED))
def test_f2_of_twelve_units_is_the_fda_formula_on_the_means(batch: str) -> None:
    """Acceptance: f2 of two profiles of 12 units each equals the FDA formula on the mean
    profiles with the 85 % rule (all four times kept: both pass 85 % only at 180 min), to
    Shah's printed two decimals; the bootstrap's 90 % interval brackets it."""
    ref, test = read_profile(SHAH["ref"]), read_profile(SHAH[batch])
    c = compare(ref, test)
    r, t = ref.units.mean(axis=1), test.units.mean(axis=1)
    by_hand = 50 * math.log10(100 / math.sqrt(1 + np.sum((r - t) ** 2) / 4))
    assert c.f2 == pytest.approx(by_hand, abs=1e-12)
    assert round(c.f2, 2) == SHAH_PRINTED[batch]
    assert c.points_used == [0, 1, 2, 3] and c.conditions_met
    assert c.f1 == pytest.approx(100 * np.sum(np.abs(r - t)) / np.sum(r), abs=1e-12)
    lo, hi = c.bootstrap["interval_bca"]
    assert lo < c.f2 < hi and c.bootstrap["n_boot"] >= 1000
    similar = "between 50 and 100: the two dissolution profiles are similar"
    assert (similar in c.outcome) == (SHAH_PRINTED[batch] >= 50)
    assert "An f2 value between 50 and 100 suggests that the two dissolution profiles are " \
           "similar" in c.outcome
    df = c.to_dataframe()
    assert df["used"].all() and df["reference_mean_percent"].tolist() == pytest.approx(r)
    assert df.attrs["f2"] == c.f2


def test_the_85_percent_rule_keeps_one_point_after_both_pass_it() -> None:
    """Only one measurement after 85 % dissolution of both products (FDA 1997): the points
    after the first one where both exceed 85 % are dropped; a point where one alone does is
    kept; zero is excluded.  The f2 is the formula on the kept means."""
    t = np.array([0, 10, 20, 30, 45, 60.0])
    r = np.array([0, 40, 70, 88, 95, 99.0])
    s = np.array([0, 35, 66, 84, 92, 98.0])
    assert points_used(t, r, s).tolist() == [False, True, True, True, True, False]
    rng = np.random.default_rng(0)
    ref = from_arrays(t, units=(r[:, None] + rng.normal(0, 0.5, (6, 12)) * (t > 0)[:, None]).T,
                      time_unit="min", released_unit="percent")
    test = from_arrays(t, units=(s[:, None] + rng.normal(0, 0.5, (6, 12)) * (t > 0)[:, None]).T,
                       time_unit="min", released_unit="percent")
    c = compare(ref, test)
    keep = [1, 2, 3, 4]
    d = ref.mean[keep] - test.mean[keep]
    assert c.points_used == keep
    assert c.f2 == pytest.approx(50 * math.log10(100 / math.sqrt(1 + np.mean(d * d))))
    assert c.conditions["one_after_85"]["met"] and c.conditions["one_after_85"]["dropped"] == 1
    assert fda_f2(ref.mean, test.mean, t) == pytest.approx(c.f2)


def test_f2_anchors_of_the_guidance() -> None:
    """f2 = 100 for identical profiles; a uniform 10 % difference gives 49.89, the similarity
    limit 50 (the FDA guidance's definition; its text prints no numerical example)."""
    r = np.array([42.0, 67.0, 84.0, 91.0])
    assert f2_value(r, r) == 100.0
    assert f2_value(r, r - 10) == pytest.approx(49.89, abs=0.005)


def test_the_cv_rule_is_checked_on_the_units() -> None:
    t = np.array([15, 30, 45, 60.0])
    base = np.array([30, 55, 75, 88.0])
    spread = np.array([0.15, 0.02, 0.02, 0.02])  # CV 15 % at the first point: allowed
    rng = np.random.default_rng(1)
    units = base[:, None] * (1 + spread[:, None] * rng.standard_normal((4, 12)))
    ref = from_arrays(t, units=units.T, time_unit="min", released_unit="percent")
    c = compare(ref, ref)
    assert c.conditions["cv"]["met"] and c.f2 == 100.0
    spread[2] = 0.2  # 20 % at a later point: refused by the rule
    units = base[:, None] * (1 + spread[:, None] * rng.standard_normal((4, 12)))
    bad = from_arrays(t, units=units.T, time_unit="min", released_unit="percent")
    c = compare(ref, bad)
    assert not c.conditions["cv"]["met"] and "test at 45 min" in c.conditions["cv"]["found"][0]
    assert "not all met" in c.outcome and "bootstrap" in c.outcome
    one = from_arrays(t, base, time_unit="min", released_unit="percent")
    c = compare(one, one)
    assert not c.conditions["units"]["met"] and c.bootstrap is None


# Published bootstrap example: the disprofas R package (P. Dahinden, bootstrap_f2(),
# man/examples/examples_bootstrap_f2.R) on Shah 1998's reference and batch 4 (its dip2 data:
# Table 4), resampling complete profiles, 200 draws, seed 421 (R's generator): f2 50.07187,
# bootstrap standard error 0.9488, 90 % BCa (boot package) 48.69289-51.99121, Shah's BCa
# 48.64613-51.75292.
PUBLISHED = {"se": 0.9488015, "bca": (48.69289, 51.99121), "shah_bca": (48.64613, 51.75292)}


def test_bootstrap_reproduces_a_published_example() -> None:
    """Our bootstrap (5000 draws, numpy's generator) agrees with the published intervals to
    their Monte Carlo error (200 draws): each end within 0.35, the standard error within 10 %."""
    c = compare(read_profile(SHAH["ref"]), read_profile(SHAH["test4"]), n_boot=5000, seed=7)
    b = c.bootstrap
    assert c.f2 == pytest.approx(50.07187, abs=5e-6)
    assert b["sd"] == pytest.approx(PUBLISHED["se"], rel=0.10)
    for pub in (PUBLISHED["bca"], PUBLISHED["shah_bca"]):
        assert abs(b["interval_bca"][0] - pub[0]) < 0.35
        assert abs(b["interval_bca"][1] - pub[1]) < 0.35
    assert not b["similar"] and "below 50" in b["outcome"]  # lower bound 48.6 < 50


def test_bootstrap_is_seeded_vectorised_and_fast() -> None:
    ref, test = read_profile(SHAH["ref"]), read_profile(SHAH["test1"])
    a = compare(ref, test, n_boot=1000, seed=3).bootstrap
    assert a == compare(ref, test, n_boot=1000, seed=3).bootstrap
    assert a != compare(ref, test, n_boot=1000, seed=4).bootstrap
    rng = np.random.default_rng(0)
    big_r = rng.uniform(0, 100, (24, 40))
    big_t = rng.uniform(0, 100, (24, 40))
    started = time.perf_counter()
    draws = bootstrap_draws(big_r, big_t, 10_000, 0)
    assert time.perf_counter() - started < 1.0 and draws.shape == (10_000,)
    with pytest.raises(ParameterError, match="n_boot"):
        compare(ref, test, n_boot=999)


# -------------------------------------------------------------- measured against predicted
def test_measured_against_predicted() -> None:
    t = np.array([60, 120, 240, 480.0])
    meas_units = np.array([[20, 30, 45, 62], [22, 31, 44, 60], [21, 29, 46, 61.0]])
    measured = from_arrays(t, units=meas_units, time_unit="s", released_unit="percent")
    ts = np.linspace(0, 600, 601)
    same = np.interp(ts, t, measured.mean / 100.0, left=0.0)
    out = measured_against_predicted(measured, ts, same)
    s = out["similarity"]
    assert s["f2"] == pytest.approx(100.0) and out["chi2"] == pytest.approx(0.0, abs=1e-9)
    assert s["bootstrap"] is not None and "measured" in s["meaning"]
    assert s["conditions"]["units"]["found"] == 3 and not s["conditions"]["units"]["met"]
    assert "prediction is one curve" in s["conditions"]["units"]["rule"]
    off = measured_against_predicted(measured, ts, same + 0.10)
    assert off["similarity"]["f2"] == pytest.approx(50 * math.log10(100 / math.sqrt(101)))
    assert off["residuals_percent"] == pytest.approx([-10.0] * 4)
    with pytest.raises(ParameterError, match="horizon"):
        measured_against_predicted(measured, ts[:300], same[:300])


def test_release_fit_report_calls_f2_a_similarity_not_a_goodness_of_fit() -> None:
    from dosing.fits.release import fit_release

    t = np.linspace(30.0, 1200.0, 12)
    y = crank_sphere(t, 2e-7 * 1e8, 50.0 * 1.9) + 0.01 * np.random.default_rng(0).normal(
        size=t.size)
    rep = fit_release(t, y, "ANB", 300.0, 300.0, 50.0)
    sim = rep["similarity"]
    assert "not a goodness of fit" in sim["meaning"] and "not a goodness" in rep["f2_meaning"]
    assert sim["f2"] == rep["f2"] and len(rep["residuals"]) == t.size
    assert rep["f2"] == pytest.approx(fda_f2(100 * y, 100 * np.asarray(rep["fitted"]), t))


# ------------------------------------------------------------------------ the CLI
def test_cli_fit_empirical_and_compare(tmp_path, capsys) -> None:
    p = tmp_path / "weibull.csv"
    prof = weibull_profile(0)
    p.write_text("time_min,released (%)\n" + "".join(
        f"{a:g},{b:.4f}\n" for a, b in zip(prof.times, prof.mean, strict=True)))
    png = tmp_path / "emp.png"
    assert main(["fit", "empirical", str(p), "--json", "--plot", str(png)]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["best"] == "weibull" and png.stat().st_size > 10_000
    assert rep["models"]["weibull"]["parameters"]["Td"] == pytest.approx(30.0, rel=0.05)
    assert main(["fit", "empirical", str(p), "--models", "weibull,higuchi"]) == 0
    text = capsys.readouterr().out
    assert "Weibull" in text and "best by AIC" in text and "Td" in text
    assert main(["fit", "empirical", str(p), "--models", "gompertz"]) == 2
    png = tmp_path / "cmp.png"
    assert main(["compare", str(SHAH["ref"]), str(SHAH["test1"]), "--json", "--plot",
                 str(png), "--seed", "5"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert round(rep["f2"], 2) == 60.03 and rep["bootstrap"]["seed"] == 5
    assert png.stat().st_size > 10_000
    assert main(["compare", str(SHAH["ref"]), str(SHAH["test5"])]) == 0
    text = capsys.readouterr().out
    assert "below 50" in text and "BCa" in text


@pytest.mark.slow
def test_cli_release_compare_states_f2_beside_the_residuals(tmp_path, capsys) -> None:
    """``thermogel release ... --compare MEASURED.csv``: the prediction against a measured
    profile of three units (f2 under the FDA rules, bootstrap over the units, residuals and
    chi-square); a measured time past the prediction's horizon is refused naming its line."""
    meas = tmp_path / "measured.csv"
    meas.write_text("time_s,unit 1 (%),unit 2 (%),unit 3 (%)\n30,20,22,21\n60,30,31,29\n"
                    "120,42,44,43\n200,57,59,58\n")
    args = ["release", "--gel", "ANB", "--t-start", "302", "--t-end", "308", "--until", "0.1",
            "--dry-radius-um", "50", "--drug-diffusivity-cm2-s", "1e-7", "--hindrance", "none",
            "--n", "100", "--samples", "200", "--paper-constants", "--json",
            "--compare", str(meas)]  # the profile's hours are the paper's tau (2205 s)
    assert main(args) == 0
    out = json.loads(capsys.readouterr().out)
    c = out["compare"]
    pred = np.interp(np.array([30, 60, 120, 200.0]), out["seconds"],
                     100 * np.asarray(out["released_fraction"]))
    assert c["predicted_percent"] == pytest.approx(pred.tolist())
    mean = np.array([21.0, 30.0, 43.0, 58.0])
    assert c["similarity"]["f2"] == pytest.approx(f2_value(mean, pred))
    assert c["residuals_percent"] == pytest.approx((mean - pred).tolist())
    assert c["chi2_dof"] == 4 and c["similarity"]["bootstrap"]["n_boot"] == 1000
    meas.write_text("time_s,released (%)\n30,20\n60,30\n120,42\n900,57\n")
    assert main(args) == 2
    assert "measured.csv: line 5, column 1 (time_s)" in capsys.readouterr().err


# ------------------------------------------------------------------------ HTTP
def _shah_body(name: str) -> dict:
    p = read_profile(SHAH[name])
    return {"time": p.times.tolist(), "time_unit": "min", "units": p.units.T.tolist(),
            "released_unit": "percent"}


@pytest.mark.anyio
async def test_http_empirical_is_a_job_and_compare_answers_at_once(tmp_path) -> None:
    """The same numbers as Python: ``POST /v1/fit/empirical`` a job polled at /v1/jobs/{id}
    and /v1/fit/jobs/{id}; ``POST /v1/compare`` at once; bad data a 422 naming the field."""
    prof = weibull_profile(1)
    body = {"time": prof.times.tolist(), "time_unit": "min", "released": prof.mean.tolist(),
            "released_unit": "percent"}
    py = fit_empirical(prof)
    cmp_py = compare(read_profile(SHAH["ref"]), read_profile(SHAH["test1"]), seed=2)
    app = create_app(warm=False, cache_path=str(tmp_path / "v.sqlite"))
    async with app.router.lifespan_context(app):
        transport = httpx.ASGITransport(app=app)
        async with httpx.AsyncClient(base_url="http://t", transport=transport) as c:
            r = await c.post("/v1/fit/empirical", json=body)
            assert r.status_code == 202 and r.json()["kind"] == "empirical", r.text
            url = "/v1/jobs/" + r.json()["id"]
            deadline = time.monotonic() + 60
            while (j := (await c.get(url)).json())["status"] not in ("done", "failed"):
                assert time.monotonic() < deadline
                await asyncio.sleep(0.05)
            assert j["status"] == "done", j
            own = (await c.get(r.headers["location"])).json()
            assert own["result"] == j["result"] and own["kind"] == "empirical"
            rep = j["result"]
            assert rep["best"] == py.best == "weibull"
            assert rep["models"]["weibull"]["parameters"]["Td"] == pytest.approx(
                py.fits["weibull"].parameters["Td"], rel=1e-9)
            bad = await c.post("/v1/fit/empirical", json={**body, "time": body["time"][::-1]})
            assert bad.status_code == 422 and bad.json()["detail"][0]["loc"] == ["body", "time",
                                                                                 1]
            r = await c.post("/v1/compare", json={"reference": _shah_body("ref"),
                                                  "test": _shah_body("test1"), "seed": 2})
            assert r.status_code == 200, r.text
            out = r.json()
            assert out["f2"] == pytest.approx(cmp_py.f2, abs=1e-12)
            assert out["bootstrap"]["interval_bca"] == pytest.approx(
                cmp_py.bootstrap["interval_bca"], abs=1e-12)
            test = _shah_body("test1")
            test["units"][3][2] = 120.0
            bad = await c.post("/v1/compare", json={"reference": _shah_body("ref"),
                                                    "test": test})
            assert bad.status_code == 422
            assert bad.json()["detail"][0]["loc"] == ["body", "test", "units", 3, 2]
            test = _shah_body("test1")
            test["time"][2] = 91.0
            bad = await c.post("/v1/compare", json={"reference": _shah_body("ref"),
                                                    "test": test})
            assert bad.status_code == 422 and "unequal time grids" in bad.text
            assert bad.json()["detail"][0]["loc"] == ["body", "test", "time", 2]
            # the CSV text itself, read as the command line reads the file
            r = await c.post("/v1/compare", json={"reference": {"csv": SHAH["ref"].read_text()},
                                                  "test": {"csv": SHAH["test1"].read_text()},
                                                  "seed": 2})
            assert r.status_code == 200 and r.json()["f2"] == pytest.approx(cmp_py.f2)
            bad_csv = "time_min,unit 1 (%),unit 2 (%)\n5,10,11\n10,20,21\n8,30,31\n"
            bad = await c.post("/v1/compare", json={"reference": {"csv": bad_csv},
                                                    "test": {"csv": bad_csv}})
            assert bad.status_code == 422
            assert "reference.csv: line 4, column 1 (time_min)" in bad.json()["detail"][0]["msg"]
            bad = await c.post("/v1/fit/empirical", json={"csv": "/etc/hostname"})
            assert bad.status_code == 422  # CSV text, never a path on the server
            short = {"time": [1, 2], "released": [0.1, 0.2]}
            bad = await c.post("/v1/compare", json={"reference": short, "test": short})
            assert bad.status_code == 422 and "at least 3" in bad.text


@pytest.mark.slow  # a real server and a browser
def test_the_analysis_page_uploads_csv_files(tmp_path) -> None:
    """GET /analysis: a CSV uploaded fits the models (the job polled) and two uploaded CSVs
    are compared, in headless Chromium; a bad file's line and column are shown."""
    from test_page_browser import CHROMIUM, FLAGS, _need_browser, _serve_gracefully

    sync_playwright = _need_browser()
    bad = tmp_path / "bad.csv"
    bad.write_text(BAD["non_monotone"][0])
    with _serve_gracefully(tmp_path / "cache.sqlite") as url, sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=FLAGS, headless=True)
        try:
            page = browser.new_page(viewport={"width": 1300, "height": 900})
            errors: list[str] = []
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(url + "/analysis")
            page.set_input_files("#emp-file", str(DATA.parent.parent.parent / "docs" /
                                                  "examples" / "release_reference.csv"))
            page.click("#emp-go")
            page.wait_for_selector("body[data-emp=done]", timeout=60_000)
            assert "best by AIC: weibull" in page.inner_text("#emp-best")
            assert page.locator("#emp-plot polyline").count() == 7
            page.set_input_files("#cmp-ref", str(SHAH["ref"]))
            page.set_input_files("#cmp-test", str(SHAH["test1"]))
            page.click("#cmp-go")
            page.wait_for_selector("body[data-cmp=done]", timeout=60_000)
            assert "f2 = 60.03" in page.inner_text("#cmp-f2")
            assert "BCa" in page.inner_text("#cmp-boot-out")
            page.screenshot(path=str(tmp_path / "analysis.png"), full_page=True)
            page.set_input_files("#cmp-test", str(bad))
            page.click("#cmp-go")
            page.wait_for_selector("body[data-cmp=error]", timeout=60_000)
            assert "line 4, column 1 (time_min)" in page.inner_text("#cmp-error")
            assert errors == []
        finally:
            browser.close()
