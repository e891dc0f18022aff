"""A batch of drug-loaded beads releasing into one shared, well-mixed medium (issue 26).

Every bead sees the medium's concentration c(t).  The solute is linear in (m, c) for a given
mechanics, so the batch is one linear system: the cells of every size class k (its own
Lagrangian solute, module ``solver.solute.kernels``) and the drug in the medium P (a
fraction of the batch's load).  Class k follows the batch's one dimensionless trajectory in
its own time s = t / rho_k (rho_k = tau_k / tau_ref = (R_k / R_ref)^2, eq. timescale); in
its own units (load, 4 pi R_k^3 / 3) its operator is the single bead's
``kernels.operator`` with the medium's unknown read as c:

    dm_k/dt = (A_k m_k + alpha_k c e_edge) / rho_k,
    dP/dt   = sum_k nu_k (beta_k m_k,edge - alpha_k c) / rho_k,     c = P / v(t),

with nu_k the classes' shares of the load (their volume weights: a bead's load is
K c_load (a0^3 - 1) 4 pi R^3 / 3 with one loading solution), v(t) = v0 + sum_k nu_k
(a0^3 - a_k(t)^3) the medium in units of the batch's dry volume (it grows by the expelled
fluid, as the single bead's), beta_k the edge's outflow per unit edge mass and alpha_k the
medium's back-flux per unit c (re-absorption included).  A perfect sink is c = 0.  One bead
class with nu = 1 is exactly the single bead in a medium v0 (the kernel's finite-medium
boundary condition).

Time: fixed-step TR-BDF2 (the kernel's scheme) on the union of the classes' mechanics
sample times (t = rho_k s_j: no step crosses a kink of any class's piecewise-linear
geometry), each interval cut into ``sub`` steps, or on even intervals; the node fluxes are
each step's mean and the conductances frozen at each class's sample interval's midpoint, as
the kernel does (at the step's midpoint when a step spans several).  Each implicit stage is
an arrowhead system solved by its Schur complement: two tridiagonal solves per class, then
one scalar equation for P.  Every flux enters two rows with opposite signs (in load
units), so the batch's mass is conserved to round-off by the scheme.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from solver.errors import ParameterError, SolverError
from solver.solute import Solute
from solver.solute.kernels import A_N, A_U, D_COEF, GAMMA, _solve, conductances, operator


@dataclass
class MediumRelease:
    """The coupled batch's release on the output ``t`` (units of tau_ref): the batch's
    released fraction of its load, each class's own (net: what left minus what it took
    back), the medium's concentration (per load / batch dry volume), the classes' load
    shares ``nu`` and time ratios ``rho``, the mass-balance error (max |gel + medium - 1|)
    and the steps taken."""

    t: np.ndarray
    released: np.ndarray
    class_released: np.ndarray  # (classes, times)
    concentration: np.ndarray
    nu: np.ndarray
    rho: np.ndarray
    medium_volume: float | None
    mass_balance_error: float
    steps: int
    diagnostics: dict[str, Any] = field(default_factory=dict)

    def released_at(self, time: float) -> float:
        """The batch's released fraction at ``time`` (linear between outputs)."""
        return float(np.interp(time, self.t, self.released))

    def time_to_release(self, fraction: float) -> float:
        """The first time the batch has released ``fraction`` of its load (ValueError when
        it does not within the outputs)."""
        r = self.released
        hit = np.nonzero(r >= fraction)[0]
        if hit.size == 0:
            raise ValueError(f"the batch releases at most {r.max():.6g} of its load by "
                             f"t = {self.t[-1]:.6g}")
        i = int(hit[0])
        if i == 0:
            return float(self.t[0])
        t0, t1, r0, r1 = self.t[i - 1], self.t[i], r[i - 1], r[i]
        return float(t0 + (fraction - r0) * (t1 - t0) / (r1 - r0))


