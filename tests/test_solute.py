"""The passive solute (solver/solute): Crank's series, fluid-proportional release, balance."""

from __future__ import annotations

import math

import numpy as np
import pytest

from solver.errors import ParameterError
from solver.full import simulate
from solver.solute import (
    Hindrance,
    Solute,
    crank_sphere,
    crank_sphere_finite,
    node_volumes,
    release,
    simulate_release,
)

BALANCE = 1e-10  # loaded = in gel + released (the kernel conserves to round-off, ~1e-13)


def _isothermal(solute: Solute, n: int = 200, until: float = 2.0, samples: int = 4000):
    return simulate_release("ANB", 302, solute, t_end=302, until=until, n=n, samples=samples)


@pytest.mark.parametrize("hindrance", [Hindrance("none"), Hindrance("free-volume", 0.5, 1.0)])
def test_isothermal_bead_matches_crank(hindrance: Hindrance) -> None:
    # No flow at T_start = T_end: Fickian release from a uniform sphere into a perfect sink.
    # Convergence study (uniform mesh, D0 = 1): max error 5.4e-4, 1.3e-4, 3.3e-5 for
    # N = 100, 200, 400 (second order), so N = 200 meets 1e-3 with a margin of 7.
    res, rel = _isothermal(Solute(diffusivity=1.0, hindrance=hindrance))
    a0, phi0 = float(res.radius[0]), float(res.phi[0, 0])
    d_eff = 1.0 * hindrance.factor(phi0)
    assert rel.effective_diffusivity == pytest.approx(d_eff, rel=1e-12)
    ref = crank_sphere(rel.t, d_eff, a0)
    assert np.max(np.abs(rel.released_fraction - ref)) < 1e-3
    assert rel.released_fraction[-1] > 0.9  # the whole release, not its start
    assert rel.mass_balance_error < BALANCE
    assert np.max(np.abs(rel.advected_fraction)) < 1e-12  # no flow: all of it diffused


def test_isothermal_bead_into_a_finite_volume_matches_crank() -> None:
    # Crank eq. 6.30 with alpha = V / (K W0): the medium ends at c_pore / K.
    res0, _ = _isothermal(Solute(diffusivity=1.0), until=0.01, samples=10)
    w0 = float(res0.radius[0]) ** 3 - 1.0
    k, alpha = 2.0, 1.5
    solute = Solute(diffusivity=1.0, hindrance=Hindrance("none"), partition=k,
                    release_volume=alpha * k * w0)
    res, rel = _isothermal(solute)
    # (t = 0 left out: there the series' tail decays like 1/q_n^2, its value is 0)
    ref = crank_sphere_finite(rel.t[1:], 1.0, float(res.radius[0]), alpha)
    assert np.max(np.abs(rel.released_fraction[1:] - ref)) < 1e-3
    # the series' own limit: the medium ends at c_pore / K, a fraction alpha / (1 + alpha)
    limit = crank_sphere_finite(np.array([1e3]), 1.0, float(res.radius[0]), alpha)[0]
    assert limit == pytest.approx(alpha / (1 + alpha), rel=1e-12)
    assert rel.released_fraction[-1] > 0.99 * limit
    assert rel.mass_balance_error < BALANCE


@pytest.mark.parametrize("gel,t_start", [("ANB", 302), ("HHT", 304)])
def test_no_diffusion_releases_drug_in_proportion_to_fluid(gel: str, t_start: float) -> None:
    # D0 = 0, uniform loading, one heating: every expelled parcel carries c0, exactly.
    res, rel = simulate_release(gel, t_start, Solute(diffusivity=0.0), t_end=308, until=0.3,
                                n=400, interfacial_length=0.01, rtol=1e-5)
    assert rel.expelled_fraction[-1] > 0.8
    assert np.max(np.abs(rel.released_fraction - rel.expelled_fraction)) < 1e-6
    assert np.max(np.abs(rel.advected_fraction - rel.released_fraction)) < 1e-6
    assert rel.mass_balance_error < BALANCE
    # the profiles stay at the loaded concentration (but for the edge cell, which takes up
    # a little drug-free medium where its porosity rises briefly: a 6e-5 dip for ANB)
    assert np.max(np.abs(rel.profiles[:, :-1] - 1.0)) < 1e-6


