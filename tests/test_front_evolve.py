"""Front evolution (eqs. SphereEvolve_Dimless, FrontEvolve): quadrature, conservation, ends."""

import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp

from solver import ANB, HHT
from solver.front import fraction_radius, front_levels, front_trajectory
from solver.front.flux import flux_from_levels
from solver.front.start import thin_shell, thin_shell_rate

JUMPS = {"ANB": (ANB, 302.0, 308.0), "HHT": (HHT, 304.0, 308.0)}


def solid(lev, a, rf):
    return lev.s_plus * a**3 - lev.jump * rf**3


@pytest.mark.parametrize("name", JUMPS)
def test_time_quadrature_matches_adaptive_quad(name: str) -> None:
    lev = front_levels(*JUMPS[name])
    res = front_trajectory(*JUMPS[name])

    def g(x: float) -> float:
        a = np.cbrt((1 + lev.jump * x**3) / lev.s_plus)
        return -lev.jump * x**2 / (lev.s_plus * lev.k_plus * flux_from_levels(lev, a, x))

    for x in (2.0, 1.3, 0.5, 0.0):
        ref = quad(g, x, lev.a0, epsabs=1e-14, epsrel=1e-13, limit=200)[0]
        # measured: Chebyshev degree 48 agrees with quad to ~1e-15
        assert res.curve.time_of_front(x) == pytest.approx(ref, rel=1e-11, abs=1e-14)


@pytest.mark.parametrize("name", JUMPS)
def test_paper_two_odes_equal_the_quadrature(name: str) -> None:
    """Integrating da/dt and dR_f/dt as two ODEs (the paper) from a state that does not
    conserve the dry solid volume gives the same curve as the quadrature with that volume."""
    gel, t0, t1 = JUMPS[name]
    lev = front_levels(gel, t0, t1)
    start = (0.01, 2.1, 1.95)
    res = front_trajectory(gel, t0, t1, start=start, conservative=False, n=41)

    def rhs(_t: float, y: np.ndarray) -> list[float]:
        a, rf = y
        amp = flux_from_levels(lev, a, rf)
        return [lev.k_plus * amp / a**2, lev.s_plus * lev.k_plus * amp / (lev.jump * rf**2)]

    t_eval = res.t[:-3]  # stop before the front reaches the centre
    sol = solve_ivp(rhs, (start[0], t_eval[-1]), start[1:], t_eval=t_eval, method="DOP853",
                    rtol=1e-12, atol=1e-13)
    assert sol.success
    np.testing.assert_allclose(sol.y[0], res.radius[:-3], rtol=1e-8)
    np.testing.assert_allclose(sol.y[1], res.front[:-3], rtol=1e-7, atol=1e-9)
    q0 = solid(lev, *start[1:])
    assert q0 != pytest.approx(1.0, abs=1e-3)  # the start really is non-conservative
    np.testing.assert_allclose(solid(lev, sol.y[0], sol.y[1]), q0, rtol=1e-9)
    assert res.diagnostics["solid"] == pytest.approx(q0, rel=1e-14)


@pytest.mark.parametrize("name", JUMPS)
def test_solid_is_conserved_and_front_reaches_centre(name: str) -> None:
    lev = front_levels(*JUMPS[name])
    res = front_trajectory(*JUMPS[name])
    np.testing.assert_allclose(solid(lev, res.radius, res.front), 1.0, rtol=1e-13)
    for arr in (res.t, res.radius, res.front):
        assert np.all(np.isfinite(arr))
    assert np.all(np.diff(res.t) > 0)
    assert np.all(np.diff(res.radius) < 0) and np.all(np.diff(res.front) < 0)
    assert res.front[-1] == 0.0 and res.flux[-1] == 0.0
    assert res.radius[-1] == pytest.approx(lev.s_plus ** (-1 / 3), rel=1e-14)
    assert np.isneginf(res.flux[0]) and np.all(np.isfinite(res.flux[1:]))
    # A -> 0 linearly as R_f -> 0: the front still reaches the centre in finite time
    x = np.array([1e-2, 1e-3])
    amp = res.curve.flux(x)
    assert amp[0] / amp[1] == pytest.approx(10.0, rel=1e-2)


