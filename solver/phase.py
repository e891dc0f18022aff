"""Spinodal and coexistence curves (eqs. Spinodal, Coexistence) and the jump classifier.

Both curves are affine in T at fixed stretches (chi is affine in T, eq. FloryParam), so
the spinodal is explicit, T_s(lambda), and the coexistence curve reduces to one bracketed
root in lambda_new.  Membership of the coexistence region is decided by the convexity
construction behind eq. Coexistence: at fixed tangential stretch lambda, the isotropic
state lies in the region when some normal stretch lies below its tangent line,
min_n [W(n, lambda) - W(lambda, lambda) - dW/dn(lambda, lambda) (n - lambda)] < 0.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from functools import lru_cache
from typing import Literal

import numpy as np

from .equilibrium import Branch, equilibrium, nearest_stable
from .errors import ParameterError
from .gel import T_MAX, T_MIN, Gel, as_gel, check_temperature
from .roots import bounded_minimum, brentq
from .thermo import normal_energy, normal_stiffness, normal_stress, osmotic_dp, osmotic_p

Behaviour = Literal["smooth", "front", "delayed_front", "spinodal"]
Direction = Literal["swell", "shrink", "none"]


def _affine(f, gel: Gel, *args):
    """Split a quantity that is affine in T into (value at T=0, slope in T)."""
    v0 = f(gel, 0.0, *args)
    return v0, f(gel, 1.0, *args) - v0


def spinodal_stiffness(gel: Gel, temperature: float, stretch: np.ndarray | float) -> np.ndarray:
    """d^2W/dlambda_i^2 at the isotropic state (eq. Spinodal); < 0 inside the spinodal."""
    lam = np.asarray(stretch, dtype=float)
    return normal_stiffness(gel, temperature, lam, lam)


def spinodal_curve(gel: Gel, t_min: float = T_MIN, t_max: float = T_MAX,
                   n: int = 3000, lambda_max: float = 10.0) -> tuple[np.ndarray, np.ndarray]:
    """(stretch, T) along the spinodal, eq. Spinodal, solved explicitly for T."""
    gel = as_gel(gel)
    lam = np.exp(np.linspace(np.log(1e-6), np.log(lambda_max - 1.0), n)) + 1.0
    s0, s1 = _affine(spinodal_stiffness, gel, lam)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = -s0 / s1
    keep = np.isfinite(t) & (t >= t_min) & (t <= t_max)
    return lam[keep], t[keep]


def tangent_gap(gel: Gel, temperature: float, ln: np.ndarray | float,
                stretch: float) -> np.ndarray:
    """W(n, lambda) minus the tangent line at the isotropic state n = lambda (eq. Coexistence)."""
    lam = float(stretch)
    w0 = normal_energy(gel, temperature, lam, lam)
    s0 = normal_stress(gel, temperature, lam, lam)
    return normal_energy(gel, temperature, ln, lam) - w0 - s0 * (np.asarray(ln) - lam)


def _normal_grid(stretch: float, n: int = 800) -> np.ndarray:
    lo = stretch**-2.0  # J = 1: the dry limit of the normal stretch
    return lo + (np.exp(np.linspace(np.log(1e-9), np.log(30.0 * stretch), n)))


def coexistence_gap(gel: Gel, temperature: float, stretch: float) -> tuple[float, float]:
    """(min gap, arg-min normal stretch) of :func:`tangent_gap`; gap < 0 inside the region."""
    lam = float(stretch)
    grid = _normal_grid(lam)
    gap = tangent_gap(gel, temperature, grid, lam)
    i = int(np.argmin(gap))
    lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    x, fx, _ = bounded_minimum(lambda v: float(tangent_gap(gel, temperature, v, lam)),
                               lo, hi, xatol=1e-12)
    if fx < gap[i]:
        return float(fx), float(x)
    return float(gap[i]), float(grid[i])


def in_coexistence(gel: Gel, temperature: float, stretch: float) -> bool:
    """True when a uniform isotropic state (T, lambda) lies in the coexistence region."""
    gap, _ = coexistence_gap(gel, temperature, stretch)
    return gap < -1e-9 * (1.0 + abs(float(normal_energy(gel, temperature, stretch, stretch))))


def path_crosses_coexistence(gel: Gel, temperature: float, path: np.ndarray,
                             refine: int = 5) -> bool:
    """True when any isotropic state along ``path`` (stretches at T) is in the coexistence region.

    The tangent gap is scanned on a grid for every sample at once; the samples with the
    smallest gaps are then checked with a refined minimum.
    """
    mins = np.empty(len(path))
    for k, lam in enumerate(path):
        mins[k] = np.min(tangent_gap(gel, temperature, _normal_grid(lam, 400), lam))
    for k in np.argsort(mins)[:refine]:
        if in_coexistence(gel, temperature, float(path[k])):
            return True
    return False


def in_spinodal(gel: Gel, temperature: float, stretch: float) -> bool:
    """True when the isotropic state (T, lambda) is inside the spinodal region (eq. Spinodal)."""
    return bool(spinodal_stiffness(gel, temperature, stretch) < 0.0)


def coexistence_points(gel: Gel, stretch: float) -> list[tuple[float, float]]:
    """All (T, lambda_new) solving eq. Coexistence at isotropic stretch lambda, T in range."""
    gel = as_gel(gel)
    lam = float(stretch)

    def temp_for(ln: np.ndarray | float) -> np.ndarray:
        # First equality of eq. Coexistence is affine in T: solve it for T.
        def jump(g: Gel, t: float, v: np.ndarray | float) -> np.ndarray:
            return normal_stress(g, t, v, lam) - normal_stress(g, t, lam, lam)

        s0, s1 = _affine(jump, gel, ln)
        with np.errstate(divide="ignore", invalid="ignore"):
            return -s0 / s1

    def chord(ln: np.ndarray | float) -> np.ndarray:
        t = temp_for(ln)
        return tangent_gap(gel, t, ln, lam)

    grid = _normal_grid(lam, 3000)
    grid = grid[np.abs(grid - lam) > 1e-4 * lam]
    with np.errstate(all="ignore"):
        vals = chord(grid)
        temps = temp_for(grid)
    out = []
    for i in range(grid.size - 1):
        if not (np.isfinite(vals[i]) and np.isfinite(vals[i + 1])):
            continue
        if (grid[i] - lam) * (grid[i + 1] - lam) < 0 or vals[i] * vals[i + 1] > 0:
            continue
        if not (np.isfinite(temps[i]) and np.isfinite(temps[i + 1])):
            continue
        if abs(temps[i] - temps[i + 1]) > 5.0:  # a pole of T(lambda_new), not a root
            continue
        ln = brentq(lambda v: float(chord(v)), grid[i], grid[i + 1], xtol=1e-14)
        t = float(temp_for(ln))
        if T_MIN <= t <= T_MAX:
            out.append((t, float(ln)))
    return out


def coexistence_curve(gel: Gel, t_min: float = T_MIN, t_max: float = T_MAX, n: int = 300,
                      lambda_max: float = 4.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(stretch, T, lambda_new) along the coexistence curve (eq. Coexistence)."""
    gel = as_gel(gel)
    lams, temps, news = [], [], []
    for lam in np.linspace(1.0 + 1e-3, lambda_max, n):
        for t, ln in coexistence_points(gel, lam):
            if t_min <= t <= t_max:
                lams.append(lam)
                temps.append(t)
                news.append(ln)
    return np.array(lams), np.array(temps), np.array(news)