def test_rest_dilutes_and_balance_holds_through_a_protocol() -> None:
    # heat, rest (the gel takes up drug-free medium at the edge), heat again
    protocol = [(0.05, 308), (0.5, 302), (0.05, 308)]
    for d0 in (0.0, 3.0):
        for vol in (None, 400.0):
            res, rel = simulate_release("ANB", 302, Solute(diffusivity=d0, release_volume=vol),
                                        protocol=protocol, n=200, interfacial_length=0.01,
                                        rtol=1e-5, samples=1200)
            assert rel.mass_balance_error < BALANCE
            assert np.all(np.diff(rel.released_fraction) > -1e-12) or vol is not None
            if d0 == 0.0:
                # the rest's fresh fluid sits in the outer cells: the second heating's fluid
                # is diluted, so it carries less drug than fluid
                k1 = int(np.searchsorted(rel.t, 0.55))
                fluid = rel.expelled_fraction[-1] - rel.expelled_fraction[k1]
                drug = rel.released_fraction[-1] - rel.released_fraction[k1]
                assert 0.0 < drug < 0.9 * fluid


def test_hindrance_laws() -> None:
    fv = Hindrance("free-volume", sieve=0.0, y=1.0)
    assert fv.factor(0.5) == pytest.approx(math.exp(-1.0))  # exp(-Y v / (1 - v)), v = 0.5
    assert fv.factor(0.2) == pytest.approx(math.exp(-4.0))
    sv = Hindrance("free-volume", sieve=1.2, y=1.0)  # excluded once r_s / xi >= 1
    assert sv.factor(0.3) == 0.0  # v = 0.7: r_s / xi = 1.2 * 0.7^(1/3) = 1.07
    assert sv.factor(0.95) == pytest.approx((1 - 1.2 * 0.05 ** (1 / 3)) * math.exp(-0.05 / 0.95))
    og = Hindrance("ogston", sieve=3.0)
    # Ogston, Preston & Wells 1973 (as in Amsden 1998, eq. 2): exp(-sqrt(v) (1 + r_s/r_f)),
    # v the polymer fraction: v = 0.09, r_s/r_f = 3 -> exp(-0.3 * 4) = exp(-1.2)
    assert og.factor(0.91) == pytest.approx(math.exp(-1.2), rel=1e-12)
    phis = np.linspace(0.05, 0.99, 50)
    for h in (fv, sv, og):
        f = h.factor(phis)
        assert np.all(np.diff(f) >= 0.0) and np.all((f >= 0.0) & (f <= 1.0))


@pytest.mark.parametrize("kwargs,field", [
    ({"diffusivity": -1.0}, "diffusivity"), ({"diffusivity": math.nan}, "diffusivity"),
    ({"diffusivity": math.inf}, "diffusivity"), ({"partition": 0.0}, "partition"),
    ({"partition": -2.0}, "partition"), ({"release_volume": 0.0}, "release_volume"),
    ({"hindrance": {"law": "magic"}}, "hindrance.law"),
    ({"hindrance": {"sieve": -1.0}}, "hindrance.sieve"),
])
def test_bad_solute_names_the_field(kwargs: dict, field: str) -> None:
    with pytest.raises(ParameterError) as exc:
        Solute(**kwargs)
    assert exc.value.field == field


def test_release_volume_smaller_than_the_bead_is_refused() -> None:
    res, _ = _isothermal(Solute(), until=0.01, samples=10)
    with pytest.raises(ParameterError) as exc:
        release(res, Solute(release_volume=float(res.radius[0]) ** 3 * 0.9))
    assert exc.value.field == "release_volume"


def test_moving_grid_mechanics_carry_the_solute_like_the_uniform_grid() -> None:
    """Issue 12: the solute runs on the moving grid's mechanics (resampled onto uniform dry
    cells, exact in the volumes).  ANB 302 -> 308 K at ell = 0.005, D0 = 0.05: against the
    uniform grid at 800 cells (4 / ell) the released fraction differs by 1.1e-3 with 200
    moving cells and 5.0e-4 with 400 (the uniform grid's own 400 -> 800 change: 8.4e-4), so
    the gap is the solute cells' resolution and falls with it."""
    sol = Solute(diffusivity=0.05)
    kw = dict(until=0.1, every=0.1 / 400, interfacial_length=0.005)
    ref = release(simulate("ANB", 302, 308, grid="lagrangian", n=800, **kw), sol)
    gaps = []
    for n in (200, 400):
        mech = simulate("ANB", 302, 308, grid="moving", n=n, **kw)
        s3 = node_volumes(mech)
        assert np.max(np.abs(s3[:, -1] - mech.radius**3)) < 1e-12  # the volume is exact
        rel = release(mech, sol)
        assert rel.mass_balance_error < 1e-10
        gaps.append(float(np.max(np.abs(rel.released_fraction - ref.released_fraction))))
    assert gaps[1] < 1e-3 and gaps[1] < 0.75 * gaps[0], gaps
