"""The reduced drug model: the solute on the step-function front model's bead.

Why this form (and not a calibrated correction of the fluid answer): the drug's release is
decided by three things the fluid answer does not see, diffusion out of the swollen core,
its hindrance and partition in the collapsed shell (D_shell = D0 f(phi_+), K(phi_+), sieving
W(phi_+)), and the competition of both with the fluid's motion (the Peclet number).  A
correction factor fitted to the fluid answer would have to be tabulated over all of them
(law, r_s / xi, r_s / r_f, Y, K0, D0 / D_gel, dose) and would carry no physics between its
nodes.  The front model already gives the mechanics in closed form (module ``evolve``): a
swollen core at phi_- inside R_f(t), a collapsed shell at phi_+ (P(phi_+) = 0) out to a(t),
with solid conserved, (1 - phi_-) R_f^3 + (1 - phi_+) (a^3 - R_f^3) = 1 (eq. FrontEvolve).
In the dry coordinate rho that is an explicit map: the material node rho lies at

    r^3(rho, t) = rho^3 / (1 - phi_-)                          (rho <= rho_f, the core)
    r^3(rho, t) = R_f^3 + (rho^3 - rho_f^3) / (1 - phi_+)       (rho > rho_f, the shell)

with rho_f^3 = (1 - phi_-) R_f^3 (the front's dry position).  The node volumes are all the
solute transport of ``solver.solute`` needs (its kernels take r^3 at the nodes over time):
continuity gives the fluid flux through every node (the fluid the collapsing front expels
flows out through the shell: advection, sieved), the cells' porosity and mesh stretch give
D0 f, K and W by the same laws as the full solver's drug (docs/drug.md), and diffusion acts
on c / K with the fixed-point kernels' TR-BDF2.  So the reduced model is the full drug model
with the front model's mechanics: a 1-D spherical diffusion-advection problem on a small
fixed dry grid (``cells``), sampled where the front crosses the nodes, and after the front
reaches the centre the collapsed bead held (diffusion alone).  A ``wait`` at T_start before
the heating holds the swollen equilibrium (pure diffusion: Crank's sphere).

Limits it meets exactly (tests/test_drug_reduced.py): no front (a wait alone) is Crank's
series for a sphere into a perfect sink (eq. 6.20 of Crank, The Mathematics of Diffusion);
D0 = 0 without sieving releases drug in proportion to the expelled fluid (the fluid
answer).  What it leaves out is the mechanics' own error: the front model's (its nucleation
at the edge, the shell's O(1/Omega) porosity profile, the interfacial length), which is why
its error is measured against the full solver (docs/drug_reduced.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from ..solute.result import ReleaseResult
from ..solute.transport import Solute, release_on_nodes
from .result import FrontResult

# the grid and tolerances (docs/drug_reduced.md sec. 3, against 384 cells, 3 samples per
# cell, rtol 1e-6: dose times within 1 % unhindered, 4 % sieved; rtol 3e-3 moves them by
# 1e-4 against 1e-3, the grid's error being 10-40 times that)
CELLS = 48  # dry cells
GRADING = 2.0  # rho_k = 1 - (1 - k / CELLS)^2: finer at the edge
PER_CELL = 1  # samples per node the front crosses (the node crossings themselves)
HOLD_SAMPLES = 48  # samples of the collapsed (or waiting) bead, geometric in time
HORIZON = 32.0  # tau after the heating starts: the longest a drug dose may take
RTOL = 3e-3


@dataclass(frozen=True)
class FrontGeometry:
    """The front model's bead on a dry grid: samples ``t``, node volumes ``s3`` (len(t),
    cells + 1) at the dry nodes rho_k^3 = ``dry``, the radius a(t) and front R_f(t)."""

    t: np.ndarray
    s3: np.ndarray
    dry: np.ndarray
    radius: np.ndarray
    front: np.ndarray


def dry_grid(cells: int, grading: float = GRADING) -> np.ndarray:
    """rho_k^3 of ``cells`` cells, rho_k = 1 - (1 - k / cells)^grading: uniform in rho for
    grading 1, finer at the edge (where the shell starts thin and the drug's boundary layer
    sits) for grading > 1."""
    if isinstance(cells, bool) or not isinstance(cells, (int, np.integer)) or not (
            8 <= cells <= 4096):
        raise ParameterError("cells", cells, "an integer 8-4096")
    if not (isinstance(grading, (int, float)) and 1.0 <= grading <= 4.0):
        raise ParameterError("grading", grading, "1 <= grading <= 4")
    return (1.0 - (1.0 - np.arange(cells + 1) / cells) ** grading) ** 3


def node_volumes(front: np.ndarray, dry: np.ndarray, phi_minus: float,
                 phi_plus: float) -> np.ndarray:
    """r^3 at the dry nodes ``dry`` (rho^3) for every front position R_f in ``front``
    (module docstring: the core at phi_-, the shell at phi_+, solid conserved)."""
    sm, sp = 1.0 - phi_minus, 1.0 - phi_plus
    xf3 = np.asarray(front, dtype=float)[:, None] ** 3
    rho3 = np.asarray(dry, dtype=float)[None, :]
    return np.where(rho3 <= sm * xf3, rho3 / sm, xf3 + (rho3 - sm * xf3) / sp)


def _hold_times(t0: float, span: float, count: int, first: float) -> np.ndarray:
    """``count`` times after t0 up to t0 + span, geometric from ``first`` (t0 excluded)."""
    first = min(max(first, 1e-12), span)
    return t0 + np.geomspace(first, span, count)


def front_geometry(fr: FrontResult, *, cells: int = CELLS, wait: float = 0.0,
                   horizon: float = HORIZON, per_cell: int = PER_CELL,
                   hold: int = HOLD_SAMPLES, grading: float = GRADING) -> FrontGeometry:
    """The bead of front trajectory ``fr`` (from the initial equilibrium, to the centre:
    ``solver.front.front_trajectory`` / ``sharp_front_trajectory``) on ``cells`` dry
    cells: ``wait`` (tau) at T_start, the heating from t = wait to wait + ``horizon``
    (the collapsed bead held once the front has reached the centre).  Samples: every node
    crossing of the front, ``per_cell`` between two, geometric in time before and after."""
    curve = fr.curve
    if fr.diagnostics.get("stop") != "centre":
        raise ParameterError("front", fr.diagnostics.get("stop"), "a trajectory run to the "
                             "centre (the default stop)")
    dry = dry_grid(cells, grading)
    a0 = curve.levels.a0
    sm = 1.0 - fr.phi_minus
    rho = np.cbrt(dry)
    # front positions: the nodes' (R_f = rho_k / (1 - phi_-)^(1/3), the front at dry node
    # k) and per_cell between them, from the start (R_f = x_start) to the centre
    x_nodes = rho / np.cbrt(sm)
    sub = np.linspace(0.0, 1.0, per_cell + 1)[:-1]
    xs = (x_nodes[:-1, None] + np.diff(x_nodes)[:, None] * sub[None, :]).ravel()
    xs = np.concatenate((xs[xs < curve.x_start], [curve.x_start]))[::-1]
    th = np.asarray(curve.time_of_front(xs), dtype=float)
    th[0], th[-1] = curve.t_start, curve.t_centre
    keep = np.concatenate(([True], np.diff(th) > 0.0))
    th, xs = th[keep], xs[keep]
    if not horizon > 0.0:
        raise ParameterError("horizon", horizon, "> 0 (tau)")
    if horizon < th[-1] - th[0]:  # stop on the way: the front at t0 + horizon last
        keep = th < th[0] + horizon
        t_end = th[0] + horizon
        th = np.append(th[keep], t_end)
        xs = np.append(xs[keep], float(curve.front_at(np.array([t_end]))[0]))
        tail = np.zeros(0)
    else:  # after the centre: the collapsed bead, held
        first = max(th[-1] - th[-2], 1e-6 * horizon) if th.size > 1 else 1e-6 * horizon
        tail = _hold_times(th[-1], horizon - (th[-1] - th[0]), hold, first)
    t = np.concatenate((th - th[0], tail - th[0]))
    x = np.concatenate((xs, np.zeros(tail.size)))
    if wait > 0.0:
        lead = np.concatenate(([0.0], _hold_times(0.0, wait, hold, wait * 1e-6)))
        t = np.concatenate((lead, t[1:] + wait))
        x = np.concatenate((np.full(lead.size, curve.x_start), x[1:]))
    s3 = node_volumes(x, dry, fr.phi_minus, fr.phi_plus)
    if abs(s3[0, -1] - a0**3) > 1e-9 * a0**3:
        raise ParameterError("front", a0, "a trajectory from the initial equilibrium "
                             "(R_f = a0 at the start)")
    return FrontGeometry(t=t, s3=s3, dry=dry, radius=np.cbrt(s3[:, -1]), front=x)


def front_release(fr: FrontResult, solute: Solute, *, cells: int = CELLS, wait: float = 0.0,
                  horizon: float = HORIZON, rtol: float = RTOL, per_cell: int = PER_CELL,
                  hold: int = HOLD_SAMPLES, grading: float = GRADING,
                  twin: str = "exact") -> ReleaseResult:
    """The drug released from the front model's bead (module docstring): a
    ``solver.solute.ReleaseResult`` with its D0 = 0 twin (``squeezed_fraction``; ``twin``
    as in ``release_on_nodes``: by default the expelled fraction where exact)."""
    for name, value in (("wait", wait), ("horizon", horizon)):  # horizon > 0: geometry
        if isinstance(value, bool) or not (isinstance(value, (int, float))
                                           and math.isfinite(value) and value >= 0.0):
            raise ParameterError(name, value, "a finite number >= 0 (tau)")
    g = front_geometry(fr, cells=cells, wait=float(wait), horizon=float(horizon),
                       per_cell=per_cell, hold=hold, grading=grading)
    rel = release_on_nodes(g.t, g.s3, solute, radius=g.radius, dry=g.dry, rtol=rtol,
                           profiles=2, twin=twin)
    rel.diagnostics.update(model="front-solute", front_model=fr.model, cells=int(cells))
    return rel


def time_to_release(rel: ReleaseResult, amount: float, after: float = 0.0) -> float:
    """First time >= ``after`` at which the release since ``after`` reaches ``amount``:
    the root of the samples' monotone cubic (PCHIP; the release into a perfect sink never
    falls), so sparse samples of a smooth release give the time to their interpolation
    order (a linear reading of a sqrt(t) release errs by up to a factor 2 in the first
    interval).  ValueError if never."""
    from scipy.interpolate import PchipInterpolator

    t = rel.t
    r = np.maximum.accumulate(rel.released_fraction)
    base = float(np.interp(after, t, r))
    i0 = int(np.searchsorted(t, after, side="right"))
    hit = np.nonzero(r[i0:] - base >= amount)[0]
    if hit.size == 0:
        raise ValueError(f"a release of {amount:.6g} is not reached by t = {t[-1]:.6g} "
                         f"(at most {float(r[-1] - base):.6g})")
    j = i0 + int(hit[0])
    if j == 0:
        return float(t[0])
    lo, hi = max(j - 3, 0), min(j + 3, t.size)
    tt, rr = t[lo:hi], r[lo:hi]
    uniq = np.concatenate(([True], np.diff(tt) > 0.0))
    f = PchipInterpolator(tt[uniq], rr[uniq] - base - amount)
    a, b = max(float(t[j - 1]), after), float(t[j])
    roots = [x for x in np.atleast_1d(f.solve(0.0, extrapolate=False)) if a <= x <= b]
    return float(roots[0]) if roots else b