@pytest.mark.parametrize("name", JUMPS)
def test_early_time_is_the_thin_shell(name: str) -> None:
    """d = a - R_f grows like sqrt(D t) from the bare equilibrium (module start)."""
    lev = front_levels(*JUMPS[name])
    res = front_trajectory(*JUMPS[name])
    errs = []
    for t in (1e-7, 1e-5):
        a, rf = res.state_at(t)
        a_ts, rf_ts = thin_shell(lev, t)
        errs.append(abs((a - rf) ** 2 / (thin_shell_rate(lev) * t) - 1))
        assert a == pytest.approx(float(a_ts), rel=1e-2)
    # measured: relative error ~ sqrt(t) (1e-3 at 1e-7 ... 1e-2 at 1e-5)
    assert errs[0] < 3e-3 and errs[0] < errs[1] / 5


@pytest.mark.parametrize("name", JUMPS)
def test_queries_invert_each_other(name: str) -> None:
    res = front_trajectory(*JUMPS[name])
    for a in (2.2, 1.7, 1.3, res.radius_range[0] + 1e-9):
        t = res.time_to_radius(a)
        assert res.state_at(t)[0] == pytest.approx(a, rel=1e-10)
    ts = [res.time_to_radius(a) for a in np.linspace(*res.radius_range, 7)[::-1]]
    assert ts[0] == pytest.approx(0.0, abs=1e-15) and np.all(np.diff(ts) > 0)
    # near the centre a - a_end ~ R_f^3: the cube root turns round-off 1e-16 into ~1e-11 in t
    assert res.time_to_radius(res.radius_range[0]) == pytest.approx(res.t[-1], rel=1e-9)
    np.testing.assert_allclose([res.time_to_radius(a) for a in res.radius[1:-1]],
                               res.t[1:-1], rtol=1e-9)


def test_measured_start_shifts_the_equilibrium_curve() -> None:
    """The conservative model from (t0, a) is the equilibrium curve shifted in time."""
    eq = front_trajectory(*JUMPS["ANB"])
    res = front_trajectory(*JUMPS["ANB"], start=(0.01, 2.0, 1.7))
    assert res.start == "full@0.01"
    shift = 0.01 - eq.time_to_radius(2.0)
    for a in (1.9, 1.5, 1.2):
        assert res.time_to_radius(a) == pytest.approx(eq.time_to_radius(a) + shift, rel=1e-11)
    assert res.diagnostics["front_used"] == pytest.approx(eq.state_at(eq.time_to_radius(2.0))[1])


def test_stops_at_target_radius_and_until() -> None:
    res = front_trajectory(*JUMPS["HHT"], target_radius=1.67, every=0.01)
    assert res.radius[-1] == pytest.approx(1.67, rel=1e-12)
    assert res.diagnostics["stop"] == "target_radius"
    np.testing.assert_allclose(np.diff(res.t[:-1]), 0.01)
    res = front_trajectory(*JUMPS["HHT"], until=0.05, n=11)
    assert res.t[-1] == 0.05 and res.t.size == 11 and res.diagnostics["stop"] == "until"
    assert res.radius_range[0] == pytest.approx(res.radius[-1], rel=1e-12)


def test_power_law_permeability_rescales_time() -> None:
    """At leading order k enters only as k(phi_+): t scales as 1 / k(phi_+)."""
    gel, t0, t1 = JUMPS["ANB"]
    slow = gel.with_permeability("power", 1.5)
    ref, res = front_trajectory(gel, t0, t1), front_trajectory(slow, t0, t1)
    k = slow.permeability(res.phi_plus)
    assert res.time_to_radius(1.5) == pytest.approx(ref.time_to_radius(1.5) / k, rel=1e-12)


def test_time_to_fraction_of_stored_fluid() -> None:
    res = front_trajectory(*JUMPS["ANB"])
    a0 = res.radius[0]
    for f in (0.1, 0.5, 0.8):
        a = fraction_radius(a0, f)
        assert (a0**3 - a**3) == pytest.approx(f * (a0**3 - 1.0), rel=1e-13)
        assert res.time_to_fraction(f) == res.time_to_radius(a)
    assert res.time_to_fraction(0.0) == pytest.approx(0.0, abs=1e-15)
    with pytest.raises(ValueError, match="fraction"):
        res.time_to_fraction(1.5)
