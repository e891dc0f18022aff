"""The equilibrium swelling fit (solver.fit.equilibrium, issue 14): recovery, coverage of the
95% intervals, identifiability warnings, non-convergence and bad data."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dosing.fits.gel import read_swelling_csv
from solver.equilibrium import folds
from solver.errors import ParameterError
from solver.fit import SwellingData, fit_equilibrium
from solver.fit.synthetic import synthetic_swelling
from solver.gel import ANB, HHT

HHT_SCALE = 0.4127  # the paper's scale between the data and the stretch (sec. Eql)
SEEDS = 50


def _truth(gel, scale: float) -> dict[str, float]:
    return {"omega": gel.omega, "a0": gel.a0, "b0": gel.b0, "a1": gel.a1, "b1": gel.b1,
            "scale": scale}


def test_exact_data_give_the_hht_parameters_and_folds() -> None:
    data = synthetic_swelling(HHT, scale=HHT_SCALE, size_noise=0.0, temperature_noise=0.0)
    res = fit_equilibrium(data)
    assert res.success
    for k, v in _truth(HHT, HHT_SCALE).items():
        assert res.parameters[k] == pytest.approx(v, rel=1e-6), k
    fitted = {t["kind"]: t["temperature"] for t in res.extra["transitions"]}
    for f in folds(HHT):
        assert fitted[f.kind] == pytest.approx(f.temperature, abs=1e-6)
    assert res.rms_residual < 1e-6


def test_diameter_and_volume_ratio_give_the_same_gel() -> None:
    r = synthetic_swelling(HHT, scale=HHT_SCALE, seed=2)
    d = SwellingData(r.temperature, 2.0 * r.size, "diameter")
    v = SwellingData(r.temperature, r.size**3, "volume_ratio")
    fr = fit_equilibrium(r)
    # warm-started one unit's optimum away (the global search is the radius fit's): a
    # diameter or volume objective that differed would move the local fit off it
    far = {**fr.parameters, "scale": 1.1 * fr.parameters["scale"], "omega": 1.5 * HHT.omega}
    fd = fit_equilibrium(d, start={**far, "scale": 2.0 * far["scale"]})
    assert fd.parameters["scale"] == pytest.approx(2.0 * fr.parameters["scale"], rel=1e-6)
    assert fd.parameters["omega"] == pytest.approx(fr.parameters["omega"], rel=1e-5)
    fv = fit_equilibrium(v, size_rel_sigma=0.03,  # 1% in radius is 3% in volume
                         start={**far, "scale": far["scale"] ** 3})
    fv.parameters["scale"] **= 1.0 / 3.0  # a volume's scale is the dry volume
    for k in fr.names:  # equal to first order in the noise: far inside the uncertainty
        assert abs(fv.parameters[k] - fr.parameters[k]) < 0.2 * fr.stderr[k], k


@pytest.mark.slow
@pytest.mark.parametrize(("gel", "scale", "fixed", "t_range"), [
    # HHT: all six parameters are identifiable from one curve (the paper fitted six)
    (HHT, HHT_SCALE, {}, (290.0, 320.0)),
    # ANB: with six free, Omega is not identifiable (test_unidentifiable_omega_is_flagged);
    # the paper took Omega = 100 from Cai & Suo, so it is fixed here.  Points over
    # 300-312 K (across the transition): over 290-320 K the linearised interval of the ANB
    # scale under-covers (43/50; z-scores' sd 1.18)
    (ANB, 1.0, {"omega": 100.0}, (300.0, 312.0)),
])
def test_true_parameters_inside_their_95_intervals(gel, scale, fixed, t_range) -> None:
    """Acceptance: 30 points, 1% noise in size, 0.05 K in temperature, 50 seeds; each true
    parameter inside its 95% interval in >= 90% of them; the heating transition (the shrink
    fold, or the steepest point where the fit has no fold; HHT's true folds are 0.0065 K
    apart) within 0.1 K rms and inside its interval in >= 90%.  Measured: HHT coverage
    0.92-0.98, transition rms 0.073 K (41/50 within 0.1 K); ANB 0.90-0.96, 0.072 K (39/50).
    The cooling (swell) fold is not pinned by heating data (ANB rms 0.48 K) and not tested.

    Cost: each seed is one local fit warm-started at the generating parameters (``start``)
    instead of the six-start global search: the same optimum (checked on seed 0 here, and
    measured on 8 seeds of each gel: chi-square equal, parameters within 3e-5 standard
    errors) at a tenth of the cost; the global search itself is tested elsewhere
    (test_exact_data_..., test_diameter_...).  All 50 seeds are kept: at a true 95%
    coverage a 45/50 bound fails with probability 0.04 and passes a true 80% coverage with
    probability 0.05 (binomial); 30 seeds would pass 80% with probability 0.12."""
    truth = _truth(gel, scale)
    hits = dict.fromkeys(truth, 0)
    true_t = next(f.temperature for f in folds(gel) if f.kind == "shrink")
    errors, inside = [], 0
    for seed in range(SEEDS):
        data = synthetic_swelling(gel, scale=scale, seed=seed, t_range=t_range)
        res = fit_equilibrium(data, fixed=fixed, start=truth)  # warm: 0.1 s, not 1.2 s
        if seed == 0:  # the global search (default) reaches the same optimum
            glob = fit_equilibrium(data, fixed=fixed)
            assert glob.extra["chi2"] == pytest.approx(res.extra["chi2"], rel=1e-8)
            for k in set(res.names) - set(fixed):
                assert abs(glob.parameters[k] - res.parameters[k]) <= 1e-3 * res.stderr[k], k
        for k, v in truth.items():
            iv = res.interval(k)
            hits[k] += (iv is None and k in fixed) or (iv is not None and iv[0] <= v <= iv[1])
        tr = next(t for t in res.extra["transitions"] if t["kind"] in ("shrink", "continuous"))
        errors.append(tr["temperature"] - true_t)
        iv = tr.get("interval")
        inside += iv is not None and iv[0] - 0.01 <= true_t <= iv[1] + 0.01
    for k, n in hits.items():
        assert n / SEEDS >= 0.9, (k, n)
    assert float(np.sqrt(np.mean(np.square(errors)))) < 0.1
    assert inside / SEEDS >= 0.9


def test_unidentifiable_omega_is_flagged() -> None:
    """Two starts (the default six give the same warnings and an omega interval as wide)."""
    res = fit_equilibrium(synthetic_swelling(ANB, seed=1), n_starts=2)
    text = " ".join(res.warnings)
    assert "omega is not identifiable" in text
    assert "strongly correlated" in text
    lo, hi = res.interval("omega")
    assert hi / lo > 1e6


def test_a_fit_that_does_not_converge_says_so_and_returns_its_best_point() -> None:
    res = fit_equilibrium(synthetic_swelling(HHT, scale=HHT_SCALE, seed=0), max_nfev=2)
    assert not res.success
    assert "did not converge" in res.warnings[0]
    assert all(math.isfinite(v) for v in res.parameters.values())


# ---------------------------------------------------------------- bad data
def _csv(tmp_path, text: str):
    p = tmp_path / "d.csv"
    p.write_text(text)
    return p


def _rows(data: SwellingData, col: str = "radius") -> str:
    return f"temperature_K,{col}\n" + "".join(
        f"{t},{y}\n" for t, y in zip(data.temperature, data.size, strict=True))


@pytest.mark.parametrize(("mutate", "field", "words"), [
    (lambda t: t.replace("radius", "radios"), "line 1, column 2",
     "unknown column name(s) 'radios'"),
    (lambda t: t.replace("temperature_K,radius", "temperature_K,radius,diameter")
     .replace("\n", ",1\n").replace("diameter,1", "diameter"), "line 1", "exactly one size"),
    (lambda t: t.replace("temperature_K,", "heat,"), "line 1, column 1", "unknown column"),
    (lambda t: t.replace(t.splitlines()[3].split(",")[1], "nan", 1), "radius", "NaN"),
    (lambda t: t.replace(t.splitlines()[3].split(",")[1], "-1.5", 1), "radius", "sizes > 0"),
    (lambda t: t.replace(t.splitlines()[3].split(",")[1], "abc", 1), "line 4, column 2 (radius)",
     "a number"),
])
def test_bad_csv_names_the_problem(tmp_path, mutate, field, words) -> None:
    text = mutate(_rows(synthetic_swelling(HHT, scale=HHT_SCALE)))
    with pytest.raises(ParameterError) as exc:
        read_swelling_csv(_csv(tmp_path, text))
    assert exc.value.field == field
    assert words in str(exc.value)


def test_fewer_points_than_parameters() -> None:
    d = synthetic_swelling(HHT, n=6, scale=HHT_SCALE)
    with pytest.raises(ParameterError, match="at least 7 points"):
        fit_equilibrium(d)


@pytest.mark.parametrize("t_range", [(290.0, 303.0), (309.0, 320.0)])
def test_all_points_on_one_side_of_the_transition(t_range) -> None:
    """Refused from the fitted curve's transition: one start, and 50 evaluations (the fit
    on one-sided data wanders to its 400-evaluation budget without changing the verdict)."""
    with pytest.raises(ParameterError, match="both sides of the volume-phase transition"):
        fit_equilibrium(synthetic_swelling(ANB, t_range=t_range), n_starts=1, max_nfev=50)


def test_unknown_fixed_parameter() -> None:
    with pytest.raises(ParameterError, match="keys among"):
        fit_equilibrium(synthetic_swelling(HHT, scale=HHT_SCALE), fixed={"chi": 1.0})


def test_reading_a_good_csv(tmp_path) -> None:
    d = synthetic_swelling(HHT, scale=HHT_SCALE)
    got = read_swelling_csv(_csv(tmp_path, "# a comment\n" + _rows(d, "diameter")))
    assert got.kind == "diameter" and len(got) == 30
    np.testing.assert_allclose(got.size, d.size)
