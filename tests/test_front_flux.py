"""Closed-form flux constant A and phi1_+ (eqs. BVP_Front-BVP_Front_BCFront) vs solve_bvp."""

import numpy as np
import pytest
from scipy.integrate import solve_bvp

from solver import ANB, HHT
from solver.errors import ParameterError
from solver.front import flux_constant, front_levels, phi1_plus
from solver.front.flux import edge_value, flux_from_levels, front_value, shell_f
from solver.front.start import thin_shell_constant

JUMPS = {"ANB": (ANB, 302.0, 308.0), "HHT": (HHT, 304.0, 308.0)}
STATES = [(1.8, 1.2), (2.2, 2.1), (1.3, 0.3), (1.6, 1.4)]


def bvp_reference(levels, a: float, rf: float):
    """solve_bvp on eq. BVP_Front with its two conditions and A as the unknown parameter."""
    sp, jump, dp = levels.s_plus, levels.jump, levels.dp_plus

    def ode(r, y, p):
        f = shell_f(levels, rf, r)
        return ((-2 * jump**2 * rf**6 / (sp * f**2 * r**7) - p[0] / r**2) / dp)[None, :]

    def bc(ya, yb, p):
        return np.array([ya[0] * dp - front_value(levels), yb[0] * dp - edge_value(levels, a)])

    r = np.geomspace(rf, a, 200)
    sol = solve_bvp(ode, bc, r, np.zeros((1, r.size)), p=[-1.0], tol=1e-10, max_nodes=20000)
    assert sol.status == 0
    return sol


@pytest.mark.parametrize("name", JUMPS)
@pytest.mark.parametrize(("a", "rf"), STATES)
def test_closed_form_matches_solve_bvp(name: str, a: float, rf: float) -> None:
    gel, t0, t1 = JUMPS[name]
    levels = front_levels(gel, t0, t1)
    sol = bvp_reference(levels, a, rf)
    amp = flux_constant(a, rf, levels.phi_minus, levels.phi_plus, gel, t1)
    # measured: agreement to ~1e-13 relative with solve_bvp at tol 1e-10
    assert amp == pytest.approx(sol.p[0], rel=1e-8)
    r = np.linspace(rf, a, 50)
    p1 = phi1_plus(r, a, rf, levels.phi_minus, levels.phi_plus, gel, t1)
    np.testing.assert_allclose(p1, sol.sol(r)[0], atol=1e-8)


@pytest.mark.parametrize("name", JUMPS)
def test_phi1_meets_both_conditions(name: str) -> None:
    gel, t0, t1 = JUMPS[name]
    lev = front_levels(gel, t0, t1)
    a, rf = 1.7, 1.1
    p1 = phi1_plus(np.array([rf, a]), a, rf, lev.phi_minus, lev.phi_plus, gel, t1)
    assert lev.dp_plus * p1[0] == pytest.approx(front_value(lev), abs=1e-13)
    assert lev.dp_plus * p1[1] == pytest.approx(edge_value(lev, a), abs=1e-13)


@pytest.mark.parametrize("name", JUMPS)
def test_thin_shell_limit(name: str) -> None:
    """A d / a^2 -> B as the shell thickness d -> 0 at the initial radius (module start)."""
    lev = front_levels(*JUMPS[name])
    b = thin_shell_constant(lev)
    assert b < 0
    errs = [abs(flux_from_levels(lev, lev.a0, lev.a0 - d) * d / lev.a0**2 - b)
            for d in (1e-3, 1e-4, 1e-5)]
    # measured: the error falls 9.95x per decade of d (first order), ~0.1 d / |B| relative
    assert errs[0] / errs[1] == pytest.approx(10.0, rel=0.02)
    assert errs[1] / errs[2] == pytest.approx(10.0, rel=0.02)


def test_flux_expels_fluid_with_paper_sign() -> None:
    lev = front_levels(ANB, 302, 308)
    assert flux_from_levels(lev, 1.8, 1.2) < 0  # dmu/dr < 0: fluid flows out, a shrinks


@pytest.mark.parametrize(("a", "rf"), [(1.5, 1.5), (1.5, 0.0), (1.5, 2.0), (float("nan"), 1.0)])
def test_flux_constant_rejects_bad_shells(a: float, rf: float) -> None:
    lev = front_levels(ANB, 302, 308)
    with pytest.raises(ParameterError):
        flux_constant(a, rf, lev.phi_minus, lev.phi_plus, ANB, 308.0)
