"""Gel parameters: presets and validation (issue 2)."""

import math

import pytest

from solver import ANB, HHT, Gel, ParameterError, Permeability, equilibria, preset


def test_presets_match_paper_parameters() -> None:
    assert (ANB.omega, ANB.a0, ANB.b0, ANB.a1, ANB.b1) == (100.0, -12.947, 0.04496, 17.92, -0.0569)
    assert (HHT.omega, HHT.a0, HHT.b0, HHT.a1, HHT.b1) == (720.0, -62.22, 0.20470, -58.28, 0.19044)
    assert preset("anb") is ANB and preset("HHT") is HHT


def test_chi_is_linear_in_temperature_and_polymer_fraction() -> None:
    t, phi = 305.0, 0.6
    assert ANB.chi(t, phi) == pytest.approx(-12.947 + 0.04496 * t + (17.92 - 0.0569 * t) * 0.4)


@pytest.mark.parametrize("omega", [0.0, -1.0, math.nan, math.inf, "x"])
def test_bad_omega_names_field_and_range(omega: object) -> None:
    with pytest.raises(ParameterError, match=r"omega.*> 0"):
        Gel(omega=omega, a0=0, b0=0, a1=0, b1=0)  # type: ignore[arg-type]


@pytest.mark.parametrize("beta", [0.0, 10.0, -1.0, 12.0, math.nan])
def test_bad_beta_names_field_and_range(beta: float) -> None:
    with pytest.raises(ParameterError, match=r"beta.*0 < beta < 10"):
        Permeability("power", beta)


def test_bad_law_and_coefficients() -> None:
    with pytest.raises(ParameterError, match="permeability.law"):
        Permeability("cubic")  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match="a1"):
        Gel(omega=1, a0=0, b0=0, a1=math.inf, b1=0)


@pytest.mark.parametrize("temperature", [273.0, 373.2, math.nan, -5.0])
def test_temperature_outside_liquid_water(temperature: float) -> None:
    with pytest.raises(ParameterError, match=r"temperature.*273\.15-373\.15 K"):
        equilibria(ANB, temperature)


def test_unknown_preset() -> None:
    with pytest.raises(ParameterError, match="gel.*ANB, HHT"):
        preset("XYZ")


def test_power_law_permeability_and_round_trip() -> None:
    gel = HHT.with_permeability("power", 1.5)
    assert gel.permeability(0.5) == pytest.approx(0.5 / 0.5**1.5)
    assert Gel.from_dict(gel.to_dict()) == gel
