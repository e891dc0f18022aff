"""Units of the dose planner: eq. timescale, volumes, the 80 % dose relation (issue 5)."""

import math

import pytest

from dosing import DoseRequest, PhysicalConstants, timescale, water_viscosity
from dosing.units import (
    expelled_volume,
    radius_after_dose,
    stored_volume,
    ul_to_volume,
    volume_to_ul,
)
from solver import ANB, HHT, ParameterError, equilibrium


def test_paper_constants_give_diffusivity_near_1e8_cm2_per_s() -> None:
    # D = k0 kB T / (eta Omega_p) = 8e-20 * 1.380649e-23 * 308 / (1e-3 * 3e-25) m^2/s
    tau = timescale(50.0, 308.0, PhysicalConstants.paper())
    d_exact = 8e-20 * 1.380649e-23 * 308.0 / (1e-3 * 3e-25) * 1e4
    assert tau.diffusivity_cm2_s == pytest.approx(d_exact, rel=1e-12)
    assert 1e-8 < tau.diffusivity_cm2_s < 1.2e-8  # not the 3e-7 the paper calls similar
    assert tau.seconds == pytest.approx((50e-6) ** 2 / (d_exact * 1e-4), rel=1e-12)


def test_default_constants_are_consistent_with_the_gels_omega() -> None:
    """Omega_p = Omega Omega_f (eq. EqlEqn's Omega = Omega_p / Omega_f, water's Omega_f
    3.0e-29 m^3): ANB (Omega 100) tau 22.05 s for a 50 um bead at 308 K, 100x below the
    paper's 2205 s; HHT (Omega 720) 13.9x below it; every request's case resolves it."""
    paper = timescale(50.0, 308.0, PhysicalConstants.paper()).seconds
    anb = timescale(50.0, 308.0, omega=ANB.omega)
    assert anb.seconds == pytest.approx(paper / 100.0, rel=1e-12)
    assert anb.seconds == pytest.approx(22.05, abs=0.01)
    assert 1.0e-6 < anb.diffusivity_cm2_s < 1.2e-6  # within 4x of Tanaka & Fillmore's 3e-7
    assert anb.polymer_volume_m3 == pytest.approx(3e-27, rel=1e-12)
    assert timescale(50.0, 308.0, omega=HHT.omega).seconds == pytest.approx(
        paper * 720 * 3e-29 / 3e-25, rel=1e-12)
    assert PhysicalConstants().for_gel(ANB.omega) == PhysicalConstants(polymer_volume_m3=3e-27)
    assert PhysicalConstants(polymer_volume_m3=1e-26).for_gel(ANB.omega).polymer_volume_m3 \
        == 1e-26  # a given value stays
    with pytest.raises(ParameterError) as err:  # unresolved and no gel: names the field
        timescale(50.0, 308.0)
    assert err.value.field == "constants.polymer_volume_m3"
    req = DoseRequest("ANB", 302.0, 308.0, dose_fraction=0.8, dry_radius_um=50.0)
    assert req.constants.polymer_volume_m3 == pytest.approx(3e-27, rel=1e-12)
    # the paper's constants one flag away: in Python, and as a request dict (HTTP's form)
    assert PhysicalConstants.from_dict({"paper": True}) == PhysicalConstants.paper()
    assert PhysicalConstants.from_dict({"paper": True, "permeability_m2": 1e-19}) == \
        PhysicalConstants.paper(permeability_m2=1e-19)


def test_timescale_scales_with_radius_squared_and_constants() -> None:
    base = timescale(10.0, 308.0, PhysicalConstants.paper()).seconds
    assert timescale(30.0, 308.0, PhysicalConstants.paper()).seconds == pytest.approx(
        9 * base, rel=1e-12)
    c = PhysicalConstants(viscosity_pa_s=2e-3, permeability_m2=4e-20, polymer_volume_m3=6e-25)
    assert timescale(10.0, 308.0, c).seconds == pytest.approx(8 * base, rel=1e-12)


def test_formula_shows_numbers_and_result() -> None:
    f = timescale(50.0, 308.0, PhysicalConstants.paper()).formula
    for part in ("eta Omega_p R^2 / (k0 k_B T_end)", "50 um", "8e-20 m^2", "308 K", "2205 s"):
        assert part in f
    f = timescale(50.0, 308.0, omega=ANB.omega).formula
    for part in ("3e-27 m^3", "22.05 s"):
        assert part in f


def test_water_viscosity_matches_tables() -> None:
    # IAPWS values: 1.0016 mPa s at 20 C, 0.7191 mPa s at 35 C; Vogel is within 2.5 %.
    assert water_viscosity(293.15) == pytest.approx(1.0016e-3, rel=0.01)
    assert water_viscosity(308.15) == pytest.approx(0.7191e-3, rel=0.01)
    c = PhysicalConstants(viscosity_pa_s="water")
    assert c.viscosity(308.15) == water_viscosity(308.15)
    assert timescale(50, 308.15, c, omega=100.0).seconds < timescale(50, 308.15,
                                                                     omega=100.0).seconds


@pytest.mark.parametrize("kw", [{"viscosity_pa_s": -1.0}, {"viscosity_pa_s": "oil"},
                                {"permeability_m2": 0.0}, {"polymer_volume_m3": math.nan}])
def test_bad_constants_name_the_field(kw: dict) -> None:
    name = next(iter(kw))
    with pytest.raises(ParameterError, match=f"constants.{name}"):
        PhysicalConstants(**kw)


def test_stored_fluid_and_80_percent_dose_relation() -> None:
    a0 = 2.3
    assert stored_volume(a0) == pytest.approx(4 * math.pi / 3 * (a0**3 - 1), rel=1e-15)
    a = radius_after_dose(a0, 0.8)
    assert a**3 == pytest.approx(0.2 * a0**3 + 0.8, rel=1e-14)
    assert expelled_volume(a0, a) == pytest.approx(0.8 * stored_volume(a0), rel=1e-14)


@pytest.mark.parametrize("gel,t0,a0,a80", [(ANB, 302.0, 2.29, 1.47), (HHT, 304.0, 2.67, 1.67)])
def test_paper_radii_for_80_percent(gel, t0: float, a0: float, a80: float) -> None:
    start = equilibrium(gel, t0).stretch
    assert round(start, 2) == a0
    # ANB 1.4750, HHT 1.6662: the paper's 1.47 and 1.67 to its printed precision
    assert radius_after_dose(start, 0.8) == pytest.approx(a80, abs=0.0051)


def test_volume_conversion_round_trip() -> None:
    # a dimensionless volume 1 for a 100 um bead is (100 um)^3 = 1e6 um^3 = 1e-3 uL
    assert volume_to_ul(1.0, 100.0) == pytest.approx(1e-3, rel=1e-15)
    assert ul_to_volume(volume_to_ul(3.7, 42.0), 42.0) == pytest.approx(3.7, rel=1e-14)
