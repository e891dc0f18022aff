"""The front model against the full solver (paper fig. 13 and sec. Application).

Reference runs: the full solver on the paper's Eulerian grid at N = 400 and on the Lagrangian
grid at N = 100 (its dose times barely depend on N: 80% dose 0.1175 at N = 100, 0.1161 at 400).
In the front regime the full model is ill-posed and its front speed depends on the grid (the
Lagrangian front is 20-60% slower), so the dose-time tolerances below are the measured errors
(`benchmarks/front_model.py --n-lagrangian 100`) plus 3 points, per grid and start.
"""

import numpy as np
import pytest

from solver import ANB, HHT
from solver.front import flux_constant, fraction_radius, front_levels, front_trajectory
from solver.front.evolve import front_of_radius

pytestmark = pytest.mark.slow

CASES = {"ANB": (ANB, 302.0, 308.0, 0.001, 1.47), "HHT": (HHT, 304.0, 308.0, 0.01, 1.67)}
UNTIL = {("ANB", "eulerian"): 0.21, ("HHT", "eulerian"): 0.23,
         ("ANB", "lagrangian"): 0.21, ("HHT", "lagrangian"): 0.34}
FRACTIONS = np.arange(1, 10) / 10.0
N = {"eulerian": 400, "lagrangian": 100}
# max |relative error| of the 10..90% dose times, measured on those grids:
# (gel, grid): (equilibrium start, full@t0 conservative, full@t0 paper)
MEASURED = {("ANB", "eulerian"): (0.501, 0.315, 0.298), ("HHT", "eulerian"): (0.607, 0.139, 0.184),
            ("ANB", "lagrangian"): (0.609, 0.335, 0.166),
            ("HHT", "lagrangian"): (0.868, 0.516, 0.529)}


@pytest.fixture(scope="module")
def runs() -> dict:
    from solver.full import simulate

    return {(name, grid): simulate(CASES[name][0], CASES[name][1], CASES[name][2],
                                   until=UNTIL[name, grid], grid=grid, n=N[grid], every=1e-3)
            for name in CASES for grid in ("eulerian", "lagrangian")}


def paper_start(full, t0: float) -> tuple[float, float, float]:
    a, rf, _ = full.state_at(t0)
    return t0, a, rf


def test_flux_constant_matches_the_full_solution_at_t02(runs: dict) -> None:
    full = runs["ANB", "eulerian"]
    lev = front_levels(ANB, 302, 308)
    a, rf, _ = full.state_at(0.2)
    ref = a * a * float(np.interp(0.2, full.step_t, full.step_rate))
    amp = flux_constant(a, rf, lev.phi_minus, lev.phi_plus, ANB, 308)
    # with the tracked front: A = -1.950, and A / R_f is the paper's printed -3.25
    assert amp == pytest.approx(-1.950, abs=0.005)
    assert amp / rf == pytest.approx(-3.25, abs=0.01)
    assert amp == pytest.approx(ref, rel=0.04)  # measured 3.6%: the tracked front sits inside
    # the front that conserves solid (the diffuse front's steepest point is ~4 cells in)
    x = float(front_of_radius(lev, 1.0, a))
    assert flux_constant(a, x, lev.phi_minus, lev.phi_plus, ANB, 308) == pytest.approx(
        ref, rel=0.02)  # measured 0.46%


@pytest.mark.parametrize(("name", "paper", "conservative_ref"),
                         [("ANB", 0.092, 0.096), ("HHT", 0.123, 0.130)])
def test_80_percent_doses_from_the_full_start(runs: dict, name: str, paper: float,
                                              conservative_ref: float) -> None:
    gel, t0, t1, ts, a80 = CASES[name]
    st = paper_start(runs[name, "eulerian"], ts)
    two_odes = front_trajectory(gel, t0, t1, start=st, conservative=False)
    assert two_odes.time_to_radius(a80) == pytest.approx(paper, rel=0.04)  # 0.0954, 0.1240
    # the measured start holds less solid than the bead (0.997 ANB, 0.969 HHT), which is why
    # the paper's curves run ahead of the conservative model
    assert two_odes.diagnostics["solid"] < 0.998
    cons = front_trajectory(gel, t0, t1, start=st)
    assert cons.time_to_radius(a80) == pytest.approx(conservative_ref, rel=0.01)  # 0.0959, 0.1303
    assert cons.time_to_radius(a80) > two_odes.time_to_radius(a80)


@pytest.mark.parametrize("grid", ["eulerian", "lagrangian"])
@pytest.mark.parametrize("name", ["ANB", "HHT"])
def test_dose_times_against_both_grids(runs: dict, name: str, grid: str) -> None:
    """Grid-specific: the paper's model (ell = 0) on the two fixed grids, each with its own
    measured front-model errors (MEASURED; the model is ill-posed, so each grid selects its
    own front speed).  The moving grid runs only the regularized model; the front models
    against it are in benchmarks/work_precision.py (its front cases' reference)."""
    gel, t0, t1, ts, _ = CASES[name]
    full = runs[name, grid]
    radii = fraction_radius(float(full.radius[0]), FRACTIONS)
    t_full = np.array([full.time_to_radius(a) for a in radii])
    st = paper_start(full, ts)
    for (start, cons), bound in zip([(None, True), (st, True), (st, False)],
                                    MEASURED[name, grid], strict=True):
        res = front_trajectory(gel, t0, t1, start=start, conservative=cons)
        ok = radii <= res.radius[0]  # doses the full run passed before t0 are skipped
        t_mod = np.array([res.time_to_radius(a) for a in radii[ok]])
        assert np.max(np.abs(t_mod / t_full[ok] - 1.0)) < bound + 0.03
