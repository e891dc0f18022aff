"""dosing.quantity: unit strings and Quantities at the edges, one unit table."""

import math

import pytest

from dosing.quantity import kelvin, micrometres, registry, seconds, to_unit
from solver.errors import ParameterError


@pytest.mark.parametrize(("value", "kelvins"), [
    (308, 308.0), ("308", 308.0), ("308 K", 308.0), ("29 degC", 302.15), ("25 °C", 298.15),
])
def test_temperatures(value, kelvins):
    assert kelvin(value) == pytest.approx(kelvins, abs=1e-12)


def test_durations_lengths_rates():
    assert seconds("10 min") == 600.0
    assert seconds("2 h") == 7200.0
    assert micrometres("0.1 mm") == pytest.approx(100.0)
    assert micrometres(registry().Quantity(50, "um")) == pytest.approx(50.0)
    assert to_unit("5 K/min", "temperature_rate", "rate") == pytest.approx(5 / 60)


@pytest.mark.parametrize("bad", ["50 K", "fifty", "", True, float("nan"), "inf um"])
def test_refused_naming_the_field(bad):
    with pytest.raises(ParameterError) as err:
        micrometres(bad, "dry_radius_um")
    assert err.value.field == "dry_radius_um"


def test_plain_numbers_need_no_pint():
    assert math.isclose(kelvin(300.5), 300.5)


@pytest.mark.parametrize("bad", ["9**9**9 s", "2**99 um", "(3)^9 s", "m**22", "9 ^ 9 s",
                                 "1" * 101])
def test_powers_that_would_hang_pint_are_refused(bad):
    """pint evaluates powers exactly: a number raised to a power, a long or chained power
    and over-long strings are refused at once, naming the field."""
    with pytest.raises(ParameterError) as err:
        to_unit(bad, "time", "protocol[0].duration")
    assert err.value.field == "protocol[0].duration"


def test_unit_powers_still_read():
    assert to_unit("1e-7 cm^2/s", "diffusivity", "d0") == pytest.approx(1e-7)
    assert to_unit("3 m ** 2", "permeability", "k0") == pytest.approx(3.0)
