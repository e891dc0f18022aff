"""A batch of beads: its released fluid, its dose time and the spread of its beads (issue 26).

Every bead of a jump follows one dimensionless trajectory a(s) (s = t / tau): the front
model's (memoised, ``model_choice.front_run``).  A bead of dry radius R has
tau(R) = tau_ref (R / R_ref)^2 (eq. timescale) and stores (4 pi/3)(a0^3 - 1) R^3 of fluid
(eq. FluidVolExpelled), so the batch's released fraction of its stored fluid is

    V(t) = sum_k v_k F(t / rho_k),   F(s) = (a0^3 - a(s)^3) / (a0^3 - 1),   rho_k = (R_k/R_ref)^2

with v_k the volume weights of the sizes (a quadrature over the volume-weighted law:
Gauss-Hermite in ln R for a lognormal, Gauss-Legendre for a normal, the rows themselves for
a measured table).  The batch's dose time T solves V(T) = f; it lies between the smallest
and the largest bead's own dose time rho_k s_f (each F_k is monotone), so a bracketing root
finder always converges.  The node count is doubled until T changes by less than ``tol``
(the last change is the reported quadrature error).  R_ref is the number-weighted mean dry
radius; times are in its tau.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from scipy.optimize import brentq

from solver.errors import NotApplicableError, ParameterError

from ..model_choice import MODEL_NAMES, front_run, model_answer
from ..request import DoseRequest
from ..runs.lru import ByteLRU
from ..truth import Part
from ..units import released_fraction, timescale
from .sizes import DrySizes

QUADRATURE_TOL = 1e-6  # relative change of the batch's dose time between n / 2 and n nodes
PERCENTILES = (0.1, 0.5, 0.9)


def exact_release_fraction(fr: Any, s: Any) -> np.ndarray:
    """F(s): the fraction of its stored fluid a bead has released at dimensionless time s
    (eq. FluidVolExpelled on the front model's exact curve, Newton on t(R_f); F(0) = 0,
    constant after the trajectory's end)."""
    a0 = float(fr.radius[0])
    t = np.clip(np.asarray(s, dtype=float), fr.t[0], fr.t_stop)
    x = np.maximum(fr.curve.front_at(t.ravel()), fr.front_stop)
    return released_fraction(a0, np.asarray(fr.curve.radius(x), dtype=float).reshape(t.shape))


TABLE_POINTS = 8001  # F(s) tabulated at this many front positions: |error| < 1e-7
_TABLES: ByteLRU = ByteLRU(32e6, max_items=16)  # bytes: a table and its trajectory


def _table(fr: Any) -> tuple[np.ndarray, np.ndarray]:
    """(s_i, F_i) on front positions clustered at the start (memoised per trajectory):
    t(R_f) is the exact curve's integral and a(R_f) solid conservation (FrontEvolve), so
    the table needs no root finding."""
    hit = _TABLES.get(id(fr))
    if hit is not None and hit[0] is fr:
        return hit[1], hit[2]
    c, a0 = fr.curve, float(fr.radius[0])
    u = np.linspace(0.0, 1.0, TABLE_POINTS)
    x = fr.front_stop + (c.x_start - fr.front_stop) * (1.0 - u**2)
    s = np.asarray(c.time_of_front(x), dtype=float)
    f = released_fraction(a0, np.asarray(c.radius(x), dtype=float))
    s[0], s = fr.t[0], np.maximum.accumulate(s)
    _TABLES[id(fr)] = (fr, s, f)  # the ByteLRU keeps 16 at most
    return s, f


def release_fraction(fr: Any, s: Any) -> np.ndarray:
    """F(s) from the trajectory's table (linear interpolation, |error| < 1e-7 against
    :func:`exact_release_fraction`; tests check it): microseconds for many beads."""
    ts, fs = _table(fr)
    return np.interp(np.asarray(s, dtype=float), ts, fs)


class BatchRelease:
    """V(t) = sum_k v_k F_b(k)(t / rho_k) with ``n`` nodes per panel: ``curves`` (s, F) per
    band of sizes (split at the inner ``edges``, um; one curve serves every bead), the panels
    split at the edges and at the bead that finishes at t (``kink``: the reference bead's
    end, the integrand's kink), so Gauss-Legendre converges fast."""

    def __init__(self, sizes: DrySizes, n: int, curves: list[tuple[np.ndarray, np.ndarray]],
                 kink: float, edges: Any = ()) -> None:
        self.sizes, self.n, self.curves, self.kink = sizes, n, curves, kink
        self.edges = np.asarray(edges, dtype=float)
        self.ref = sizes.mean_um

    @classmethod
    def front(cls, fr: Any, sizes: DrySizes, n: int) -> BatchRelease:
        """On the front model's trajectory ``fr`` (its table: every bead follows it)."""
        return cls(sizes, n, [_table(fr)], fr.t_stop)

    def nodes(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(rho_k, v_k, the band of each node) for time t."""
        cut = (self.ref * math.sqrt(t / self.kink),) if t > 0 else ()
        r, v = self.sizes.nodes(self.n, (*self.edges.tolist(), *cut))
        return (r / self.ref) ** 2, v, np.searchsorted(self.edges, r)

    def __call__(self, t: float) -> float:
        rho, v, band = self.nodes(t)
        if len(self.curves) == 1:  # one curve serves every bead (the front model's)
            return float(np.interp(t / rho, *self.curves[0]) @ v)
        return sum(float(np.interp(t / rho[band == b], s, f) @ v[band == b])
                   for b, (s, f) in enumerate(self.curves))

    def curve(self, times: Any) -> np.ndarray:
        """V at each of ``times``."""
        return np.array([self(float(t)) for t in np.ravel(times)])

    def dose_time(self, fraction: float, single: float, guess: float | None = None) -> float:
        """T with V(T) = fraction; ``single`` is the reference bead's own time s_f.  The
        root lies between the smallest and the largest bead's own time (each F_k is
        monotone); ``guess`` (the previous rung's) narrows the bracket when it holds."""
        rho = self.nodes(single)[0]
        lo, hi = single * float(rho.min()), single * float(rho.max())
        if hi <= lo * (1.0 + 1e-15):
            return lo

        def g(t: float) -> float:
            return self(t) - fraction

        # the tabulated F is within 1e-7 of the curve s_f came from: widen the bracket
        # until it holds (never more than a few steps)
        for _ in range(60):
            if g(lo) <= 0.0:
                break
            lo *= 0.9
        for _ in range(60):
            if g(hi) >= 0.0:
                break
            hi *= 1.1

        if guess is not None and lo < guess < hi:
            a, b = max(lo, 0.98 * guess), min(hi, 1.02 * guess)
            if g(a) < 0.0 < g(b):
                lo, hi = a, b
        return float(brentq(g, lo, hi, xtol=1e-13 * hi, rtol=1e-11))

    def newton(self, t: float, fraction: float) -> float:
        """One Newton step on V(t) = fraction from t (a central-difference slope)."""
        h = 1e-4 * t
        slope = (self(t + h) - self(t - h)) / (2.0 * h)
        return t - (self(t) - fraction) / slope if slope > 0 else t


NODE_LADDER = (8, 16, 32, 64, 128, 256)  # Gauss-Legendre nodes per panel
FIRST_PANEL_NODES = 32  # the first rung of an answer (16 leaves 1e-4 at CV 0.3)


@dataclass(frozen=True)
class Quadrature:
    """The quadrature over sizes: its rule, the nodes needed (in all), its error (the
    relative change of the dose time from the previous rung), and its table (nodes, the
    batch's dose time with that many nodes)."""

    rule: str
    nodes: int
    error: float
    converged: bool
    table: list[tuple[int, float]]
    per_panel: int = 0

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form."""
        return asdict(self)


def _rule(sizes: DrySizes) -> str:
    if sizes.exact:
        return ("exact: the sum over the table's distinct sizes" if sizes.spec.kind == "table"
                else "exact: a single size")
    var = "ln R" if sizes.spec.kind == "lognormal" else "R"
    return (f"Gauss-Legendre in {var} over the volume-weighted law, split at the bead that "
            "finishes at the dose time (the integrand's kink)")


def _exact(fr: Any, sizes: DrySizes, fraction: float,
           single: float) -> tuple[float, Quadrature, BatchRelease]:
    rel = BatchRelease.front(fr, sizes, 0)
    t = rel.dose_time(fraction, single)
    k = len(rel.nodes(t)[0])
    return t, Quadrature(_rule(sizes), k, 0.0, True, [(k, t)], k), rel


def converge(fr: Any, sizes: DrySizes, fraction: float, single: float,
             tol: float = QUADRATURE_TOL) -> tuple[float, Quadrature, BatchRelease]:
    """The batch's dose time: solved with n nodes per panel (from FIRST_PANEL_NODES), then
    checked with 2n by one Newton step on V_2n (its change is the quadrature error of the
    n-node time; the answer is the 2n-node time, whose own error is far smaller); n is
    doubled until the change is below ``tol``."""
    if sizes.exact:
        return _exact(fr, sizes, fraction, single)
    table: list[tuple[int, float]] = []
    n, t, err = FIRST_PANEL_NODES, None, math.inf
    while True:
        rel = BatchRelease.front(fr, sizes, n)
        t = rel.dose_time(fraction, single, t)
        table.append((len(rel.nodes(t)[0]), t))
        fine = BatchRelease.front(fr, sizes, 2 * n)
        t2 = fine.newton(t, fraction)
        err = abs(t2 - t) / t2
        table.append((len(fine.nodes(t2)[0]), t2))
        if err < tol or 2 * n >= NODE_LADDER[-1]:
            return t2, Quadrature(_rule(sizes), table[-1][0], err, err < tol, table,
                                  2 * n), fine
        n, t = 2 * n, t2


def convergence_table(fr: Any, sizes: DrySizes, fraction: float, single: float,
                      ladder: tuple[int, ...] = NODE_LADDER) -> list[tuple[int, float]]:
    """(nodes, the batch's dose time solved with them) for every rung of ``ladder``
    (nodes per panel): the quadrature's convergence table (tests, docs/batch.md)."""
    out: list[tuple[int, float]] = []
    t = None
    for n in ladder:
        rel = BatchRelease.front(fr, sizes, n)
        t = rel.dose_time(fraction, single, t)
        out.append((len(rel.nodes(t)[0]), t))
    return out


@dataclass(frozen=True)
class NodesPart:
    """The ``nodes`` entry of a batch's uncertainty under a protocol
    (dosing.population.curves): which size nodes ran on the full solver and which on the
    reduced model, in words (``relative`` None: not a size)."""

    relative: float | None
    full_um: list[float]
    reduced_um: list[float]
    full_fluid_fraction: float
    own_time_full_um: list[float]
    text: str


@dataclass
class BatchAnswer:
    """A batch's dose: its time (dimensionless in the reference bead's tau, and seconds),
    the reference (number-weighted mean) bead's own time, the fraction of beads that have
    delivered their own dose by then, the 10th / 50th / 90th percentile bead's dose time,
    the distribution, the model and the quadrature."""

    distribution: dict[str, Any]
    description: str
    model: str
    dose_fraction: float
    reference_dry_radius_um: float
    time: float
    seconds: float | None
    timescale_seconds: float | None
    mean_bead_time: float
    mean_bead_seconds: float | None
    delay: float
    fraction_delivered: float
    percentile_radii_um: list[float]
    percentile_times: list[float]
    percentile_seconds: list[float] | None
    quadrature: Quadrature
    note: str
    # a validated batch's (dosing.population.bands: its parts and ``bands``) or a batch's
    # under a protocol (dosing.population.curves: its parts and ``nodes``)
    uncertainty: dict[str, Part | NodesPart | list[dict[str, float]]] | None = None

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form (JSON-ready)."""
        d = asdict(self)
        d["quadrature"] = self.quadrature.to_dict()
        return d


def batch_sizes(req: DoseRequest) -> DrySizes:
    """The request's batch as dry radii (swollen sizes over a0)."""
    if req.size_distribution is None:
        raise ParameterError("size_distribution", None, "a size distribution for a batch")
    return req.size_distribution.resolve(req.start_radius, req.t_start)


def batch_answer(req: DoseRequest, tol: float = QUADRATURE_TOL) -> BatchAnswer:
    """The batch's dose from the front model (milliseconds; module doc)."""
    sizes = batch_sizes(req)
    choice = model_answer(req)
    if choice.front_time is None:
        raise NotApplicableError(f"a batch answer needs the front model: {choice.why}")
    fr = front_run(req.gel, req.t_start, req.t_end, req.branch, req.settings.regularized)
    single = choice.front_time
    t, quad, _ = converge(fr, sizes, req.fraction, single, tol)
    ref = sizes.mean_um
    delivered = float(sizes.cdf(ref * math.sqrt(t / single))) if single > 0 else 1.0
    pr = np.asarray(sizes.quantile(np.array(PERCENTILES)), dtype=float)
    pt = (pr / ref) ** 2 * single
    tau = timescale(ref, req.t_end, req.constants).seconds
    note = (f"{MODEL_NAMES[choice.model]}: one dimensionless trajectory serves every bead "
            f"(tau ~ R^2, fluid ~ R^3); the batch ({sizes.spec.describe()}) releases "
            f"{req.fraction:.0%} of its fluid at {t:.4g} tau_ref = {t * tau:.4g} s, "
            f"{t / single - 1.0:+.1%} against its number-weighted mean bead "
            f"({ref:.4g} um dry); {delivered:.0%} of the beads have delivered their own dose "
            f"by then. Quadrature: {quad.rule}, {quad.nodes} nodes, error {quad.error:.1e}.")
    return BatchAnswer(
        distribution=sizes.spec.to_dict(), description=sizes.spec.describe(),
        model=choice.model, dose_fraction=req.fraction, reference_dry_radius_um=ref,
        time=t, seconds=t * tau, timescale_seconds=tau, mean_bead_time=single,
        mean_bead_seconds=single * tau, delay=t / single - 1.0, fraction_delivered=delivered,
        percentile_radii_um=pr.tolist(), percentile_times=pt.tolist(),
        percentile_seconds=(pt * tau).tolist(), quadrature=quad, note=note)


def batch_release(req: DoseRequest, times: Any, tol: float = QUADRATURE_TOL) -> dict[str, Any]:
    """The batch's released fraction at ``times`` (dimensionless, in the reference bead's
    tau) and the 10th / 50th / 90th percentile beads' own curves (a release plot per size
    class and for the batch)."""
    sizes = batch_sizes(req)
    choice = model_answer(req)
    if choice.front_time is None:
        raise NotApplicableError(f"a batch release needs the front model: {choice.why}")
    fr = front_run(req.gel, req.t_start, req.t_end, req.branch, req.settings.regularized)
    _, _, rel = converge(fr, sizes, req.fraction, choice.front_time, tol)
    t = np.asarray(times, dtype=float)
    ref = sizes.mean_um
    pr = np.asarray(sizes.quantile(np.array(PERCENTILES)), dtype=float)
    classes = {f"p{round(100 * p)}": release_fraction(fr, t / (r / ref) ** 2).tolist()
               for p, r in zip(PERCENTILES, pr, strict=True)}
    return {"time": t.tolist(), "batch": rel.curve(t).reshape(t.shape).tolist(),
            "mean_bead": release_fraction(fr, t).tolist(), "size_classes": classes,
            "size_class_radii_um": pr.tolist(), "reference_dry_radius_um": ref}
