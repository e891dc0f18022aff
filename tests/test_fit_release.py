"""Release-curve fits with f2 (issue 27, item 5)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from api.cli import main
from dosing import SolverSettings
from dosing.fits import release_steps as fp
from dosing.fits.release import f2, fit_release
from dosing.payload.drug import DrugModel
from dosing.runs.mechanics import protocol_mechanics
from dosing.units import PhysicalConstants
from solver.equilibrium import equilibrium
from solver.errors import ParameterError
from solver.gel import ANB
from solver.solute.crank import crank_sphere

D0 = 2.0e-7  # cm^2/s
DRY_UM, T = 50.0, 300.0


def _curve(seed: int, noise: float = 0.01, n: int = 25):
    """Crank's sphere series (eq. 6.20) for the swollen ANB bead at 300 K, 1% noise."""
    a = equilibrium(ANB, T, "swollen").stretch * DRY_UM  # um
    t = np.geomspace(5.0, 3.0 * a * a / (D0 * 1e8), n)  # up to ~ full release
    y = crank_sphere(t, D0 * 1e8, a) + noise * np.random.default_rng(seed).standard_normal(n)
    return t, y


def test_f2_follows_the_fda_definition() -> None:
    """FDA 1997 (Dissolution Testing of IR Solid Oral Dosage Forms): f2 = 100 for identical
    profiles, and an average difference of 10% at every point gives f2 ~ 50 (the guidance's
    similarity limit: 50 log10(100 / sqrt(101)) = 49.89).  The numbers below are by hand:
    differences 3, 3, 4, 2 -> mean square 9.5 -> 50 log10(100 / sqrt(10.5)) = 74.47 (a
    calculator page found online prints 67.32 for the same profiles, which the formula does
    not give; the printed example checked is Shah et al. 1998, below)."""
    r = np.array([42.0, 67.0, 84.0, 91.0])
    assert f2(r, r) == pytest.approx(100.0)
    assert f2(r, r - 10.0) == pytest.approx(50 * math.log10(100 / math.sqrt(101)))
    assert f2(r, r - 10.0) == pytest.approx(49.89, abs=0.01)
    assert f2(r, [39.0, 64.0, 80.0, 89.0]) == pytest.approx(74.47, abs=0.01)
    # only one point after 85% of both products: 95/90 (after 88/86) is dropped; a point
    # where only the reference is past 85% is kept (issue 38: the rule is of both)
    r2 = np.array([42.0, 67.0, 88.0, 95.0])
    assert f2(r2, [39.0, 64.0, 86.0, 90.0], fda_85_rule=True) == pytest.approx(
        50 * math.log10(100 / math.sqrt(1 + (9 + 9 + 4) / 3)))
    assert f2(r2, [39.0, 64.0, 84.0, 80.0], fda_85_rule=True) == pytest.approx(
        50 * math.log10(100 / math.sqrt(1 + (9 + 9 + 16 + 225) / 4)))
    with pytest.raises(ParameterError):
        f2([1, 2], [1, 2, 3])


# Shah VP, Tsong Y, Sathe P, Liu JP, "In vitro dissolution profile comparison - statistics
# and analysis of the similarity factor, f2", Pharm Res 15(6):889-896 (1998): 12 tablets of a
# reference and five test batches at 30, 60, 90 and 180 min.  The per-tablet data and the
# printed f2 values are as reproduced by the bootf2 R package (zhengguoxu/bootf2,
# data/shah1998.rda and tests/testthat/test_calcf2.R); the means below are of its 12 units
# (4 decimals).
SHAH_REF = [34.9167, 59.5, 79.2667, 95.075]
SHAH_TESTS = {  # batch: (12-unit mean % dissolved, f2 printed)
    1: ([40.3392, 67.1458, 87.0075, 97.725], 60.03),
    2: ([49.3333, 65.3333, 86.75, 102.8333], 51.08),
    3: ([25.7917, 50.6417, 66.9917, 88.6], 51.19),
    4: ([15.0833, 59.5, 79.2667, 95.075], 50.07),
    5: ([43.3917, 77.9583, 86.325, 98.575], 48.05),
}


@pytest.mark.parametrize("batch", sorted(SHAH_TESTS))
def test_f2_reproduces_the_printed_worked_example(batch: int) -> None:
    """A printed worked example (Shah et al. 1998, above): f2 of each test batch's mean
    profile against the reference's, to the printed two decimals; the FDA rule (one point
    after 85% of the reference) keeps all four times here (the reference passes 85% only
    at 180 min), and batch 5 (48.05) falls below the similarity limit 50."""
    mean, printed = SHAH_TESTS[batch]
    assert round(f2(SHAH_REF, mean, fda_85_rule=True), 2) == printed
    assert round(f2(SHAH_REF, mean), 2) == printed
    assert (printed >= 50.0) == (batch != 5)


def test_crank_curve_is_fitted_back_within_3_percent() -> None:
    t, y = _curve(seed=0)
    rep = fit_release(t, y, "ANB", T, T, DRY_UM)
    d = rep["parameters"]["drug_diffusivity_cm2_s"]
    lo, hi = rep["intervals"]["drug_diffusivity_cm2_s"]
    assert d == pytest.approx(D0, rel=0.03)
    assert lo < D0 < hi
    assert rep["f2"] > 80.0  # the fit against its own noisy data
    assert rep["hindrance_factor"] == 1.0
    # issue 36: D0 stated at its temperature and at the 25 degC an input D0 is read at
    from dosing.units import water_viscosity

    assert rep["drug_diffusivity_temperature_K"] == T
    f = (298.15 / T) * water_viscosity(T) / water_viscosity(298.15)
    assert rep["drug_diffusivity_at_reference_cm2_s"] == pytest.approx(d * f, rel=1e-12)
    assert f < 1.0 and "298.15 K" in rep["drug_diffusivity_note"]