class _Class:
    """One size class: the shared trajectory's node volumes in its own time, its work
    arrays and its state (solute mass per cell, units of its own load)."""

    def __init__(self, s: np.ndarray, s3: np.ndarray, dw: np.ndarray, rho_dry: np.ndarray,
                 par: Any, rho: float, m0: np.ndarray) -> None:
        self.s, self.s3, self.dw, self.rd, self.par, self.rho = s, s3, dw, rho_dry, par, rho
        n = dw.size
        self.n = n
        self.m = m0.copy()
        z = np.zeros
        self.lo, self.di, self.up = z(n + 1), z(n + 1), z(n + 1)
        self.r3, self.q, self.g, self.fw, self.fl = z(n + 1), z(n), z(n), z(n), z(4)
        self.phi, self.lam, self.kc, self.wc = z(n), z(n), z(n), z(n)
        self.cp, self.out = z(n + 1), z(n)
        self.s3a, self.s3b = s3[0].copy(), s3[0].copy()
        self.frozen = -1  # the sample interval whose conductances g holds (-1: none)

    def _volumes(self, s: float) -> np.ndarray:
        """r^3 at the nodes at own time s (linear between samples; the final state after
        the trajectory's end: the bead rests there)."""
        if s >= self.s[-1]:
            return self.s3[-1]
        j = int(np.searchsorted(self.s, s, side="right")) - 1
        th = (s - self.s[j]) / (self.s[j + 1] - self.s[j])
        return (1.0 - th) * self.s3[j] + th * self.s3[j + 1]

    def step(self, ta: float, tb: float) -> None:
        """Prepare the step [ta, tb] (units of tau_ref): the node volumes at its ends, the
        node flux rates (own time; the mean over the step, so the fluid volumes change
        exactly by the trajectory's) and the conductances at its midpoint geometry."""
        sa, sb = ta / self.rho, tb / self.rho
        self.s3a, self.s3b = self._volumes(sa), self._volumes(sb)
        self.q[:] = -(self.s3b[1:] - self.s3a[1:]) / (sb - sa)
        if self.par.d0 <= 0.0:
            return
        sm, last = 0.5 * (sa + sb), self.s.size - 1
        j = int(np.searchsorted(self.s, sm, side="right")) - 1
        tol = 1e-12 * max(1.0, sb)
        if j < last and sa >= self.s[j] - tol and sb <= self.s[j + 1] + tol:
            key = j  # inside one sample interval: frozen at its midpoint, as the kernel
            geo = 0.5 * (self.s3[j] + self.s3[j + 1])
        else:
            key, geo = -1, 0.5 * (self.s3a + self.s3b)
        if key < 0 or key != self.frozen:
            conductances(np.ascontiguousarray(geo), self.dw, self.rd, self.par, self.g,
                         self.phi, self.lam, self.kc, self.wc)
        self.frozen = key

    def at(self, theta: float) -> tuple[float, float, float]:
        """Assemble the operator at the fraction ``theta`` of the step: (alpha, beta, a^3),
        rates per unit own time."""
        self.r3[:] = (1.0 - theta) * self.s3a + theta * self.s3b
        if not operator(self.r3, self.dw, self.rd, self.par, self.q, self.g, 1.0, self.lo,
                        self.di, self.up, self.fw, self.fl, self.phi, self.lam, self.kc,
                        self.wc):
            raise SolverError("batch medium: a cell without fluid", {"theta": theta})
        n = self.n
        return float(self.up[n - 1]), float(self.lo[n - 1]), float(self.r3[n])

    def apply(self, m: np.ndarray) -> np.ndarray:
        """A m over the cells (own time), without the medium's column."""
        n = self.n
        out = self.di[:n] * m
        out[1:] += self.lo[: n - 1] * m[:-1]
        out[:-1] += self.up[: n - 1] * m[1:]
        return out

    def solve(self, dh: float, rhs: np.ndarray) -> np.ndarray:
        """(I - dh A / rho)^-1 rhs over the cells."""
        n = self.n
        _solve(self.lo[: n - 1], self.di[:n], self.up[: n - 1], dh / self.rho,
               np.ascontiguousarray(rhs), self.out, self.cp)
        return self.out.copy()


def _start(s3: np.ndarray, dw: np.ndarray, par: Any) -> tuple[np.ndarray, np.ndarray]:
    """(dry node radii, the loaded state): uniform in equilibrium with one loading solution
    (m_i ~ w_i K_i, total 1), as ``solver.solute.release``."""
    from solver.solute.kernels import cell_props

    n = dw.size
    rho = np.cbrt(np.concatenate(([0.0], np.cumsum(dw))))
    phi, lam, kc, wc = (np.zeros(n) for _ in range(4))
    cell_props(np.ascontiguousarray(s3[0]), dw, rho, par, phi, lam, kc, wc)
    m = (s3[0, 1:] - s3[0, :-1] - dw) * kc
    return rho, m / m.sum()


