"""The bordered band solver (solver/full/banded.py), checked directly against dense solves."""

from __future__ import annotations

import numpy as np
import pytest

from solver.full.banded import band_lu, band_solve, bordered_factor, bordered_solve


def _band_matrix(rng: np.random.Generator, m: int, lower: int, upper: int) -> np.ndarray:
    a = np.zeros((m, m))
    for k in range(-lower, upper + 1):
        a += np.diag(rng.normal(size=m - abs(k)), k)
    return a


def _pack(a: np.ndarray, lower: int, upper: int) -> np.ndarray:
    """LAPACK band layout with fill-in rows: A[i, j] at ab[lower + upper + i - j, j]."""
    m = a.shape[0]
    ab = np.zeros((2 * lower + upper + 1, m))
    for j in range(m):
        for i in range(max(0, j - upper), min(m, j + lower + 1)):
            ab[lower + upper + i - j, j] = a[i, j]
    return ab


@pytest.mark.parametrize(("lower", "upper"), [(1, 1), (2, 2), (1, 2), (3, 1)])
@pytest.mark.parametrize("seed", range(5))
def test_band_solve_matches_dense(lower: int, upper: int, seed: int) -> None:
    """Random (unsymmetric, not diagonally dominant, so pivoting is exercised) band systems."""
    rng = np.random.default_rng(seed)
    m = 17
    a = _band_matrix(rng, m, lower, upper)
    b = rng.normal(size=m)
    ab, ipiv = _pack(a, lower, upper), np.zeros(m, dtype=np.int64)
    assert band_lu(ab, lower, upper, ipiv)
    x = b.copy()
    band_solve(ab, lower, upper, ipiv, x)
    np.testing.assert_allclose(x, np.linalg.solve(a, b), rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize(("lower", "upper"), [(1, 1), (2, 2)])
def test_band_lu_reports_singular(lower: int, upper: int) -> None:
    m = 6
    a = _band_matrix(np.random.default_rng(1), m, lower, upper)
    a[:, 2] = 0.0  # a zero column: singular
    ab, ipiv = _pack(a, lower, upper), np.zeros(m, dtype=np.int64)
    assert not band_lu(ab, lower, upper, ipiv)


@pytest.mark.parametrize("p", [0, 1, 2])
@pytest.mark.parametrize("seed", range(4))
def test_bordered_solve_matches_dense(p: int, seed: int) -> None:
    """[[A, C], [D, E]] with A tridiagonal or pentadiagonal and dense p-wide borders."""
    rng = np.random.default_rng(100 + seed)
    m, lower, upper = 12, 1 + seed % 2, 1 + seed % 2
    a = _band_matrix(rng, m, lower, upper) + 4 * np.eye(m)
    cmat, dmat = rng.normal(size=(m, p)), rng.normal(size=(p, m))
    emat = rng.normal(size=(p, p)) + 5 * np.eye(p)
    full = np.block([[a, cmat], [dmat, emat]]) if p else a
    b = rng.normal(size=m + p)
    ab, ipiv = _pack(a, lower, upper), np.zeros(m, dtype=np.int64)
    xmat, spiv, zbuf = np.zeros((m, p)), np.zeros(p, dtype=np.int64), np.zeros(p)
    e = emat.copy()
    assert bordered_factor(ab, lower, upper, ipiv, cmat.copy(), dmat, e, xmat, spiv)
    x = b.copy()
    bordered_solve(ab, lower, upper, ipiv, dmat, xmat, e, spiv, x, zbuf)
    np.testing.assert_allclose(x, np.linalg.solve(full, b), rtol=1e-9, atol=1e-10)