def test_coverage_over_50_seeds() -> None:
    """95% intervals of D0 cover the truth in 90-99% of 50 noise seeds (1% noise)."""
    hits = 0
    for seed in range(50):
        t, y = _curve(seed=1000 + seed)
        lo, hi = fit_release(t, y, "ANB", T, None, DRY_UM)["intervals"][
            "drug_diffusivity_cm2_s"]
        hits += lo < D0 < hi
    assert 45 <= hits <= 49, hits  # 0.90-0.98 of 50 (0.99 x 50 = 49.5)


def test_hindrance_and_refusals() -> None:
    t, y = _curve(seed=2)
    free = fit_release(t, y, "ANB", T, T, DRY_UM, hindrance="free-volume", mesh_size_nm=20.0)
    # the same effective diffusivity, a larger free D0 behind the hindrance
    assert free["effective_diffusivity_cm2_s"] == pytest.approx(D0, rel=0.03)
    assert free["parameters"]["drug_diffusivity_cm2_s"] > D0
    with pytest.raises(ParameterError, match="t_end"):
        fit_release(t, y, "ANB", T, 308.0, DRY_UM)


def test_cli_fit_release(tmp_path, capsys) -> None:
    t, y = _curve(seed=3)
    p = tmp_path / "rel.csv"
    p.write_text("time_min;released (%)\n" + "".join(
        f"{a / 60:.5f};{100 * b:.4f}\n".replace(".", ",") for a, b in zip(t, y, strict=True)))
    png = tmp_path / "rel.png"
    assert main(["fit", "release", str(p), "--gel", "ANB", "--t-start", "300", "--t-end",
                 "300", "--dry-radius-um", "50", "--json", "--plot", str(png)]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["plots"] == [str(png)] and png.stat().st_size > 10_000  # data, fit and band
    assert rep["parameters"]["drug_diffusivity_cm2_s"] == pytest.approx(D0, rel=0.03)
    assert rep["f2"] > 80 and rep["intervals"]["drug_diffusivity_cm2_s"]


RAMP = "Heat to 308 K at 5 K/min"
COARSE = SolverSettings(grid="moving", n=100, rtol=1e-4)  # ~2 s of mechanics (truth: ~1 min)
DEFAULTS = PhysicalConstants().for_gel(ANB.omega)  # the fit's own constants for ANB
D0_RAMP = 3.0e-8  # cm^2/s: its half-release time (~150 s) is of the ramp's 96 s


def ramp_curve(seed: int = 0, noise: float = 0.01) -> tuple[np.ndarray, np.ndarray]:
    """A release curve made under the ramp 300 -> 308 K at 5 K/min (ANB, 50 um dry) with the
    known D0_RAMP: the solute on the full solver's mechanics (the fit's own forward model,
    at COARSE settings), 1% noise."""
    t = np.linspace(10.0, 600.0, 25)
    prot = fp.parse_protocol(T, RAMP)
    mech = protocol_mechanics(ANB, prot, DRY_UM, float(t.max()), DEFAULTS,
                                 COARSE)
    clean = fp.released_under(mech, DrugModel(hindrance="none"), D0_RAMP,
                              DEFAULTS, DRY_UM, t)
    return t, clean + noise * np.random.default_rng(seed).standard_normal(t.size)


def test_release_under_a_ramp_is_fitted_back() -> None:
    """Issue 27: a release under a heating protocol.  One mechanics run (memoised: the data's
    and the fit's are the same run) serves every trial D0.  The fit recovers D0 within 3%
    with an interval that covers it; the isothermal model on the same curve (the bead's
    shrinking ignored) is off by more than 50% and fits visibly worse (f2)."""
    t, y = ramp_curve()
    rep = fit_release(t, y, "ANB", T, None, DRY_UM, protocol=RAMP, settings=COARSE)
    d = rep["parameters"]["drug_diffusivity_cm2_s"]
    lo, hi = rep["intervals"]["drug_diffusivity_cm2_s"]
    assert d == pytest.approx(D0_RAMP, rel=0.03) and lo < D0_RAMP < hi
    assert rep["f2"] > 80.0 and rep["success"] and not rep["warnings"]
    assert rep["drug_diffusivity_temperature_K"] == 308.0
    assert "Heat to 308 K at 5 K/min" in rep["model"] and "moving grid, N = 100" in rep["model"]
    cost = rep["cost"]
    assert cost["solute_runs"] >= 3 and cost["mechanics_cpu_seconds"] > 0.0
    # the squeezing alone releases less than the drug curve (diffusion adds to it)
    assert np.all(np.asarray(rep["squeezed_released"]) <= np.asarray(rep["fitted"]) + 1e-9)
    iso = fit_release(t, y, "ANB", T, None, DRY_UM)
    assert iso["parameters"]["drug_diffusivity_cm2_s"] > 1.5 * D0_RAMP
    assert iso["f2"] < rep["f2"] - 10.0
    with pytest.raises(ParameterError, match="until"):
        fit_release(t, y, "ANB", T, None, DRY_UM,
                    protocol=["Heat to 308 K at 5 K/min", "Hold at 308 K until 30 % released"],
                    settings=COARSE)
    with pytest.raises(ParameterError, match="t_end"):
        fit_release(t, y, "ANB", T, 308.0, DRY_UM, protocol=RAMP)
