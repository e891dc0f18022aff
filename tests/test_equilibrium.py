"""Equilibria on every branch, stability and folds (eq. EqlEqn; issue 2 acceptance)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from solver import ANB, HHT, Gel, equilibria, equilibrium, folds
from solver.equilibrium import equilibrium_curve, residual
from solver.thermo import free_energy


def _one(gel: Gel, t: float) -> float:
    eqs = equilibria(gel, t)
    assert len(eqs) == 1
    return eqs[0].stretch


@pytest.mark.parametrize(
    ("gel", "t", "stretch", "porosity"),
    [(ANB, 308, 1.11, 0.27), (ANB, 302, 2.29, 0.92), (HHT, 308, 1.16, 0.36),
     (HHT, 304, 2.67, 0.95)],
)
def test_paper_equilibria_to_printed_digits(gel: Gel, t: float, stretch: float,
                                            porosity: float) -> None:
    lam = _one(gel, t)
    assert round(lam, 2) == stretch
    assert round(1 - lam**-3, 2) == porosity


def test_anb_folds() -> None:
    fl = folds(ANB)
    assert [f.kind for f in fl] == ["swell", "shrink"]
    assert round(fl[0].temperature, 1) == 304.7
    assert round(fl[1].temperature, 1) == 305.8


def test_hht_window_and_shrunken_branch() -> None:
    fl = folds(HHT)
    assert len(fl) == 2 and all(round(f.temperature, 1) == 307.6 for f in fl)
    width = fl[1].temperature - fl[0].temperature
    assert 0.003 < width < 0.02  # "approximately 0.01 K wide"
    assert round(equilibrium(HHT, 307.6, "shrunken").stretch, 2) == 1.41
    mid = 0.5 * (fl[0].temperature + fl[1].temperature)
    eqs = equilibria(HHT, mid)
    assert [e.stable for e in eqs] == [True, False, True]


def test_three_equilibria_inside_anb_window() -> None:
    eqs = equilibria(ANB, 305.0)
    assert [e.stable for e in eqs] == [True, False, True]
    assert equilibrium(ANB, 305.0, "swollen").stretch == eqs[2].stretch
    assert equilibrium(ANB, 305.0, "shrunken").stretch == eqs[0].stretch


def test_curve_passes_through_roots() -> None:
    curve = equilibrium_curve(ANB, 300.0, 310.0)
    assert np.all(np.abs(residual(ANB, curve.temperature, curve.stretch)) < 1e-9)
    assert curve.stable.any() and (~curve.stable).any()


gels = st.builds(
    lambda base, om, da0, da1: Gel(omega=base.omega * om, a0=base.a0 + da0, b0=base.b0,
                                   a1=base.a1 + da1, b1=base.b1),
    st.sampled_from([ANB, HHT]), st.floats(0.3, 5.0), st.floats(-0.3, 0.3), st.floats(-0.3, 0.3),
)


@settings(max_examples=40, deadline=None)
@given(gel=gels, t=st.floats(290.0, 320.0))
def test_every_equilibrium_solves_eqlEqn_and_is_stationary(gel: Gel, t: float) -> None:
    eqs = equilibria(gel, t)
    assert len(eqs) % 2 == 1  # residual < 0 as lambda -> 1+ and > 0 as lambda -> infinity
    for e in eqs:
        # relative to the sum of the magnitudes of eq. EqlEqn's terms (floating-point scale)
        lam, c0, c1 = e.stretch, gel.chi0(t), gel.chi1(t)
        terms = abs((lam**2 - 1) / lam**3) + gel.omega * (
            abs(np.log(e.porosity)) + lam**-3 + abs(c0 - c1) * lam**-6 + 2 * abs(c1) * lam**-9)
        assert abs(residual(gel, t, lam)) < 1e-10 * terms
        # dW/dlambda of the isotropic free energy, by central differences of W itself
        h = 1e-5 * e.stretch
        wp = free_energy(gel, t, *(3 * [e.stretch + h]))
        wm = free_energy(gel, t, *(3 * [e.stretch - h]))
        scale = abs(free_energy(gel, t, *(3 * [e.stretch]))) + gel.omega
        assert abs((wp - wm) / (2 * h)) < 1e-7 * scale / h
    stab = [e.stable for e in eqs]
    assert stab[0] and stab[-1] and all(a != b for a, b in zip(stab, stab[1:], strict=False))


@settings(max_examples=25, deadline=None)
@given(gel=gels, u=st.floats(0.0, 1.0), v=st.floats(0.0, 1.0))
def test_branch_count_changes_only_at_folds(gel: Gel, u: float, v: float) -> None:
    knots = [290.0, *[f.temperature for f in folds(gel, 290.0, 320.0)], 320.0]
    for lo, hi in zip(knots, knots[1:], strict=False):
        if hi - lo < 1e-6:
            continue
        pad = 1e-6 * (hi - lo)
        t1, t2 = lo + pad + u * (hi - lo - 2 * pad), lo + pad + v * (hi - lo - 2 * pad)
        assert len(equilibria(gel, t1)) == len(equilibria(gel, t2))


def test_public_functions_take_a_preset_name() -> None:
    """``solver.equilibrium('ANB', 305.0)`` works as ``simulate`` does; a non-gel names it."""
    import solver

    assert solver.equilibrium("ANB", 305.0) == solver.equilibrium(solver.ANB, 305.0)
    assert solver.classify_jump("hht", 304, 308).behaviour == "front"
    assert solver.folds("ANB") == solver.folds(solver.ANB)
    with pytest.raises(solver.ParameterError, match="gel"):
        solver.equilibrium(3, 305.0)  # type: ignore[arg-type]