GRADING = 0.25  # near the start, steps <= GRADING / sub x t (the start's sqrt(t) layer)
START_FLOOR = 1e-10  # the first step, a fraction of the grid's first interval


def time_grid(s: np.ndarray, rho: np.ndarray, t_end: float, times: np.ndarray,
              sub: int, points: int | None = None) -> np.ndarray:
    """The union of the classes' sample times rho_k s_j (or, given ``points``, that many
    even intervals; 0: none) and the output times up to ``t_end``, each interval cut into ``sub``
    equal steps, the start graded."""
    pts = [times[times <= t_end], np.array([0.0, t_end])]
    if points is None:
        pts += [r * s[r * s < t_end] for r in rho]
    elif points > 0:
        pts.append(np.linspace(0.0, t_end, points + 1))
    base = np.unique(np.concatenate(pts))
    base = base[np.concatenate(([True], np.diff(base) > 1e-14 * max(t_end, 1.0)))]
    frac = np.arange(sub) / sub
    fine = np.concatenate(((base[:-1, None] + np.diff(base)[:, None] * frac[None, :]).ravel(),
                           base[-1:]))
    if fine.size < 2:
        return fine
    # the release starts in a diffusive layer (sqrt(t)): steps <= q t until the grid's own
    # steps are finer (q = GRADING / sub, so the start converges with the rest)
    q = GRADING / sub
    h0 = fine[1]
    k = int(math.ceil(math.log(1.0 / (q * START_FLOOR)) / math.log1p(q)))
    geo = h0 * START_FLOOR * (1.0 + q) ** np.arange(k + 1)
    return np.unique(np.concatenate((fine, geo[geo < h0 / q])))


