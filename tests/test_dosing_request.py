"""Dose and schedule requests: validated on construction, errors name the field (issue 5)."""

import pytest

from dosing import DoseRequest, ScheduleRequest, SolverSettings
from dosing.units import stored_volume, volume_to_ul
from solver import ANB, ParameterError

JUMP = {"gel": "ANB", "t_start": 302.0, "t_end": 308.0}


def test_fraction_volume_and_drug_mass_agree() -> None:
    by_fraction = DoseRequest(**JUMP, dose_fraction=0.4, dry_radius_um=50.0)
    stored_ul = volume_to_ul(stored_volume(by_fraction.start_radius), 50.0)
    by_volume = DoseRequest(**JUMP, dose_volume_ul=0.4 * stored_ul, dry_radius_um=50.0)
    by_mass = DoseRequest(**JUMP, drug_mass_ug=0.4 * stored_ul * 2.5,
                          concentration_ug_per_ul=2.5, dry_radius_um=50.0)
    assert by_volume.fraction == pytest.approx(0.4, rel=1e-12)
    assert by_mass.fraction == pytest.approx(0.4, rel=1e-12)
    assert by_fraction.gel is ANB


def test_swollen_radius_gives_dry_radius() -> None:
    r = DoseRequest(**JUMP, dose_fraction=0.5, swollen_radius_um=114.6)
    assert r.bead_dry_radius_um == pytest.approx(114.6 / r.start_radius, rel=1e-14)


@pytest.mark.parametrize("kw,field", [
    ({"dose_fraction": 1.5}, "dose_fraction"),          # more than the stored fluid
    ({"dose_fraction": 0.98}, "dose_fraction"),         # more than the gel can expel at T_end
    ({"dose_fraction": -0.1}, "dose_fraction"),
    ({"dose_fraction": 0.5, "dose_volume_ul": 1e-3}, "dose_volume_ul"),
    ({}, "dose_fraction"),
    ({"dose_volume_ul": 1.0, "dry_radius_um": 50.0}, "dose_volume_ul"),  # > stored 5.8e-3 uL
    ({"dose_volume_ul": 1e-3}, "dry_radius_um"),        # a volume needs a bead size
    ({"drug_mass_ug": 1e-3, "dry_radius_um": 50.0}, "concentration_ug_per_ul"),
    ({"dose_fraction": 0.5, "dry_radius_um": -50.0}, "dry_radius_um"),
    ({"dose_fraction": 0.5, "swollen_radius_um": 0.0}, "swollen_radius_um"),
    ({"dose_fraction": 0.5, "branch": "middle"}, "branch"),
    ({"dose_fraction": 0.5, "settings": {"n": 5}}, "settings.n"),
    ({"dose_fraction": 0.5, "settings": {"interfacial_length": -1.0}},
     "settings.interfacial_length"),
])
def test_bad_doses_and_sizes_name_the_field(kw: dict, field: str) -> None:
    with pytest.raises(ParameterError) as err:
        DoseRequest(**JUMP, **kw)
    assert err.value.field == field
    assert "valid range" in str(err.value)


def test_dose_larger_than_stored_fluid_says_so() -> None:
    with pytest.raises(ParameterError, match="larger than the stored fluid"):
        DoseRequest(**JUMP, dose_fraction=1.2)


@pytest.mark.parametrize("t_start,t_end", [(308.0, 302.0), (302.0, 302.0)])
def test_swelling_jump_asked_to_release_names_t_end(t_start: float, t_end: float) -> None:
    with pytest.raises(ParameterError, match="releases none") as err:
        DoseRequest("ANB", t_start, t_end, dose_fraction=0.5)
    assert err.value.field == "t_end"


@pytest.mark.parametrize("gel", ["PNIPAM", 42, {"omega": 1.0}])
def test_unknown_gel_names_the_field(gel: object) -> None:
    with pytest.raises(ParameterError) as err:
        DoseRequest(gel, 302.0, 308.0, dose_fraction=0.5)
    assert err.value.field == "gel"


def test_temperature_out_of_range_names_the_field() -> None:
    with pytest.raises(ParameterError) as err:
        DoseRequest("ANB", 250.0, 308.0, dose_fraction=0.5)
    assert err.value.field == "t_start"


def test_schedule_validation() -> None:
    s = ScheduleRequest(**JUMP, doses=[0.3, 0.3, 0.3], rests=[0.5, 0.5])
    assert s.doses == (0.3, 0.3, 0.3) and s.rests == (0.5, 0.5)
    assert s.settings == SolverSettings()
    with pytest.raises(ParameterError) as err:
        ScheduleRequest(**JUMP, doses=[0.3, 0.3], rests=[0.5, 0.5])
    assert err.value.field == "rests"
    with pytest.raises(ParameterError) as err:
        ScheduleRequest(**JUMP, doses=[0.5, 0.5], rests=[0.5])
    assert err.value.field == "doses"
    with pytest.raises(ParameterError) as err:
        ScheduleRequest(**JUMP, doses=[0.3, 0.3], rests=[-1.0])
    assert err.value.field == "rests[0]"
    with pytest.raises(ParameterError) as err:
        ScheduleRequest(**JUMP, doses=[0.3, 0.3], rests_seconds=[60.0])
    assert err.value.field == "dry_radius_um"


def test_schedule_rests_in_seconds_use_tau() -> None:
    s = ScheduleRequest(**JUMP, doses=[0.3, 0.3], rests_seconds=[22.05], dry_radius_um=50.0)
    assert s.rests[0] == pytest.approx(1.0, rel=1e-3)  # tau = 22.05 s for 50 um ANB at 308 K
