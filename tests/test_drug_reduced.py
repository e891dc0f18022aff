"""The reduced drug model (issue 23): the solute on the front model's bead.

Analytic limits: a bead waiting at T_start (no front) is Crank's sphere into a perfect sink
(eq. 6.20); D0 = 0 without sieving is the fluid answer; D0 -> 0 tends to it.  Then where it
answers and how its answer states model, error and the way to the full solver.
"""

from __future__ import annotations

import numpy as np
import pytest

from dosing import PhysicalConstants
from dosing.model_choice import front_run
from dosing.payload.drug import DrugModel
from dosing.payload.reduced import MEASURED, STATED_LIMIT, stated_error
from dosing.payload.release import DrugDoseRequest, plan_drug_dose
from solver.errors import ParameterError
from solver.front.solute import dry_grid, front_geometry, front_release, time_to_release
from solver.gel import ANB
from solver.solute import Hindrance, Solute, crank_sphere

FREE = Hindrance("none", convective=False)


@pytest.fixture(scope="module")
def anb():
    return front_run(ANB, 302.0, 308.0, "swollen", True)


def test_geometry_conserves_solid_and_follows_the_front(anb):
    g = front_geometry(anb, cells=48)
    sp = 1.0 - anb.phi_plus
    # the edge is the front model's radius at every sample before the centre
    inside = g.front > 0.0
    assert np.allclose(g.radius[inside], anb.curve.radius(g.front[inside]), rtol=1e-12)
    # every cell holds its dry volume: fluid volumes positive, porosities phi_- or phi_+
    cells = np.diff(g.s3, axis=1)
    dw = np.diff(g.dry)
    phi = 1.0 - dw[None, :] / cells
    assert np.all((phi >= anb.phi_plus - 1e-9) & (phi <= anb.phi_minus + 1e-9))
    assert g.radius[-1] == pytest.approx(sp ** (-1.0 / 3.0), rel=1e-12)  # collapsed
    assert np.all(np.diff(g.t) > 0.0)


# measured: 3.1e-4 (48 cells), 7.8e-5 (96), 2.0e-5 (192): second order in the grid
@pytest.mark.parametrize("cells, tol", [(48, 5e-4), (192, 4e-5)])
def test_waiting_bead_is_cranks_sphere(anb, cells, tol):
    """No front while the bead waits at T_start: Crank's eq. 6.20 with D0 (no hindrance)
    in the swollen sphere (the release's largest error over the wait)."""
    d, wait = 3.0, 0.05
    rel = front_release(anb, Solute(d, FREE), cells=cells, wait=wait, rtol=1e-6)
    a0 = anb.curve.levels.a0
    t = rel.t[(rel.t > 0.0) & (rel.t <= wait)]
    exact = crank_sphere(t, d, a0)
    got = np.interp(t, rel.t, rel.released_fraction)
    assert np.max(np.abs(got - exact)) < tol
    assert rel.mass_balance_error < 1e-12


def test_crank_error_converges(anb):
    errs = []
    for cells in (24, 48, 96):
        rel = front_release(anb, Solute(3.0, FREE), cells=cells, wait=0.05, rtol=1e-7)
        t = rel.t[(rel.t > 1e-4) & (rel.t <= 0.05)]
        errs.append(np.max(np.abs(np.interp(t, rel.t, rel.released_fraction)
                                  - crank_sphere(t, 3.0, anb.curve.levels.a0))))
    assert errs[2] < errs[1] < errs[0]
    assert errs[1] / errs[2] > 3.0  # second order (measured 3.97)


def test_no_diffusion_is_the_fluid_answer(anb):
    rel = front_release(anb, Solute(0.0))
    assert np.allclose(rel.released_fraction, np.maximum(rel.expelled_fraction, 0.0),
                       atol=1e-12)
    for f in (0.1, 0.3, 0.5, 0.8, 0.9):
        # the samples' cubic against the front model's exact curve (measured < 3e-5)
        assert time_to_release(rel, f) == pytest.approx(anb.time_to_fraction(f), rel=1e-4)


def test_small_diffusivity_tends_to_the_fluid_answer(anb):
    gaps = []
    for d in (1e-2, 1e-3, 1e-4):
        rel = front_release(anb, Solute(d, FREE))
        gaps.append(abs(time_to_release(rel, 0.5) / anb.time_to_fraction(0.5) - 1.0))
    assert gaps[2] < gaps[1] < gaps[0]
    assert gaps[2] < 1e-4  # measured 4.8e-4, 4.7e-5, 7e-6


def test_diffusion_speeds_release_and_hindrance_slows_it(anb):
    t_free = time_to_release(front_release(anb, Solute(10.0, FREE)), 0.5)
    t_hind = time_to_release(front_release(anb, Solute(10.0, Hindrance(
        "ogston", fiber=1.0, convective=False))), 0.5)
    t_fluid = anb.time_to_fraction(0.5)
    assert t_free < t_hind < t_fluid


