"""The equilibrium swelling fit (solver.fit.equilibrium, issue 14): recovery, coverage of the
95% intervals, identifiability warnings, non-convergence and bad data."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dosing.fit import read_swelling_csv
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
    fr, fd = fit_equilibrium(r), fit_equilibrium(d)
    assert fd.parameters["scale"] == pytest.approx(2.0 * fr.parameters["scale"], rel=1e-6)
    assert fd.parameters["omega"] == pytest.approx(fr.parameters["omega"], rel=1e-5)
    fv = fit_equilibrium(v, size_rel_sigma=0.03)  # 1% in radius is 3% in volume
    fv.parameters["scale"] **= 1.0 / 3.0  # a volume's scale is the dry volume
    for k in fr.names:  # equal to first order in the noise: far inside the uncertainty
        assert abs(fv.parameters[k] - fr.parameters[k]) < 0.2 * fr.stderr[k], k


@pytest.mark.slow
@pytest.mark.parametrize(("gel", "scale", "fixed", "floor"), [
    # HHT: all six parameters are identifiable from one curve (the paper fitted six)
    (HHT, HHT_SCALE, {}, {}),
    # ANB: with six free, Omega is not identifiable (interval over 40 decades); the paper
    # took Omega = 100 from Cai & Suo, so Omega is fixed and the other five covered.  The
    # linearised interval of the ANB scale under-covers (z-scores' sd 1.18 over 30 seeds;
    # measured 43/50): its floor is 0.8, the others' 0.9
    (ANB, 1.0, {"omega": 100.0}, {"scale": 0.8}),
])
def test_true_parameters_inside_their_95_intervals(gel, scale, fixed, floor) -> None:
    truth = _truth(gel, scale)
    hits = dict.fromkeys(truth, 0)
    inside = dict.fromkeys([f.kind for f in folds(gel)], 0)
    for seed in range(SEEDS):
        res = fit_equilibrium(synthetic_swelling(gel, scale=scale, seed=seed), fixed=fixed)
        for k, v in truth.items():
            iv = res.interval(k)
            hits[k] += iv is None and k in fixed or (iv is not None and iv[0] <= v <= iv[1])
        for f in folds(gel):
            same = [t for t in res.extra["transitions"] if t["kind"] in (f.kind, "continuous")]
            iv = same[0].get("interval") if same else None
            inside[f.kind] += iv is not None and iv[0] - 0.01 <= f.temperature <= iv[1] + 0.01
    for k, n in hits.items():
        assert n / SEEDS >= floor.get(k, 0.9), (k, n)
    for kind, n in inside.items():  # HHT's two folds are 0.0065 K apart (the 0.01 K slack)
        assert n / SEEDS >= 0.85, (kind, n)


def test_unidentifiable_omega_is_flagged() -> None:
    res = fit_equilibrium(synthetic_swelling(ANB, seed=1))
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
    (lambda t: t.replace("radius", "radios"), "columns", "unknown column name(s) 'radios'"),
    (lambda t: t.replace("temperature_K,radius", "temperature_K,radius,diameter")
     .replace("\n", ",1\n").replace("diameter,1", "diameter"), "columns", "exactly one size"),
    (lambda t: t.replace("temperature_K,", "T,"), "columns", "unknown column"),
    (lambda t: t.replace(t.splitlines()[3].split(",")[1], "nan", 1), "radius", "NaN"),
    (lambda t: t.replace(t.splitlines()[3].split(",")[1], "-1.5", 1), "radius", "sizes > 0"),
    (lambda t: t.replace(t.splitlines()[3].split(",")[1], "abc", 1), "line 4, radius",
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
    with pytest.raises(ParameterError, match="both sides of the volume-phase transition"):
        fit_equilibrium(synthetic_swelling(ANB, t_range=t_range))


def test_unknown_fixed_parameter() -> None:
    with pytest.raises(ParameterError, match="keys among"):
        fit_equilibrium(synthetic_swelling(HHT, scale=HHT_SCALE), fixed={"chi": 1.0})


def test_reading_a_good_csv(tmp_path) -> None:
    d = synthetic_swelling(HHT, scale=HHT_SCALE)
    got = read_swelling_csv(_csv(tmp_path, "# a comment\n" + _rows(d, "diameter")))
    assert got.kind == "diameter" and len(got) == 30
    np.testing.assert_allclose(got.size, d.size)
