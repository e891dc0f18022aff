"""The front model under a slowly changing temperature T(t) (issue 24; docs/heating.md).

Three stages, each the leading order in 1/Omega of the paper's model (sec. FrontSoln):

1. Uniform shrinking.  From the equilibrium at T_start the bead stays uniform and relaxes
   towards the equilibrium of the current temperature (eq. EqlEqn; the stable branch it is
   on, the shrunken one past the fold) as a linear poro-elastic sphere: the volume V = a^3
   obeys dV/dt = -m(T) (V - V_eq(T)) / tau_lag, tau_lag = a^2 / (15 D), D = k(phi)
   d^2W/dlambda_n^2 / lambda (the diffusivity of eq. PDE_Dimless linearised about the
   uniform state; 15 = 1 / sum_n 6/(n pi)^4, the mean lag of Crank's diffusive sphere with
   a fixed surface value, Tanaka & Fillmore 1979).  A one-mode closure, not exact: this
   model's edge follows a (eq. Boundary_Dimless), so its modes depend on G / (K + 4G/3)
   (Li & Tanaka 1990); the closure's error is largest for small doses, whose time is mostly
   this stage (10 % doses 10-63 % late, docs/heating.md), which lie outside the region.
2. Nucleation.  When the uniform state (T(t), a(t)) enters the coexistence region
   (eq. Coexistence at the isotropic stretch; T_n(lambda), tabulated) a front forms at the
   edge: the core keeps phi_- = 1 - a_n^-3, the current uniform porosity.
3. The front, with levels at the current temperature: the shell at phi_+(T(t)) (P = 0),
   the front condition at T(t) (the sharp-interface Maxwell level F_M(T) of module sharp,
   or the paper's eq. BVP_Front_BCFront), solid conservation s_+ (a^3 - R_f^3) + s_- R_f^3
   = 1.  With s_+ changing the shell also expels its own fluid: r^2 v_s = [3 (s_+ - s_-)
   R_f^2 R_f' - s_+' (r^3 - R_f^3)] / (3 s_+), so the flux A(r) = r^2 dmu/dr is no longer
   uniform and the shell's integral of eq. BVP_Front gives

       dR_f/dt = a (s_+ m k_+ N + s_+' I / 3) / ((s_+ - s_-) R_f (a - R_f)),
       I = a^2/2 - 3 R_f^2/2 + R_f^3/a,   N = F - E(a) - [h]  (module flux),

   which is eq. FrontEvolve when T is constant.  After the front reaches the centre the
   bead is uniform at phi_+(T(t)).

Heating only: the program's temperature must not fall (NotApplicableError otherwise).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.polynomial import Chebyshev
from scipy.interpolate import CubicSpline

from ..equilibrium import equilibrium, residual
from ..errors import NotApplicableError, ParameterError, SolverError
from ..gel import T_MAX, Gel, as_gel
from ..heating import Program, temperature_rate
from ..phase import coexistence_points, shrunken_level
from .maxwell import maxwell_pair
from .slow_kernel import integrate, level_values, radius, rhs

NUCLEATION_GRID = 24  # stretches at which the coexistence onset is found (spline between)
EDGE_GRID = 200  # stretches at which T_n(lambda) is tabulated (linear between)
LEVEL_DEGREE = 12  # Chebyshev degree of phi_+(T) and F(T) over a run's temperatures
THIN_SHELL = 1e-4  # the shell thickness (relative to a) the front stage starts from
RTOL = 1e-8
EDGE_FOLD = True  # nucleation waits for the edge's swollen root to vanish
HORIZON = 50.0  # tau held at the last temperature after the program


# ----------------------------------------------------------------------------- tables
@lru_cache(maxsize=64)
def equilibrium_branches(gel: Gel, a0: float) -> tuple[np.ndarray, np.ndarray, float]:
    """(T, lambda) along the stable equilibria a bead heated from stretch ``a0`` follows
    (the swollen branch to its fold, then the shrunken one; eq. EqlEqn solved for T, which
    it is affine in), and the fold temperature (inf without a fold)."""
    lam = np.linspace(1.0005, a0 * 1.02, 6000)
    r0 = residual(gel, 0.0, lam)
    r1 = residual(gel, 1.0, lam) - r0
    temps = -r0 / r1
    slope = np.diff(temps)
    j = int(np.searchsorted(lam, a0)) - 1
    lo = j
    while lo > 0 and slope[lo - 1] < 0.0:
        lo -= 1
    sw_t, sw_l = temps[lo:][::-1], lam[lo:][::-1]
    if lo == 0:
        return sw_t, sw_l, math.inf
    hi = 0
    while hi < slope.size and slope[hi] < 0.0:
        hi += 1
    sh_t, sh_l = temps[: hi + 1][::-1], lam[: hi + 1][::-1]
    fold = float(sw_t[-1])
    keep = sh_t > fold
    return np.concatenate([sw_t, sh_t[keep]]), np.concatenate([sw_l, sh_l[keep]]), fold


def edge_fold(gel: Gel, lam: float, t_from: float) -> float:
    """T_e(lambda): the temperature at which the swollen root J of the edge condition
    (eq. Boundary_Dimless, J / a^4 - 1/J + Omega [...] = 0 at a = lambda) disappears on
    heating from ``t_from`` (eq. Boundary_Dimless is affine in T: T(J) explicit; its local
    maximum below the swollen root, on a grid polished by the parabola through three points)."""
    lj = np.linspace(math.log(1e-4), math.log(3.0 * lam**3 - 1.0), 4000)

    def temp_of(ljj: np.ndarray | float) -> np.ndarray:
        jac = 1.0 + np.exp(ljj)
        g = jac / lam**4 - 1.0 / jac
        base = np.log1p(-1.0 / jac) + 1.0 / jac
        m0 = gel.omega * (base + (gel.a0 - gel.a1) / jac**2 + 2.0 * gel.a1 / jac**3)
        m1 = gel.omega * ((gel.b0 - gel.b1) / jac**2 + 2.0 * gel.b1 / jac**3)
        return -(g + m0) / m1

    temps = temp_of(lj)
    cross = np.nonzero(np.diff(np.sign(temps - t_from)))[0]
    if cross.size == 0:
        return math.inf
    j = int(cross[-1])
    while j > 0 and temps[j - 1] >= temps[j]:
        j -= 1
    if j == 0:
        return float(temps[0])
    y0, y1, y2 = temps[j - 1], temps[j], temps[j + 1]  # the parabola's vertex
    den = y0 - 2.0 * y1 + y2
    return float(y1 - 0.125 * (y2 - y0) ** 2 / den) if den < 0.0 else float(y1)


@lru_cache(maxsize=64)
def nucleation_curve(gel: Gel, lam_lo: float, lam_hi: float,
                     t_from: float) -> tuple[np.ndarray, np.ndarray]:
    """(lambda, T_n): the temperature at which a front forms in a uniform bead of stretch
    lambda: the state is in the coexistence region (eq. Coexistence, the lowest such T,
    smooth in lambda: on NUCLEATION_GRID stretches, a cubic spline between) and the edge has
    lost its swollen root (:func:`edge_fold`, on EDGE_GRID stretches), whichever is later."""
    coarse = np.linspace(lam_lo, lam_hi, NUCLEATION_GRID)
    t_c = []
    for lam in coarse:
        pts = [t for t, _ in coexistence_points(gel, float(lam))]
        t_c.append(min(pts) if pts else T_MAX + 100.0)
    lams = np.linspace(lam_lo, lam_hi, EDGE_GRID)
    onset = CubicSpline(coarse, np.minimum(t_c, T_MAX + 100.0))(lams)
    if not EDGE_FOLD:
        return lams, onset
    edge = np.array([edge_fold(gel, float(lam), t_from) for lam in lams])
    return lams, np.maximum(onset, edge)


@lru_cache(maxsize=4096)
def _shrunken_near(gel: Gel, temp: float) -> float:
    """phi_+ at a rounded temperature (the start of the Newton continuation)."""
    return shrunken_level(gel, temp)


@lru_cache(maxsize=4096)
def _pair_near(gel: Gel, temp: float, lt: float) -> tuple[float, float]:
    """The Maxwell pair at a rounded (T, lambda_t) (the start of the Newton continuation)."""
    return maxwell_pair(gel, temp, lt)


def level_tables(gel: Gel, phi_minus: float, t_lo: float, t_hi: float,
                 sharp: bool) -> np.ndarray:
    """Chebyshev coefficients (rows: s_+, ds_+/dT, F) on [t_lo, t_hi] of the shell's solid
    fraction s_+ = 1 - phi_+ (P(phi_+) = 0 at T) and the front condition F at T for a core
    at ``phi_minus``: the Maxwell level Omega P(phi_shell^M) at the core's stretch
    (``sharp``, module sharp) or eq. BVP_Front_BCFront (the paper's)."""
    sm = 1.0 - phi_minus
    lt = sm ** (-1.0 / 3.0)
    nodes = np.polynomial.chebyshev.chebpts2(LEVEL_DEGREE + 1)
    temps = t_lo + (t_hi - t_lo) * 0.5 * (nodes + 1.0)
    phi0 = _shrunken_near(gel, round(float(temps[0]), 2))
    n1, n2 = _pair_near(gel, round(float(temps[0]), 2), round(lt, 3)) if sharp else (1.0, 2.0)
    par = np.array([gel.omega, gel.a0, gel.b0, gel.a1, gel.b1])
    sp, fr, ok = level_values(par, temps, lt, phi0, n1, n2, sharp)
    if not ok:  # the continuation left the pair: each node from its own exact pair
        ok = True
        for i, temp in enumerate(temps):
            try:
                n1, n2 = maxwell_pair(gel, float(temp), lt) if sharp else (1.0, 2.0)
            except NotApplicableError:
                ok = False
                break
            s_i, f_i, ok_i = level_values(par, temps[i:i + 1], lt, phi0, n1, n2, sharp)
            sp[i], fr[i], ok = s_i[0], f_i[0], ok and ok_i
            phi0 = 1.0 - s_i[0]
    if not (ok and np.all(np.isfinite(sp)) and np.all(np.isfinite(fr))):
        raise SolverError("slow front model: the shell levels did not converge",
                          {"t_lo": t_lo, "t_hi": t_hi, "phi_minus": phi_minus})
    out = np.zeros((3, LEVEL_DEGREE + 1))
    c_sp = Chebyshev.fit(temps, sp, LEVEL_DEGREE, domain=[t_lo, t_hi])
    out[0] = c_sp.coef
    der = c_sp.deriv().coef
    out[1, : der.size] = der
    out[2] = Chebyshev.fit(temps, fr, LEVEL_DEGREE, domain=[t_lo, t_hi]).coef
    return out


# ----------------------------------------------------------------------------- result
@dataclass
class SlowFrontResult:
    """The trajectory: (t, a) at the integrator's steps, each target's crossing time, the
    nucleation (time, temperature, core porosity) and the time the front reaches the centre."""

    gel: str
    a0: float
    model: str
    t: np.ndarray
    radius: np.ndarray
    hits: dict[float, float]
    t_nucleation: float | None
    temperature_nucleation: float | None
    phi_minus: float | None
    t_centre: float | None
    ends: dict[int, float] = field(default_factory=dict)
    diagnostics: dict[str, Any] = field(default_factory=dict)

    def time_to_radius(self, target: float, after: float = 0.0) -> float:
        """The time a(t) falls to ``target``: the located crossing for a run's target, else
        a^3 linear between the steps (ValueError if the run never reaches it)."""
        for k, v in self.hits.items():
            if abs(k - target) <= 1e-12 * target and math.isfinite(v) and v >= after:
                return v
        sel = self.t >= after
        t, a = self.t[sel], self.radius[sel]
        hit = np.nonzero(a <= target)[0]
        if hit.size == 0:
            raise ValueError(f"the radius never reaches {target:.6g} (the run ends at "
                             f"{self.radius[-1]:.6g} at t = {self.t[-1]:.6g})")
        j = int(hit[0])
        if j == 0:
            return float(t[0])
        v0, v1 = a[j - 1] ** 3, a[j] ** 3
        return float(t[j - 1] + (t[j] - t[j - 1]) * (v0 - target**3) / (v0 - v1))

    @property
    def terminal_time(self) -> float:
        """The run's last time."""
        return float(self.t[-1])


# ----------------------------------------------------------------------------- the run
def _check_heating(heat: np.ndarray, t_start: float) -> None:
    prev = t_start
    for row in heat[1:]:
        t0, t1, kind, temp0, p, q = row
        end = temp0 + p * (t1 - t0) if kind == 0 else q + (temp0 - q) * math.exp(
            -(t1 - t0) / p)
        if temp0 < prev - 1e-9 or end < temp0 - 1e-9:
            raise NotApplicableError("slow front model not applicable: the temperature "
                                     "falls somewhere in the program (heating only)")
        prev = end


def _params(gel: Gel, program: Program, sm: float, t_lo: float, t_hi: float) -> np.ndarray:
    perm = gel.permeability
    return np.array([gel.omega, gel.a0, gel.b0, gel.a1, gel.b1, float(perm.code),
                     float(perm.beta), float(program.mobility_code), float(program.reference),
                     sm, t_lo, t_hi])


def _temp(heat: np.ndarray, t: float) -> float:
    return float(temperature_rate(heat, float(t))[0])


def slow_front_trajectory(gel: Gel | str, t_start: float, program: Program, *,
                          targets: tuple[float, ...] = (), sharp: bool = True,
                          ends: dict[int, float] | None = None,
                          horizon: float = HORIZON, rtol: float = RTOL) -> SlowFrontResult:
    """The front model under ``program`` from the equilibrium at ``t_start`` (module doc),
    until the radius reaches the smallest of ``targets`` (dry radii; each crossing located)
    or ``horizon`` tau after the program.  ``ends``: until-steps' end times (as
    ``Program.pieces``); without them until-steps are resolved here, in order, by this
    model's own crossing of their radii; ``rtol`` the integrator's relative tolerance.
    NotApplicableError where the temperature falls."""
    gel = as_gel(gel)
    a0 = float(equilibrium(gel, t_start, "swollen").stretch)
    tg = np.sort(np.array([float(x) for x in targets], dtype=float))[::-1].copy()
    if tg.size and not (np.all(np.isfinite(tg)) and tg[-1] >= 1.0 and tg[0] <= a0):
        raise ParameterError("targets", targets, f"radii 1 <= a <= a0 = {a0:.6g}")
    if ends is None:
        ends = _resolve_untils(gel, t_start, program, a0, sharp, horizon)
    heat = program.table(t_start, ends)
    _check_heating(heat, t_start)
    t_last = float(heat[-1, 1])
    t_hi = max(_temp(heat, t_last), float(t_start))
    breaks = np.unique(np.concatenate([heat[1:, 0], heat[1:, 1]]))
    b_t, b_l, fold = equilibrium_branches(gel, a0)
    tab = np.vstack([b_t, b_l**3])
    lam_lo = max(1.02, float(b_l.min()))
    n_l, n_t = nucleation_curve(gel, lam_lo, a0 * 1.001, float(t_start))
    nuc = np.vstack([n_l, np.where(np.isfinite(n_t), n_t, T_MAX + 100.0)])
    empty = np.zeros((3, LEVEL_DEGREE + 1))
    par = _params(gel, program, 1.0, t_start, t_hi)
    t_end = t_last + horizon
    ts, rs, hits, t1, y1, flag = integrate(0, 0.0, a0**3, t_end, breaks, tg, heat, par, empty,
                                           tab, nuc, rtol, 1e-12)
    model = "front-slow-sharp" if sharp else "front-slow"
    res = SlowFrontResult(gel.name, a0, model, ts, rs, {}, None, None, None, None, dict(ends),
                          {"fold_temperature": fold, "stage": "uniform"})
    if flag == 1:
        t_n, a_n = float(t1), float(y1) ** (1.0 / 3.0)
        temp_n = _temp(heat, t_n)
        sm = a_n**-3.0
        lo = temp_n
        hi = max(t_hi, lo + 1e-6)
        cheb = level_tables(gel, 1.0 - sm, lo, hi, sharp)
        par = _params(gel, program, sm, lo, hi)
        x0, dt0 = _thin_shell_start(a_n, t_n, heat, par, cheb, tab)
        left = tg[np.isnan(hits)]
        ts2, rs2, hits2, t2, y2, flag2 = integrate(1, t_n + dt0, x0, t_end, breaks, left,
                                                   heat, par, cheb, tab, nuc, rtol, 1e-14)
        hits[np.isnan(hits)] = hits2
        res.t, res.radius = np.concatenate([ts, ts2]), np.concatenate([rs, rs2])
        res.t_nucleation, res.temperature_nucleation, res.phi_minus = t_n, temp_n, 1.0 - sm
        res.diagnostics.update({"stage": "front", "a_nucleation": a_n,
                                "thin_shell_start": dt0})
        if flag2 == 1:
            res.t_centre = float(t2)
            _after_centre(res, heat, par, cheb, tg, hits, float(t2), t_end)
    res.hits = {float(a): float(h) for a, h in zip(tg, hits, strict=True)}
    return res


def _thin_shell_start(a_n: float, t_n: float, heat: np.ndarray, par: np.ndarray,
                      cheb: np.ndarray, tab: np.ndarray) -> tuple[float, float]:
    """(X0, dt0): the front a thin shell d = THIN_SHELL a_n after dt0, from d^2 = D (t - t_n)
    with dR_f/dt = -(rate) (a / d) near R_f = a (module start)."""
    d = THIN_SHELL * a_n
    rf = a_n - d
    dx = float(rhs(1, t_n, rf**3, heat, par, cheb, tab))  # = 3 R_f^2 dR_f/dt
    if dx >= 0.0:
        return rf**3, 0.0
    speed = -dx / (3.0 * rf * rf)  # |dR_f/dt| = c / d, and d' = (s_- / s_+) |dR_f/dt|
    s_plus = float(np.polynomial.chebyshev.chebval(-1.0, cheb[0]))
    return rf**3, d * s_plus / (2.0 * speed * par[9])


def _after_centre(res: SlowFrontResult, heat: np.ndarray, par: np.ndarray, cheb: np.ndarray,
                  tg: np.ndarray, hits: np.ndarray, t_c: float, t_end: float) -> None:
    """After the core is gone the bead is uniform at phi_+(T(t)): samples and crossings."""
    ts = np.linspace(t_c, t_end, 400)
    rs = np.array([float(radius(1, t, 0.0, heat, par, cheb)) for t in ts])
    for i in np.nonzero(np.isnan(hits))[0]:
        k = np.nonzero(rs <= tg[i])[0]
        if k.size:
            j = int(k[0])
            lo, hi = (ts[j - 1], ts[j]) if j else (t_c, t_c)
            for _ in range(60 if j else 0):
                mid = 0.5 * (lo + hi)
                lo, hi = (lo, mid) if radius(1, mid, 0.0, heat, par, cheb) <= tg[i] else (mid, hi)
            hits[i] = hi
    res.t = np.concatenate([res.t, ts[1:]])
    res.radius = np.concatenate([res.radius, rs[1:]])


def _resolve_untils(gel: Gel, t_start: float, program: Program, a0: float, sharp: bool,
                    horizon: float) -> dict[int, float]:
    """Each until-step's end time, in order, from this model's crossing of its radius."""
    ends: dict[int, float] = {}
    for _ in range(len(program.steps)):
        pending = [p for p in program.pieces(t_start, a0, ends)
                   if p.until is not None and p.step not in ends]
        if not pending:
            break
        p = pending[0]
        part = Program(program.steps[: p.step + 1], program.mobility, program.reference)
        res = slow_front_trajectory(gel, t_start, part, targets=(p.until,), sharp=sharp,
                                    ends=dict(ends), horizon=horizon)
        hit = res.hits.get(float(p.until), math.nan)
        ends[p.step] = p.t1 if not math.isfinite(hit) or hit > p.t1 else max(hit, p.t0)
    return ends