def test_a_shorter_run_gives_the_same_release(anb):
    """Stopping on the way (horizon before the centre) changes nothing before the stop."""
    sol = Solute(10.0, FREE)
    full = front_release(anb, sol)
    short = front_release(anb, sol, horizon=0.02)
    assert short.t[-1] == pytest.approx(0.02)
    assert time_to_release(short, 0.5) == pytest.approx(time_to_release(full, 0.5), rel=2e-3)


def test_bad_grid_is_refused():
    with pytest.raises(ParameterError, match="cells"):
        dry_grid(3)
    with pytest.raises(ParameterError, match="grading"):
        dry_grid(48, 9.0)


# ------------------------------------------------------------------ the answers


def _req(**drug):
    kw = {"dose_fraction": drug.pop("dose_fraction", 0.5),
          "dry_radius_um": drug.pop("dry_radius_um", 50.0), "wait": drug.pop("wait", None),
          "settings": drug.pop("settings", None),
          # the table's D0 / D_gel rows were picked as D0 in cm^2/s at the paper's D_gel
          "constants": drug.pop("constants", PhysicalConstants.paper())}
    return DrugDoseRequest("ANB", 302.0, 308.0, DrugModel(**drug), **kw)


class NoRuns:
    """Drug runs that must not be asked for (the reduced model answers)."""

    def run(self, sc):
        raise LookupError("full solver asked")


needs_table = pytest.mark.skipif(not MEASURED, reason="no measured table")


@needs_table
def test_reduced_model_answers_where_measured():
    req = _req(diffusivity_cm2_s=1e-7, hindrance="none", dose_fraction=0.5)
    ans = plan_drug_dose(None, req, runs=NoRuns())
    assert ans.model == "front-solute"
    err = ans.uncertainty.model_form.relative
    assert err is not None and 0.0 <= err <= STATED_LIMIT
    assert "validate" in ans.uncertainty.model_form.text
    assert ans.uncertainty.numerical.relative == pytest.approx(0.01)  # unsieved (sec. 3)
    assert "reduced drug model" in ans.note
    assert ans.interfacial_length == pytest.approx(8e-5)
    assert ans.mass_balance_error < 1e-10
    assert ans.squeezed_fraction + ans.diffused_fraction == pytest.approx(0.5)
    # validate asks the full solver
    with pytest.raises(LookupError, match="full solver asked"):
        plan_drug_dose(None, req, runs=NoRuns(), validate=True)


@pytest.mark.parametrize("change", [
    {"wait": 0.01},  # a wait at T_start: not measured
    {"release_volume_ul": 1.0},  # a finite medium: not measured
    {"solute_radius_nm": 3.0, "hindrance": "free-volume"},  # more hindered than measured
    {"dry_radius_um": 10.0},  # a bead far from the measured 50 um
    {"settings": {"interfacial_length": 0.01}},  # not the bead's own ell
])
def test_full_solver_answers_outside_the_region(change):
    drug = {"diffusivity_cm2_s": 1e-7, "hindrance": "none", **change}
    req = _req(**drug)
    with pytest.raises(LookupError, match="full solver asked"):
        plan_drug_dose(None, req, runs=NoRuns())


def test_stated_error_is_none_outside_measured_ranges():
    assert stated_error(Solute(0.0), 0.5) is None  # no diffusion: the fluid answer
    assert stated_error(Solute(1e-6, FREE), 0.5) is None  # below the measured D0
    assert stated_error(Solute(1.0, FREE), 0.05) is None  # below the measured doses
    assert stated_error(Solute(1.0, FREE), 0.95) is None


@pytest.mark.parametrize("fraction", [0.01, 0.1, 0.5, 0.7])
def test_leak_time_is_cranks_root(fraction):
    """dosing.payload.drug.leak_time: the closed root of Crank 6.21 (fraction <= 0.5), else the
    bisection on 6.20; either way Crank's series there gives the fraction back."""
    from dosing.payload.drug import leak_time

    sol = Solute(2.0, FREE)
    t = leak_time(sol, 2.29, fraction)
    assert crank_sphere(np.array([t]), 2.0, 2.29)[0] == pytest.approx(fraction, abs=1e-12)


@needs_table
def test_a_drug_between_two_measured_sizes_needs_both():
    """Ogston at D0 = 1e-8 cm^2/s, 90 %: the 1 nm drug is within the stated error, the
    0.25 nm one is not (the table), so a 0.5 nm drug between them is not answered."""
    def err(r_s):
        req = _req(diffusivity_cm2_s=1e-8, hindrance="ogston", solute_radius_nm=r_s,
                   fiber_radius_nm=1.0, dose_fraction=0.9)
        return stated_error(req.solute, req.fraction)

    assert err(1.0) is not None and err(1.0) <= STATED_LIMIT
    assert err(0.25) is None
    assert err(0.5) is None