def coupled_release(s: Any, s3: Any, solute: Solute, rho: Any, nu: Any,
                    medium_volume: float | None, times: Any, sub: int = 2,
                    points: int | None = None) -> MediumRelease:
    """The batch's release into one medium (module doc).

    ``s`` (samples) and ``s3`` (samples, n + 1: the node volumes r^3 of the dry cells,
    ``solver.solute.node_volumes``) are the one dimensionless mechanics trajectory;
    ``solute`` its drug (its own ``release_volume`` is not used); ``rho`` the classes' tau
    over the reference tau, ``nu`` their shares of the load (normalised here);
    ``medium_volume`` v0 in units of the batch's dry volume (None: a perfect sink);
    ``times`` the outputs (units of tau_ref, from 0); ``sub`` steps per grid interval;
    ``points``: even grid intervals (None: the classes' own sample times; 0: the outputs
    alone)."""
    s = np.asarray(s, dtype=float)
    s3 = np.ascontiguousarray(s3, dtype=float)
    rho = np.atleast_1d(np.asarray(rho, dtype=float))
    nu = np.atleast_1d(np.asarray(nu, dtype=float))
    times = np.asarray(times, dtype=float)
    if rho.size != nu.size or rho.size == 0 or not np.all(rho > 0) or not np.all(nu >= 0):
        raise ParameterError("size_distribution", rho.size, "classes with tau > 0 and "
                             "shares >= 0")
    nu = nu / nu.sum()
    if s.size < 2 or s3.shape[0] != s.size or abs(s[0]) > 1e-14:
        raise ParameterError("mechanics", s.size, "at least two samples from s = 0")
    if times.size == 0 or times[0] < 0 or np.any(np.diff(times) < 0):
        raise ParameterError("times", times, "non-decreasing times >= 0")
    if isinstance(sub, bool) or not isinstance(sub, int) or not 1 <= sub <= 64:
        raise ParameterError("sub", sub, "an integer 1-64")
    n = s3.shape[1] - 1
    a3_0 = float(s3[0, n])
    if medium_volume is not None and not medium_volume > 0.0:
        raise ParameterError("medium_volume", medium_volume, "None (a perfect sink) or > 0")
    dw = np.diff((np.arange(n + 1) / n) ** 3)
    par = solute.params()
    rd, m0 = _start(s3, dw, par)
    classes = [_Class(s, s3, dw, rd, par, float(r), m0) for r in rho]
    grid = time_grid(s, rho, float(times[-1]), times, sub, points)
    sink = medium_volume is None
    v0 = 0.0 if sink else float(medium_volume)
    p = 0.0  # the medium's drug, a fraction of the batch's load

    def assemble(theta: float) -> tuple[list[tuple[float, float]], float]:
        ab, vol = [], v0
        for c in classes:
            alpha, beta, a3 = c.at(theta)
            ab.append((alpha, beta))
            vol += nu_of[id(c)] * (a3_0 - a3)
        return ab, (0.0 if sink else 1.0 / vol)

    nu_of = {id(c): float(w) for c, w in zip(classes, nu, strict=True)}

    def rates(ab: list[tuple[float, float]], inv_v: float, ms: list[np.ndarray],
              pp: float) -> tuple[list[np.ndarray], float]:
        conc = pp * inv_v
        fs, fp = [], 0.0
        for c, (alpha, beta), m in zip(classes, ab, ms, strict=True):
            f = c.apply(m)
            f[-1] += alpha * conc
            fs.append(f / c.rho)
            fp += nu_of[id(c)] * (beta * m[-1] - alpha * conc) / c.rho
        return fs, fp

    def implicit(ab: list[tuple[float, float]], inv_v: float, dh: float,
                 rhs: list[np.ndarray], rp: float) -> tuple[list[np.ndarray], float]:
        """(I - dh B) (m, P) = (rhs, rp) by the Schur complement on P."""
        av, bv = [], []
        den, num = 1.0, rp
        e = np.zeros(classes[0].n)
        for c, (alpha, beta), r in zip(classes, ab, rhs, strict=True):
            a = c.solve(dh, r)
            e[-1] = dh * alpha * inv_v / c.rho
            b = c.solve(dh, e) if inv_v > 0.0 else np.zeros_like(a)
            w = nu_of[id(c)] * dh * beta / c.rho
            den += nu_of[id(c)] * dh * alpha * inv_v / c.rho - w * b[-1]
            num += w * a[-1]
            av.append(a)
            bv.append(b)
        pp = num / den
        return [a + pp * b for a, b in zip(av, bv, strict=True)], pp

    out_rel = np.zeros((rho.size, times.size))
    out_p = np.zeros(times.size)
    out_c = np.zeros(times.size)
    # per class: the net drug it has released (the medium's share that came from it)
    gone = np.zeros(rho.size)
    balance = 0.0
    k_out = 0

    def record(t: float, inv_v: float) -> None:
        nonlocal k_out
        while k_out < times.size and times[k_out] <= t + 1e-12 * max(1.0, t):
            out_rel[:, k_out] = [1.0 - c.m.sum() for c in classes]
            out_p[k_out] = p
            out_c[k_out] = p * inv_v
            k_out += 1

    record(0.0, 0.0 if sink else 1.0 / v0)
    steps = 0
    for ta, tb in zip(grid[:-1], grid[1:], strict=True):
        h = tb - ta
        if h <= 0.0:
            continue
        dh = D_COEF * h
        for c in classes:
            c.step(ta, tb)
        ab0, iv0 = assemble(0.0)
        ms = [c.m for c in classes]
        f0, fp0 = rates(ab0, iv0, ms, p)
        abg, ivg = assemble(GAMMA)
        u, up = implicit(abg, ivg, dh, [m + dh * f for m, f in zip(ms, f0, strict=True)],
                         p + dh * fp0)
        ab1, iv1 = assemble(1.0)
        y, p = implicit(ab1, iv1, dh, [A_U * a + A_N * m for a, m in zip(u, ms, strict=True)],
                        A_U * up + A_N * p)
        for c, m in zip(classes, y, strict=True):
            c.m = m
        steps += 1
        total = sum(nu_of[id(c)] * c.m.sum() for c in classes) + p
        balance = max(balance, abs(total - 1.0))
        if not math.isfinite(total):
            raise SolverError("batch medium: a non-finite state", {"t": tb})
        record(tb, iv1)
    gone = out_rel
    return MediumRelease(
        t=times.copy(), released=out_p, class_released=gone, concentration=out_c,
        nu=nu, rho=rho, medium_volume=None if sink else v0, mass_balance_error=balance,
        steps=steps, diagnostics={"grid_points": int(grid.size), "sub": sub, "n": n})
