"""Doses and schedules in drug mass (dosing/drug*.py) and their command line."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from api.cli import main
from dosing import DoseRequest, PhysicalConstants, SolverSettings
from dosing.payload.cycles import DrugScheduleRequest, plan_drug_schedule
from dosing.payload.drug import DrugModel
from dosing.payload.release import DrugDoseRequest, plan_drug_dose
from dosing.runs.solute import DrugRuns, DrugScenario, drug_settings
from solver.errors import ParameterError
from solver.solute import crank_sphere_finite

# ell = 0.01 (N = 400 Lagrangian cells): the coarsest ladder rung of the benchmarks; drug
# runs at the planner's default ell = 0.005 (N = 800) behave alike, twice as slowly
SETTINGS = SolverSettings(interfacial_length=0.01)
PAPER = PhysicalConstants.paper()  # these drugs' D0 / D_gel were set at the paper's tau
BALANCE = 1e-10
# a protein-like drug: D0 = 1e-7 cm^2/s in water at 25 degC (Stokes-Einstein radius 24.5 nm
# with water's viscosity) in a swollen mesh of 60 nm (xi_dry = 26 nm): free-volume law
# (Lustig & Peppas, Y = 1) with sieving; it passes the swollen gel (r_s / xi = 0.41) and is
# held by the shrunken shell (issue 28).  In a 23 nm mesh (the README's first protein) it
# is larger than the swollen mesh and never leaves (test below).
PROTEIN = DrugModel(diffusivity_cm2_s=1e-7, mesh_size_nm=60.0, load_ug=1.0)
# a small drug: D0 = 1e-6 cm^2/s (r_s = 2.45 nm) in the gel's own 4 nm dry mesh
SMALL = DrugModel(diffusivity_cm2_s=1e-6, load_ug=1.0)




def test_no_diffusion_dose_is_the_fluid_answer(planner) -> None:
    req = DrugDoseRequest("ANB", 302, 308, DrugModel(load_ug=2.0), drug_mass_ug=0.6,
                          dry_radius_um=50)
    ans = plan_drug_dose(planner, req)
    fluid = planner.dose(DoseRequest("ANB", 302, 308, dose_fraction=0.3, dry_radius_um=50))
    assert ans.time == fluid.time and ans.model == fluid.model == "front-sharp"
    assert ans.dose_fraction == pytest.approx(0.3) and ans.leaked_before_heating == 0.0
    assert ans.mechanism.startswith("squeezed out") and math.isinf(ans.leak_time_10pct)


def test_protein_dose_leaks_while_it_waits_as_crank_says(planner) -> None:
    # At T_start nothing flows and the bead is uniform: the leak before heating is Crank's
    # series with the hindered diffusivity (the solute's own test bounds it by 1e-3).
    drug = DrugModel(diffusivity_cm2_s=1e-6, load_ug=1.0, release_volume_ul=0.1)
    req = DrugDoseRequest("ANB", 302, 308, drug, dose_fraction=0.2, wait=0.002,
                          dry_radius_um=50, settings=SETTINGS)
    ans = plan_drug_dose(planner, req)
    sol = req.solute
    d_eff = sol.diffusivity * sol.hindrance.factor(1 - 1 / req.start_radius**3)
    # the 0.1 uL medium holds 16 bead volumes: Crank's well-stirred sphere, alpha = V / W0
    alpha = sol.release_volume / (req.start_radius**3 - 1.0)
    want = crank_sphere_finite(np.array([0.002]), d_eff, req.start_radius, alpha)[0]
    assert ans.leaked_before_heating == pytest.approx(want, abs=2e-3)
    assert ans.model == "full" and ans.mass_balance_error < BALANCE
    assert ans.squeezed_fraction + ans.diffused_fraction == pytest.approx(0.2)
    assert ans.peclet is not None and ans.peclet > 0.0 and "D0 = 0" in ans.split
    assert "xi_dry = 4 nm" in ans.mesh and "none" in ans.permeability_law
    assert ans.drug_diffusivity_cm2_s == pytest.approx(drug.d0_cm2_s(308.0), rel=1e-12)
    d_gel = req.constants.diffusivity(308.0) * 1e4  # the gel's R^2 / tau in cm^2/s
    assert ans.effective_diffusivity_cm2_s == pytest.approx(d_eff * d_gel, rel=1e-12)
    released = ans.leaked_before_heating + 0.2
    grown_ul = ans.fluid_fraction * (req.start_radius**3 - 1) * 4 * math.pi / 3 * 50**3 / 1e9
    assert ans.medium_concentration_ug_per_ul == pytest.approx(released / (0.1 + grown_ul),
                                                               rel=1e-3)
    # issue 12: the drug runs state the fluid answers' truth (model, ell, bead size)
    assert ans.interfacial_length == 0.01 and ans.bead_dry_radius_um == 50
    assert "given interfacial length ell = 0.01" in ans.truth and "moving grid" in ans.truth


@pytest.mark.parametrize("kwargs,field", [
    ({"diffusivity_cm2_s": -1e-7}, "drug.diffusivity_cm2_s"),
    ({"diffusivity_cm2_s": math.nan}, "drug.diffusivity_cm2_s"),
    ({"diffusivity_cm2_s": math.inf}, "drug.diffusivity_cm2_s"),
    ({"partition": 0.0}, "drug.partition"), ({"partition": -1.0}, "drug.partition"),
    ({"release_volume_ul": 1e-4}, "drug.release_volume_ul"),  # smaller than the bead
    ({"load_ug": 1.0, "mass": 1.5}, "drug_mass_ug"),  # above the load
    ({"fraction": 1.0}, "dose_fraction"),
])
def test_bad_drug_dose_names_the_field(kwargs: dict, field: str) -> None:
    mass = kwargs.pop("mass", None)
    fraction = kwargs.pop("fraction", None if mass else 0.3)
    with pytest.raises(ParameterError) as exc:
        DrugDoseRequest("ANB", 302, 308, DrugModel(**kwargs) if "partition" not in kwargs
                        and "diffusivity_cm2_s" not in kwargs else kwargs,
                        dose_fraction=fraction, drug_mass_ug=mass, dry_radius_um=50)
    assert exc.value.field == field


def test_a_solute_larger_than_the_swollen_mesh_cannot_be_dosed(planner) -> None:
    # D0 = 1e-7 cm^2/s (r_s = 24.5 nm) in a 23 nm swollen mesh: excluded everywhere, so the
    # dose is refused at once (the first horizon releases nothing), naming the field
    drug = DrugModel(diffusivity_cm2_s=1e-7, mesh_size_nm=23.0, load_ug=1.0)
    req = DrugDoseRequest("ANB", 302, 308, drug, dose_fraction=0.2, dry_radius_um=50,
                          settings=SETTINGS)
    with pytest.raises(ParameterError) as exc:
        plan_drug_dose(planner, req)
    assert exc.value.field == "dose_fraction" and "shell holds" in str(exc.value)


def test_schedule_doses_above_the_load_are_refused() -> None:
    with pytest.raises(ParameterError) as exc:
        DrugScheduleRequest("ANB", 302, 308, PROTEIN, doses_ug=[0.5, 0.6], rests=[0.5])
    assert exc.value.field == "doses_ug"


def _check(ans, doses, tol=0.01) -> dict:
    cor = ans.corrected
    assert cor["met"] and cor["mass_balance_error"] < BALANCE
    assert np.allclose(cor["delivered_fractions"], doses, rtol=tol, atol=0)
    assert len(cor["rest_leak_fractions"]) == len(doses) - 1
    return cor


@pytest.mark.slow
def test_anb_drug_schedule_without_diffusion_dilutes(planner) -> None:
    # ANB [0.3, 0.3, 0.3] of the load, rests [0.5, 0.5] (README "Drug release").
    req = DrugScheduleRequest("ANB", 302, 308, DrugModel(load_ug=1.0), doses=[0.3] * 3,
                              rests=[0.5, 0.5], dry_radius_um=50, settings=SETTINGS)
    ans = plan_drug_schedule(planner, req)
    cor = _check(ans, [0.3] * 3)
    fluid, drug = cor["fluid_fractions"], cor["delivered_fractions"]
    assert fluid[0] == pytest.approx(drug[0], abs=1e-6)  # the first heating: drug = fluid
    assert fluid[1] > 1.5 * drug[1] and fluid[2] > 2.0 * drug[2]  # diluted by the rests
    assert max(abs(x) for x in cor["rest_leak_fractions"]) < 1e-12  # no diffusion: no leak
    assert ans.protocol_check["delivered_fractions"][0] < 0.3  # hold times: too short first
    assert not ans.warnings
    # the simulated schedule's numerical part: the corrected protocol on n / 2 cells
    # (measured 1.3e-4 of a dose at ell = 0.01)
    u = ans.uncertainty
    assert 0.0 < u.numerical.relative < 0.01 and "200 cells instead of 400" in u.numerical.text
    assert u.interfacial_length_range.relative is None and "--validate" in u.model_form.text


@pytest.mark.slow
def test_anb_drug_schedule_of_a_protein(planner) -> None:
    # Issue 28: the protein passes the swollen gel (r_s / xi = 0.41) and is held by the
    # collapsed shell, so a rest at T_start, not a heating, lets most of it out: measured on
    # 200 cells, a 0.02 heating releases 0.35 and the 0.5 rest after it 0.65 of the load.
    req = DrugScheduleRequest("ANB", 302, 308, PROTEIN, doses=[0.3] * 3, rests=[0.5, 0.5],
                              dry_radius_um=50, settings=SETTINGS, constants=PAPER)
    ans = plan_drug_schedule(planner, req)
    assert not ans.corrected["met"]
    assert any("rest 1 leaks" in w for w in ans.warnings)
    check = ans.protocol_check
    assert check["rest_leak_fractions"][0] > 0.3  # more than a dose leaks in the first rest
    assert sum(check["delivered_fractions"]) + sum(check["rest_leak_fractions"]) + \
        check["in_gel_after"] == pytest.approx(1.0, abs=1e-9)
    # the same schedule into 1 uL of medium (1000 bead volumes: nearly a sink)
    finite = DrugScheduleRequest("ANB", 302, 308, DrugModel(**{**PROTEIN.to_dict(),
                                                                "release_volume_ul": 1.0}),
                                 doses=[0.3] * 3, rests=[0.5, 0.5], dry_radius_um=50,
                                 settings=SETTINGS, correct=False, constants=PAPER)
    conc = plan_drug_schedule(planner, finite).protocol_check["medium_concentration_ug_per_ul"]
    assert len(conc) == 3 and 0.3 / 1.01 < conc[0] < 0.3 * 1.01 and np.all(np.diff(conc) >= 0)


@pytest.mark.slow
def test_a_leaky_drug_cannot_meet_its_later_doses(planner) -> None:
    drug = DrugModel(diffusivity_cm2_s=1e-6, load_ug=1.0)  # a small drug: it leaks freely
    req = DrugScheduleRequest("ANB", 302, 308, drug, doses=[0.3] * 3, rests=[0.5, 0.5],
                              settings=SETTINGS, check_protocol=False, constants=PAPER)
    ans = plan_drug_schedule(planner, req)
    assert not ans.corrected["met"] and len(ans.corrected["actuation_times"]) == 1
    assert "medium_concentration_ug_per_ul" not in ans.corrected  # a perfect sink
    assert any("no actuation time meets dose 2" in w for w in ans.warnings)


def test_drug_runs_are_cached_in_their_own_table(planner, tmp_path) -> None:
    req = DrugDoseRequest("ANB", 302, 308, PROTEIN, dose_fraction=0.1, settings=SETTINGS)
    sc = DrugScenario(req.gel, 302.0, ((0.02, 308.0),), req.solute, "swollen",
                      drug_settings(SETTINGS))
    runs = DrugRuns(planner)
    first = runs.run(sc)
    again = DrugRuns(planner).cached(sc)
    assert again is not None and np.array_equal(again.released_fraction,
                                                first.released_fraction)
    assert len(planner.cache) == 0  # the validation table is untouched
    runs.close()


# ------------------------------------------------------------------------ command line

def test_release_command_json(capsys) -> None:
    rc = main(["release", "--gel", "ANB", "--t-start", "302", "--t-end", "308", "--until",
               "0.1", "--dry-radius-um", "50", "--drug-diffusivity-cm2-s", "0", "--n", "200",
               "--samples", "400", "--json"])
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    for key in ("t", "seconds", "released_fraction", "expelled_fraction",
                "effective_diffusivity_cm2_s"):
        assert key in out
    rel, exp = np.array(out["released_fraction"]), np.array(out["expelled_fraction"])
    assert np.max(np.abs(rel - exp)) < 1e-6 and out["mass_balance_error"] < BALANCE
    assert out["effective_diffusivity_cm2_s"] == 0.0
    assert out["seconds"][-1] == pytest.approx(0.1 * out["timescale_seconds"])


@pytest.mark.parametrize("extra,field", [
    (["--drug-diffusivity-cm2-s=-1e-7"], "drug.diffusivity_cm2_s"),
    (["--drug-diffusivity-cm2-s", "nan"], "drug.diffusivity_cm2_s"),
    (["--partition", "0"], "drug.partition"),
    (["--release-volume-ul", "1e-5", "--dry-radius-um", "50"], "drug.release_volume_ul"),
])
def test_release_command_bad_input_exits_2(extra, field, capsys) -> None:
    rc = main(["release", "--t-start", "302", "--t-end", "308", "--until", "0.1", *extra])
    assert rc == 2 and field in capsys.readouterr().err


def test_dose_command_drug_above_the_load_exits_2(tmp_path, capsys) -> None:
    rc = main(["dose", "--t-start", "302", "--t-end", "308", "--drug-mass-ug", "3",
               "--load-ug", "2", "--drug-diffusivity-cm2-s", "1e-7", "--cache",
               str(tmp_path / "c.sqlite")])
    assert rc == 2 and "drug_mass_ug" in capsys.readouterr().err
    rc = main(["schedule", "--t-start", "302", "--t-end", "308", "--doses", "0.5", "0.6",
               "--rests", "0.5", "--drug-diffusivity-cm2-s", "0", "--cache",
               str(tmp_path / "c.sqlite")])
    assert rc == 2 and "doses" in capsys.readouterr().err


def test_release_plot_and_file(tmp_path) -> None:
    from api.plots.release import draw_release
    from solver.solute import ReleaseResult, Solute, simulate_release

    _, rel = simulate_release("ANB", 302, Solute(diffusivity=2.0),
                              protocol=[(0.02, 308), (0.05, 302)], n=100, samples=200)
    png = draw_release(rel, tmp_path / "rel.png", tau_seconds=2205.0, doses=[0.2])
    assert png.stat().st_size > 10_000
    back = ReleaseResult.load(rel.save(tmp_path / "rel.npz"))
    assert np.array_equal(back.released_fraction, rel.released_fraction)
    assert back.mass_balance_error == rel.mass_balance_error < BALANCE


@pytest.mark.slow
def test_drug_answer_states_its_uncertainty_in_three_parts(planner) -> None:
    """Every answer states its error in parts: the drug run at n / 2 cells gives the
    numerical part; the mechanics' interfacial-length and model-form parts come from the
    fluid validation at the fluid fraction expelled by then, once it is cached (before, they
    are not measured and the text says how to measure them)."""
    req = DrugDoseRequest("ANB", 302, 308, SMALL, dose_fraction=0.5, dry_radius_um=50,
                          settings=SETTINGS, constants=PAPER)
    ans = plan_drug_dose(planner, req)
    u = ans.uncertainty
    assert u.numerical.relative is not None and u.numerical.relative < 0.01, u.numerical.text
    assert u.interfacial_length_range.relative is None and u.model_form.relative is None
    assert f"dose_fraction = {ans.fluid_fraction:.3g}" in u.interfacial_length_range.text
    fluid = planner.dose(DoseRequest("ANB", 302, 308, dose_fraction=ans.fluid_fraction,
                                     dry_radius_um=50, settings=SETTINGS), validate=True)
    again = plan_drug_dose(planner, req).uncertainty
    assert again.numerical == u.numerical
    for part in ("interfacial_length_range", "model_form"):
        assert getattr(again, part).relative == getattr(fluid.uncertainty, part).relative
        assert "from the fluid validation" in getattr(again, part).text


@pytest.mark.slow
def test_release_at_its_defaults_meets_the_validated_dose(tmp_path, capsys) -> None:
    """One truth for every way in (issue 21): a D0 = 0 ``thermogel release`` at its defaults
    (the planner's truth: moving grid at the bead's own ell), run to the validated 80 %
    time, releases 0.800 +- 0.004 of the load (drug = fluid exactly when D0 = 0)."""
    from dosing import DoseRequest, plan_dose

    ans = plan_dose(DoseRequest("ANB", 302.0, 308.0, dose_fraction=0.8, dry_radius_um=50.0),
                    validate=True, cache_path=str(tmp_path / "c.sqlite"))
    t80 = ans.validation.time
    assert main(["release", "--gel", "ANB", "--t-start", "302", "--t-end", "308", "--until",
                 repr(t80), "--dry-radius-um", "50", "--drug-diffusivity-cm2-s", "0",
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["grid"] == "moving" and out["interfacial_length"] == ans.interfacial_length
    assert out["released_fraction"][-1] == pytest.approx(0.8, abs=0.004)