@dataclass(frozen=True)
class JumpClass:
    """What a uniform equilibrium does after an instant jump T_start -> T_end."""

    t_start: float
    t_end: float
    branch: str
    start_stretch: float
    final_stretch: float
    direction: Direction
    behaviour: Behaviour
    reason: str

    def to_dict(self) -> dict[str, float | str]:
        """Plain-data form."""
        return asdict(self)


def classify_jump(gel: Gel, t_start: float, t_end: float, branch: Branch | None = None,
                  path_samples: int = 200) -> JumpClass:
    """Classify a temperature jump (sec. Comparison of results).

    Start: the uniform equilibrium at T_start on ``branch`` (default: swollen when
    heating, shrunken when cooling).  Behaviour at T_end: ``spinodal`` if the start is
    inside the spinodal region, ``front`` if inside the coexistence region,
    ``delayed_front`` if the isotropic path from the start stretch to the final
    equilibrium crosses the coexistence region, else ``smooth``.
    """
    gel = as_gel(gel)
    t0 = check_temperature(t_start, "t_start")
    t1 = check_temperature(t_end, "t_end")
    if branch is None:
        branch = "swollen" if t1 >= t0 else "shrunken"
    if branch not in ("swollen", "shrunken"):
        raise ParameterError("branch", branch, "'swollen' or 'shrunken'")
    return _classify(gel, t0, t1, branch, int(path_samples))


