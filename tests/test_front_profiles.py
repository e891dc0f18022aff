"""Leading-order stretches and stresses of the front (eqs. Front_Strain_theta-Front_Stress_r)."""

import numpy as np
import pytest

from solver import ANB, HHT
from solver.front import front_levels, leading_profiles
from solver.front.evolve import radius_of_front


@pytest.mark.parametrize(("gel", "t0", "t1"), [(ANB, 302, 308), (HHT, 304, 308)])
def test_profiles_are_consistent(gel, t0: float, t1: float) -> None:
    lev = front_levels(gel, t0, t1)
    rf = 1.2
    a = float(radius_of_front(lev, 1.0, rf))
    p = leading_profiles(lev, a, rf, n=801)
    jac = 1.0 / (1.0 - p.porosity_leading)
    np.testing.assert_allclose(p.stretch_r * p.stretch_theta**2, jac, rtol=1e-13)
    np.testing.assert_allclose(p.stress_r, (p.stretch_r**2 - 1) / jac, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(p.stress_theta, (p.stretch_theta**2 - 1) / jac, rtol=1e-12,
                               atol=1e-14)
    assert p.stretch_theta[-1] == pytest.approx(a, rel=1e-13)  # lambda_theta = a at the edge
    # the edge condition: Terzaghi radial stress = osmotic pressure P'(phi_+) phi1_+
    assert p.stress_r[-1] == pytest.approx(lev.dp_plus * p.phi1[-1], rel=1e-12)
    # the hoop stretch is continuous across the front; the core carries no flux
    core, shell = p.r < rf, p.r > rf
    q = leading_profiles(lev, a, rf, r=rf * np.array([1 - 1e-12, 1 + 1e-12]))
    assert q.stretch_theta[1] == pytest.approx(q.stretch_theta[0], rel=1e-10)
    assert np.all(p.dmu_dr[core] == 0) and np.all(p.dmu_dr[shell] < 0)
    np.testing.assert_allclose(p.dmu_dr[shell] * p.r[shell] ** 2,
                               p.dmu_dr[-1] * a**2, rtol=1e-12)
    assert np.all(np.abs(p.porosity - p.porosity_leading) < 0.05)
