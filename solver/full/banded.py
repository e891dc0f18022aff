"""Bordered banded linear algebra in numba: LU with partial pivoting and block solves.

The iteration matrix of either grid is M = [[A, C], [D, E]] with A (m x m) banded
(``lower``/``upper`` half-widths), C (m x p) and D (p x m) dense borders and E (p x p);
p = 0 on the Lagrangian grid, 2 on the Eulerian grid (s_{n-1} and a).  A is factored in
LAPACK band layout (ldab = 2 lower + upper + 1, A[i, j] at ab[lower + upper + i - j, j]);
the border is eliminated through the p x p Schur complement S = E - D A^-1 C.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _tri_lu(ab, ipiv):
    """:func:`band_lu` specialised to lower = upper = 1 (LAPACK dgttrf); the diagonal of U
    is stored inverted (so solves multiply)."""
    m = ab.shape[1]
    for j in range(m - 1):
        if abs(ab[3, j]) > abs(ab[2, j]):
            ipiv[j] = j + 1
            t = ab[2, j]
            ab[2, j] = ab[3, j]
            ab[3, j] = t
            t = ab[1, j + 1]
            ab[1, j + 1] = ab[2, j + 1]
            ab[2, j + 1] = t
            if j + 2 < m:
                t = ab[0, j + 2]
                ab[0, j + 2] = ab[1, j + 2]
                ab[1, j + 2] = t
        else:
            ipiv[j] = j
        piv = ab[2, j]
        if piv == 0.0 or not np.isfinite(piv):
            return False
        el = ab[3, j] / piv
        ab[3, j] = el
        ab[2, j] = 1.0 / piv
        ab[2, j + 1] -= el * ab[1, j + 1]
        if j + 2 < m:
            ab[1, j + 2] -= el * ab[0, j + 2]
    ipiv[m - 1] = m - 1
    last = ab[2, m - 1]
    if last == 0.0 or not np.isfinite(last):
        return False
    ab[2, m - 1] = 1.0 / last
    return True


@njit(cache=True)
def _tri_solve(ab, ipiv, b):
    """:func:`band_solve` specialised to lower = upper = 1 (LAPACK dgttrs)."""
    m = ab.shape[1]
    for j in range(m - 1):
        if ipiv[j] != j:
            t = b[j]
            b[j] = b[j + 1]
            b[j + 1] = t
        b[j + 1] -= ab[3, j] * b[j]
    b[m - 1] *= ab[2, m - 1]
    if m >= 2:
        b[m - 2] = (b[m - 2] - ab[1, m - 1] * b[m - 1]) * ab[2, m - 2]
    for j in range(m - 3, -1, -1):
        b[j] = (b[j] - ab[1, j + 1] * b[j + 1] - ab[0, j + 2] * b[j + 2]) * ab[2, j]


@njit(cache=True)
def band_lu(ab, lower, upper, ipiv):
    """In-place LU with partial pivoting of a band matrix (LAPACK dgbtf2); False if singular.

    The first ``lower`` rows of ``ab`` (fill-in space) must be zero on entry.
    """
    if lower == 1 and upper == 1:
        return _tri_lu(ab, ipiv)
    m = ab.shape[1]
    kv = lower + upper
    ju = 0
    for j in range(m):
        km = min(lower, m - 1 - j)
        jp = 0
        best = abs(ab[kv, j])
        for i in range(1, km + 1):
            v = abs(ab[kv + i, j])
            if v > best:
                best = v
                jp = i
        ipiv[j] = j + jp
        if best == 0.0 or not np.isfinite(best):
            return False
        ju = max(ju, min(j + upper + jp, m - 1))
        if jp != 0:
            for c in range(j, ju + 1):
                t = ab[kv + j + jp - c, c]
                ab[kv + j + jp - c, c] = ab[kv + j - c, c]
                ab[kv + j - c, c] = t
        piv = ab[kv, j]
        for i in range(1, km + 1):
            ab[kv + i, j] /= piv
        for c in range(j + 1, ju + 1):
            t = ab[kv + j - c, c]
            if t != 0.0:
                for i in range(1, km + 1):
                    ab[kv + j + i - c, c] -= ab[kv + i, j] * t
    return True


@njit(cache=True)
def band_solve(ab, lower, upper, ipiv, b):
    """Solve A x = b in place with the factors of :func:`band_lu` (LAPACK dgbtrs)."""
    if lower == 1 and upper == 1:
        _tri_solve(ab, ipiv, b)
        return
    m = ab.shape[1]
    kv = lower + upper
    for j in range(m - 1):
        lm = min(lower, m - 1 - j)
        p = ipiv[j]
        if p != j:
            t = b[p]
            b[p] = b[j]
            b[j] = t
        for i in range(1, lm + 1):
            b[j + i] -= ab[kv + i, j] * b[j]
    for j in range(m - 1, -1, -1):
        b[j] /= ab[kv, j]
        bj = b[j]
        for i in range(max(0, j - kv), j):
            b[i] -= ab[kv + i - j, j] * bj


@njit(cache=True)
def dense_lu(a, ipiv):
    """In-place LU with partial pivoting of a small dense matrix; False if singular."""
    p = a.shape[0]
    for j in range(p):
        jp = j
        best = abs(a[j, j])
        for i in range(j + 1, p):
            if abs(a[i, j]) > best:
                best = abs(a[i, j])
                jp = i
        ipiv[j] = jp
        if best == 0.0 or not np.isfinite(best):
            return False
        if jp != j:
            for c in range(p):
                t = a[j, c]
                a[j, c] = a[jp, c]
                a[jp, c] = t
        for i in range(j + 1, p):
            a[i, j] /= a[j, j]
            for c in range(j + 1, p):
                a[i, c] -= a[i, j] * a[j, c]
    return True


@njit(cache=True)
def dense_solve(a, ipiv, b):
    """Solve with the factors of :func:`dense_lu` in place."""
    p = a.shape[0]
    for j in range(p):
        if ipiv[j] != j:
            t = b[j]
            b[j] = b[ipiv[j]]
            b[ipiv[j]] = t
    for i in range(p):
        for c in range(i):
            b[i] -= a[i, c] * b[c]
    for i in range(p - 1, -1, -1):
        for c in range(i + 1, p):
            b[i] -= a[i, c] * b[c]
        b[i] /= a[i, i]


@njit(cache=True)
def bordered_factor(ab, lower, upper, ipiv, cmat, dmat, emat, xmat, spiv):
    """Factor [[A, C], [D, E]]: band LU of A, X = A^-1 C, Schur complement E - D X in emat."""
    if not band_lu(ab, lower, upper, ipiv):
        return False
    m = ab.shape[1]
    p = emat.shape[0]
    for k in range(p):
        for i in range(m):
            xmat[i, k] = cmat[i, k]
        band_solve(ab, lower, upper, ipiv, xmat[:, k])
    for r in range(p):
        for k in range(p):
            acc = 0.0
            for i in range(m):
                acc += dmat[r, i] * xmat[i, k]
            emat[r, k] -= acc
    if p > 0:
        return dense_lu(emat, spiv)
    return True


@njit(cache=True)
def bordered_solve(ab, lower, upper, ipiv, dmat, xmat, emat, spiv, b, zbuf):
    """Solve M x = b in place (b = [band part, border part]) with :func:`bordered_factor`."""
    m = ab.shape[1]
    p = emat.shape[0]
    band_solve(ab, lower, upper, ipiv, b[:m])
    if p == 0:
        return
    for r in range(p):
        acc = b[m + r]
        for i in range(m):
            acc -= dmat[r, i] * b[i]
        zbuf[r] = acc
    dense_solve(emat, spiv, zbuf)
    for r in range(p):
        b[m + r] = zbuf[r]
    for i in range(m):
        acc = 0.0
        for k in range(p):
            acc += xmat[i, k] * zbuf[k]
        b[i] -= acc
