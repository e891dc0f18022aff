"""Spinodal and coexistence curves (eqs. Spinodal, Coexistence) and the jump classifier."""

import numpy as np
import pytest

from solver import ANB, HHT, Gel, classify_jump
from solver.phase import (
    coexistence_points,
    in_coexistence,
    in_spinodal,
    spinodal_curve,
    spinodal_stiffness,
)
from solver.thermo import normal_energy, normal_stress


@pytest.mark.parametrize(
    ("gel", "t0", "t1", "direction", "behaviour"),
    [
        (ANB, 308, 302, "swell", "smooth"),
        (ANB, 302, 308, "shrink", "front"),
        (ANB, 308, 304, "swell", "delayed_front"),
        (ANB, 302, 306, "shrink", "delayed_front"),
        (ANB, 302, 312, "shrink", "spinodal"),
        (HHT, 308, 304, "swell", "smooth"),
        (HHT, 304, 308, "shrink", "front"),
        (HHT, 304, 307.6, "shrink", "smooth"),
    ],
)
def test_classifier_reproduces_paper(gel: Gel, t0: float, t1: float, direction: str,
                                     behaviour: str) -> None:
    c = classify_jump(gel, t0, t1)
    assert (c.direction, c.behaviour) == (direction, behaviour)


def test_no_jump_is_no_change() -> None:
    assert classify_jump(ANB, 302, 302).direction == "none"


@pytest.mark.parametrize("lam", [1.3, 1.6, 2.0, 2.29])
def test_coexistence_points_solve_both_equalities(lam: float) -> None:
    pts = coexistence_points(ANB, lam)
    assert pts
    for t, new in pts:
        s_iso = normal_stress(ANB, t, lam, lam)
        s_new = normal_stress(ANB, t, new, lam)
        chord = (normal_energy(ANB, t, new, lam) - normal_energy(ANB, t, lam, lam)) / (new - lam)
        assert abs(s_new - s_iso) < 1e-8 * (1 + abs(s_iso))
        assert abs(chord - s_iso) < 1e-7 * (1 + abs(s_iso))
        # the curve bounds the region: just past T (towards heating) the state is inside
        inside = [in_coexistence(ANB, t + d, lam) for d in (-0.05, 0.05)]
        assert inside[0] != inside[1]


def test_spinodal_curve_and_nesting() -> None:
    lam, t = spinodal_curve(ANB, 300.0, 320.0)
    assert lam.size > 10
    assert np.all(np.abs(spinodal_stiffness(ANB, t, lam)) < 1e-8 * ANB.omega)
    rng = np.random.default_rng(1)
    for tt, ll in zip(rng.uniform(300, 320, 60), rng.uniform(1.05, 2.6, 60), strict=False):
        if in_spinodal(ANB, tt, ll):
            assert in_coexistence(ANB, tt, ll)


def test_hht_regions_miss_the_equilibrium_curve_when_swelling() -> None:
    # Paper sec. Hirotsu dynamics: for HHT the regions do not cross the equilibrium curve.
    assert classify_jump(HHT, 308, 300).behaviour == "smooth"


def test_dry_gel_is_a_clear_error() -> None:
    from solver import ParameterError

    with pytest.raises(ParameterError, match="temperature.*holds fluid"):
        classify_jump(HHT, 274, 358)