@lru_cache(maxsize=1024)
def _classify(gel: Gel, t0: float, t1: float, branch: Branch, path_samples: int) -> JumpClass:
    """:func:`classify_jump` on validated inputs, memoised (the gel is immutable)."""
    lam0 = equilibrium(gel, t0, branch).stretch
    lam1 = nearest_stable(gel, t1, lam0).stretch
    if abs(lam1 - lam0) <= 1e-12 * lam0:
        return JumpClass(t0, t1, branch, lam0, lam1, "none", "smooth",
                         "the start state is already the equilibrium at T_end")
    direction: Direction = "swell" if lam1 > lam0 else "shrink"
    if in_spinodal(gel, t1, lam0):
        behaviour: Behaviour = "spinodal"
        reason = "the start state is inside the spinodal region at T_end: spinodal decomposition"
    elif in_coexistence(gel, t1, lam0):
        behaviour = "front"
        reason = "the start state is inside the coexistence region at T_end: a front forms"
    else:
        path = lam0 + (lam1 - lam0) * np.linspace(0.0, 1.0, path_samples + 2)[1:-1]
        if path_crosses_coexistence(gel, t1, path):
            behaviour = "delayed_front"
            reason = ("the start state is outside the coexistence region, but the path to the "
                      "final equilibrium crosses it: a front forms after a delay")
        else:
            behaviour = "smooth"
            reason = "the path to the final equilibrium avoids the coexistence region"
    return JumpClass(t0, t1, branch, lam0, lam1, direction, behaviour, reason)


def spinodal_p_prime(gel: Gel, temperature: float, phi: float) -> float:
    """P'(phi) at T, the osmotic stiffness entering eq. Spinodal."""
    return float(osmotic_dp(phi, gel.chi0(temperature), gel.chi1(temperature)))


def shrunken_level(gel: Gel, temperature: float) -> float:
    """The shrunken root phi_+ of P(phi) = 0 at T (sec. FrontSoln): the fully relaxed shell."""
    gel = as_gel(gel)
    chi0, chi1 = gel.chi0(temperature), gel.chi1(temperature)
    phi = np.linspace(1e-9, 1 - 1e-12, 20001)
    p = osmotic_p(phi, chi0, chi1)
    idx = np.nonzero(np.sign(p[:-1]) * np.sign(p[1:]) <= 0)[0]
    if idx.size == 0:
        raise ParameterError("t_end", temperature, "a temperature where P(phi) = 0 has a root")
    i = idx[0]
    return float(brentq(lambda v: osmotic_p(v, chi0, chi1), phi[i], phi[i + 1], xtol=1e-15))


def nucleation_level(gel: Gel, t_start: float, t_end: float, branch: Branch = "swollen") -> float:
    """Edge porosity at which a front has nucleated after T_start -> T_end: midway between
    the start equilibrium's porosity and the final (nearest stable) equilibrium's."""
    gel = as_gel(gel)
    start = equilibrium(gel, t_start, branch)
    final = nearest_stable(gel, t_end, start.stretch)
    return 0.5 * (start.porosity + final.porosity)
