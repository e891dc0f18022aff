"""The solute carried by the pore fluid: parameters, validation, and the run on a mechanics
result (the kernels are in ``kernels``).

The solute is passive: it does not change the mechanics, so it is integrated after the
mechanical run on the Lagrangian cells, from the run's samples of the node volumes.  In the
dry coordinate the fluid fluxes follow from continuity alone, so advection is exactly
conservative; diffusion uses the physical face areas and distances of r(rho, t).  Units as
in the paper: lengths by the dry radius R, time by tau (eq. timescale), so the diffusivity is
in units of the gel's D = R^2 / tau; volumes in 4 pi R^3 / 3.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from ..errors import ParameterError, SolverError
from ..full.result import FullResult
from .hindrance import MESH_STRETCHES, PARTITION_LAWS, Hindrance
from .kernels import BAD, BUDGET, SoluteParams, cell_props, release_run
from .result import ReleaseResult

D_MAX = 1e8  # solute diffusivity / gel diffusivity
STATE_ROW_EXTRA = 2  # a march state's row: n + 1 masses, then the step size, the advected mass
K_RANGE = (1e-6, 1e6)
MAX_PROFILES = 201
DEFAULT_RTOL = 1e-6
MAX_STEPS = 5_000_000


def _number(name: str, value: Any) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        x = math.nan
    if isinstance(value, bool) or not math.isfinite(x):
        raise ParameterError(name, value, "a finite number")
    return x


@dataclass(frozen=True)
class Solute:
    """A passive solute, dimensionless: ``diffusivity`` D0 in the pore fluid (units of the
    gel's R^2 / tau; 0 allowed: carried by the fluid alone), the ``hindrance`` law
    D = D0 f (with the convective sieving W and the steric partition K_s(phi)), the
    equilibrium ``partition`` K0 = c_pore / c_medium (the solute's affinity; the partition
    is K0 K_s(phi), K_s = 1 under the default ``hindrance.partition_law``), and the
    ``release_volume`` of a well-mixed medium at t = 0 (units of 4 pi R^3 / 3; None: a
    perfect sink).  Loading: uniform in the pore fluid at the start state."""

    diffusivity: float = 0.0
    hindrance: Hindrance = field(default_factory=Hindrance)
    partition: float = 1.0
    release_volume: float | None = None

    def __post_init__(self) -> None:
        d = _number("diffusivity", self.diffusivity)
        if not 0.0 <= d <= D_MAX:
            raise ParameterError("diffusivity", self.diffusivity,
                                 f"0 <= D0 <= {D_MAX:g} (units of the gel's R^2/tau)")
        object.__setattr__(self, "diffusivity", d)
        h = self.hindrance
        if isinstance(h, dict):
            h = Hindrance(**h)
        if not isinstance(h, Hindrance):
            raise ParameterError("hindrance", h, "a Hindrance or a dict of its fields")
        object.__setattr__(self, "hindrance", h)
        k = _number("partition", self.partition)
        if not K_RANGE[0] <= k <= K_RANGE[1]:
            raise ParameterError("partition", self.partition,
                                 f"{K_RANGE[0]:g} <= K <= {K_RANGE[1]:g} (> 0)")
        object.__setattr__(self, "partition", k)
        if self.release_volume is not None:
            v = _number("release_volume", self.release_volume)
            if not v > 0.0:
                raise ParameterError("release_volume", self.release_volume,
                                     "None (a perfect sink) or a volume > 0")
            object.__setattr__(self, "release_volume", v)

    @property
    def squeezed_is_expelled(self) -> bool:
        """True if the D0 = 0 twin's release is the expelled fraction exactly (no sieving
        of the fluid's solute, a perfect sink): its run is not needed, and a run of this
        solute can continue from a stored state (:class:`SoluteStart`)."""
        h = self.hindrance
        return not (h.convective and h.mesh_ratio > 0.0) and self.release_volume is None

    def diffusivity_at(self, phi: float | np.ndarray) -> float | np.ndarray:
        """The hindered diffusivity D0 f(phi) (isotropic state)."""
        return self.diffusivity * self.hindrance.factor(phi)

    def partition_at(self, phi: float | np.ndarray) -> float | np.ndarray:
        """The partition K0 K_s(phi) (c_pore / c_medium in equilibrium)."""
        return self.partition * self.hindrance.steric_partition(phi)

    def params(self, diffusivity: float | None = None) -> SoluteParams:
        """The kernels' constants (``diffusivity`` overrides D0: the D0 = 0 twin run)."""
        h = self.hindrance
        d0 = self.diffusivity if diffusivity is None else float(diffusivity)
        return SoluteParams(float(d0), int(h.code), float(h.mesh_ratio), float(h.fiber_ratio),
                            float(h.y), float(self.partition),
                            int(PARTITION_LAWS[h.partition_law]), int(h.convective),
                            int(MESH_STRETCHES[h.mesh_stretch]))

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form."""
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Solute:
        """Inverse of :meth:`to_dict`."""
        d = dict(d)
        d["hindrance"] = Hindrance(**d.get("hindrance", {}))
        return cls(**d)


@dataclass(frozen=True)
class SoluteStart:
    """Where a solute run continues a stored one: ``record`` (a :class:`ReleaseResult` of
    the same solute on mechanics that share the samples up to ``index``) kept its march's
    state at sample ``index`` (``record.state_index``, a step boundary).  The run then
    marches only the samples after it, exactly as the one run would (the same masses, step
    size and advected mass), and takes the record's outputs before it."""

    record: ReleaseResult
    index: int

    @classmethod
    def at(cls, record: ReleaseResult, t: float, ts: np.ndarray | None = None
           ) -> SoluteStart | None:
        """The start at time ``t`` (its output sample, :func:`_sample_at`) of a record that
        kept its state there, else None; with ``ts``, also None unless a run on those
        samples shares the record's up to the start."""
        k = _sample_at(np.asarray(record.t, dtype=float), t)
        if k is None or k == 0 or k not in _state_indices(record):
            return None
        start = cls(record, k)
        return None if ts is not None and not start.shares(ts) else start

    def shares(self, ts: np.ndarray) -> bool:
        """True if a run on samples ``ts`` has the record's samples up to the start."""
        k, t = self.index, self.record.t
        return 0 < k < len(ts) and t.size > k and np.array_equal(t[:k + 1], ts[:k + 1])

    def state(self) -> np.ndarray:
        """The march's state row at ``index``."""
        row = int(np.flatnonzero(_state_indices(self.record) == self.index)[0])
        return np.asarray(self.record.states[row], dtype=float)


def _state_indices(record: ReleaseResult) -> np.ndarray:
    """The samples whose march state a record kept (stored as floats in its npz)."""
    return np.asarray(record.state_index, dtype=float).astype(np.int64)


def _sample_at(ts: np.ndarray, t: float) -> int | None:
    """The first output sample at time ``t`` (to 1e-12 relative: a protocol boundary's time
    and its output may differ in the last bits), or None."""
    k = int(np.searchsorted(ts, t - 1e-12 * max(1.0, abs(t))))
    return k if k < ts.size and abs(ts[k] - t) <= 1e-12 * max(1.0, abs(t)) else None


def node_volumes(res: FullResult, cells: int | None = None) -> np.ndarray:
    """r_k^3 at the material nodes rho_k = k/n (k = 0..n, r_0 = 0) of every output.

    A Lagrangian run's cells are those nodes.  A moving-grid run (issue 12: its nodes move
    through the material) is resampled onto ``cells`` uniform dry cells (default its own
    count): within each of its cells the enclosed volume r^3 is linear in the dry volume
    rho^3 (slope 1 / (1 - phi)), so linear interpolation of r^3 in rho^3 is exact and
    conserves both volumes.
    """
    if res.grid not in ("lagrangian", "moving"):
        raise ParameterError("grid", res.grid, "'lagrangian' or 'moving' (the solute lives on "
                             "the dry coordinate's cells)")
    if res.grid == "lagrangian":
        n = res.coords.size
        dw = np.diff((np.arange(n + 1) / n) ** 3)
        s3 = np.zeros((res.t.size, n + 1))
        s3[:, 1:] = np.cumsum(dw[None, :] / (1.0 - res.phi), axis=1)
        return s3
    n = int(cells or res.phi.shape[1])
    dry = res.nodes**3
    own = np.zeros_like(dry)
    own[:, 1:] = np.cumsum(np.diff(dry, axis=1) / (1.0 - res.phi), axis=1)
    target = (np.arange(n + 1) / n) ** 3
    return np.stack([np.interp(target, d, v) for d, v in zip(dry, own, strict=True)])


def release(res: FullResult, solute: Solute, *, rtol: float = DEFAULT_RTOL,
            profiles: int = 51, max_steps: int = MAX_STEPS,
            twin: str = "exact", start: SoluteStart | None = None) -> ReleaseResult:
    """Integrate the solute through the mechanics samples of ``res`` (Lagrangian grid).

    The solute starts in equilibrium with one loading solution in the pore fluid of the
    first sample (c = K c_load, uniform in a uniform gel; loaded mass 1), enters and leaves
    with the fluid (upwind, sieved), diffuses with D0 f on grad(c / K) and leaves at the
    edge into the medium (kernels module).  ``squeezed_fraction`` is the release of the
    same mechanics with D0 = 0 (the twin; ``twin`` as in :func:`release_on_nodes`): what
    the fluid's motion alone releases,
    grid-independent (the released mass crossing the edge with the fluid,
    ``advected_fraction``, is not: diffusion moves solute to the edge cell on the grid's
    own scale).  The samples should
    be dense enough for the fluid's motion (``simulate(..., every=...)``); the time steps
    adapt within them to ``rtol``.  ``profiles`` concentration profiles are kept at evenly
    spread samples.  A protocol run's step boundaries (``res.boundary_states``) that are
    output times keep the march's state (``ReleaseResult.states``); ``start`` continues a
    stored run from one.
    """
    if not isinstance(solute, Solute):
        raise ParameterError("solute", solute, "a Solute")
    s3 = node_volumes(res)
    ts = np.asarray(res.t, dtype=float)
    marks = [k for k in (_sample_at(ts, st.t) for st in res.boundary_states
                         if not st.stopped) if k is not None]
    return release_on_nodes(ts, s3, solute,
                            radius=np.asarray(res.radius, dtype=float),
                            temperature=np.asarray(res.temperature, dtype=float),
                            rtol=rtol, profiles=profiles, max_steps=max_steps, twin=twin,
                            marks=marks, start=start)


def release_on_nodes(ts: np.ndarray, s3: np.ndarray, solute: Solute, *,
                     radius: np.ndarray | None = None, temperature: np.ndarray | None = None,
                     dry: np.ndarray | None = None, rtol: float = DEFAULT_RTOL,
                     profiles: int = 51, max_steps: int = MAX_STEPS,
                     twin: str = "exact", marks: Sequence[int] | np.ndarray = (),
                     start: SoluteStart | None = None) -> ReleaseResult:
    """:func:`release` on given mechanics: node volumes ``s3`` (len(ts), n + 1; r_k^3 at
    the material nodes, s3[:, 0] = 0) sampled at ``ts``, on dry cells ending at rho_k^3 =
    ``dry`` (n + 1 values from 0 to 1; default uniform in rho, rho_k = k / n).  Any
    mechanics that gives r(rho, t) serves: a full-solver run (:func:`release`) or the
    front model's (``solver.front.solute``).  ``twin``: "exact" (default) takes the
    expelled fraction where that is the twin's release exactly (no sieving, a perfect
    sink: a uniform pore concentration stays uniform under the fluid's motion alone, and
    the conservative upwind scheme keeps it so to round-off: the run twin agrees to
    ~1e-13, tests/test_solute_twin.py), else runs it; "run": always run the D0 = 0 twin
    (it costs a third to a half of the solute's time); "none": no twin
    (``squeezed_fraction`` empty).  ``marks``: sample indices whose march state the result
    keeps (``states``).  ``start``: continue a stored run (:class:`SoluteStart`; its samples
    up to the start must be these): only where the twin needs no run (it has no state)."""
    if not isinstance(solute, Solute):
        raise ParameterError("solute", solute, "a Solute")
    if not (isinstance(rtol, (int, float)) and 1e-12 <= rtol <= 1e-2):
        raise ParameterError("rtol", rtol, "1e-12 <= rtol <= 1e-2")
    if twin not in ("run", "exact", "none"):
        raise ParameterError("twin", twin, "'run', 'exact' or 'none'")
    started = time.perf_counter()
    ts = np.ascontiguousarray(ts, dtype=float)
    s3 = np.ascontiguousarray(s3, dtype=float)
    n = s3.shape[1] - 1
    dw = np.diff((np.arange(n + 1) / n) ** 3 if dry is None else np.asarray(dry, dtype=float))
    a3 = s3[:, n]
    if radius is None:
        radius = np.cbrt(a3)
    if temperature is None:
        temperature = np.full(ts.size, np.nan)
    w0 = a3[0] - 1.0
    vol = solute.release_volume
    if vol is not None and vol <= a3[0]:
        raise ParameterError("release_volume", vol, f"> {a3[0]:.6g} (the swollen bead's "
                             "volume, units of 4 pi R^3/3): the medium must hold the bead")
    par = solute.params()
    phi0c, lam0, k0c, w0c = (np.zeros(n) for _ in range(4))
    rho = np.cbrt(np.concatenate(([0.0], np.cumsum(dw))))
    cell_props(np.ascontiguousarray(s3[0]), dw, rho, par, phi0c, lam0, k0c, w0c)
    m = np.zeros(n + 1)
    m[:n] = (s3[0, 1:] - s3[0, :-1] - dw) * k0c
    m[:n] /= m[:n].sum()
    m_start = m.copy()
    exact_twin = solute.squeezed_is_expelled
    k0 = 0 if start is None else _check_start(start, ts, n, solute.diffusivity > 0.0
                                              and twin == "run" or not exact_twin)
    marks = np.unique(np.asarray(marks, dtype=np.int64))
    marks = marks[(marks >= 0) & (marks < ts.size)]
    mark_idx = np.full(ts.size, -1, dtype=np.int64)
    mark_idx[marks] = np.arange(marks.size)
    out_mark = np.zeros((marks.size, n + 1 + STATE_ROW_EXTRA))
    picks, kept = _profile_picks(ts, k0, start, profiles)
    prof_idx = np.full(ts.size, -1, dtype=np.int64)
    prof_idx[picks] = np.arange(picks.size)
    out_prof = np.zeros((picks.size, n))
    rel = np.zeros(ts.size)
    adv = np.zeros(ts.size)
    h = solute.hindrance
    counters = np.zeros(2, dtype=np.int64)
    gel = np.zeros(ts.size)
    vmed = -1.0 if vol is None else float(vol)
    carry = np.zeros(2)
    if start is not None:  # the stored run's state at the start, its outputs before it
        row = start.state()
        m[:] = row[:n + 1]
        carry[:] = row[n + 1:]
        for out, name in ((rel, "released_fraction"), (adv, "advected_fraction"),
                          (gel, "in_gel_fraction")):
            out[:k0] = getattr(start.record, name)[:k0]
        mark_idx[:k0] = -1
    series = np.zeros((3, ts.size - k0))  # released, advected, in the gel
    _check(release_run(ts[k0:], s3[k0:], dw, vmed, par, m, series, out_prof, prof_idx[k0:],
                       float(rtol), int(max_steps), counters, carry, mark_idx[k0:], out_mark),
           max_steps, counters)
    rel[k0:], adv[k0:], gel[k0:] = series
    state_index, states = marks, out_mark
    if start is not None:  # the stored run's states before the start, then this run's
        old = _state_indices(start.record)
        before = old < k0
        state_index = np.concatenate([old[before], marks[marks >= k0]])
        states = np.concatenate([np.asarray(start.record.states)[before],
                                 out_mark[marks >= k0]])
    balance = float(np.max(np.abs(gel + rel - 1.0)))
    if solute.diffusivity > 0.0 and twin == "none":
        squeezed = np.zeros(0)
    elif solute.diffusivity > 0.0 and twin == "exact" and exact_twin:
        squeezed = np.maximum((a3[0] - a3) / w0, 0.0)
    elif solute.diffusivity > 0.0:  # the D0 = 0 twin: the release of the fluid's motion alone
        twin_series = np.zeros((3, ts.size))
        twin_counters = np.zeros(2, dtype=np.int64)
        _check(release_run(ts, s3, dw, vmed, solute.params(0.0), m_start, twin_series,
                           np.zeros_like(out_prof), prof_idx, float(rtol), int(max_steps),
                           twin_counters, np.zeros(2), np.full(ts.size, -1, dtype=np.int64),
                           np.zeros((0, n + 1 + STATE_ROW_EXTRA))), max_steps, twin_counters)
        squeezed, twin_gel = twin_series[0], twin_series[2]
        balance = max(balance, float(np.max(np.abs(twin_gel + squeezed - 1.0))))
    else:
        squeezed = rel.copy()
    if vol is None:
        conc = np.zeros(ts.size)
    else:
        conc = rel / (vol + (a3[0] - a3))
    phi0 = 1.0 - 1.0 / float(a3[0])  # the loaded bead's mean porosity (solid volume 1)
    d_eff = float(solute.diffusivity * h.factor(phi0))
    radii = np.cbrt(0.5 * (s3[picks, 1:] + s3[picks, :-1]))
    diag = {"steps": int(counters[0]), "rejected": int(counters[1]), "rtol": rtol,
            "samples": int(ts.size), "n": n, "solute": solute.to_dict(),
            "wall_time": time.perf_counter() - started, "from_sample": int(k0)}
    return ReleaseResult(
        t=ts.copy(), radius=np.asarray(radius, dtype=float).copy(),
        released_fraction=rel, advected_fraction=adv,
        expelled_fraction=(a3[0] - a3) / w0, in_gel_fraction=gel,
        medium_concentration=conc, temperature=np.asarray(temperature, dtype=float).copy(),
        profile_t=ts[picks].copy(), profile_radii=radii,
        profiles=out_prof * w0 if start is None else np.concatenate(
            [start.record.profiles[kept], out_prof[kept.size:] * w0]),
        mass_balance_error=balance, effective_diffusivity=d_eff, diagnostics=diag,
        squeezed_fraction=squeezed, start_partition=float(solute.partition_at(phi0)),
        state_index=state_index.astype(float), states=states)


def _check_start(start: SoluteStart, ts: np.ndarray, n: int, twin_runs: bool) -> int:
    """The sample index a run continues ``start`` from (ParameterError if it cannot)."""
    k0 = int(start.index)
    if twin_runs:
        raise ParameterError("start", "a stored solute run", "no start where the D0 = 0 twin "
                             "is run (sieving, or a finite medium): it keeps no state")
    if not start.shares(ts):
        raise ParameterError("start", k0, "a sample both runs share (the same outputs up "
                             "to it)")
    if start.state().size != n + 1 + STATE_ROW_EXTRA:
        raise ParameterError("start", k0, f"a state on {n} cells")
    return k0


def _profile_picks(ts: np.ndarray, k0: int, start: SoluteStart | None, profiles: int
                   ) -> tuple[np.ndarray, np.ndarray]:
    """The samples whose profiles are kept, and which of a start's stored profiles (those
    before the start) are taken: ``profiles`` evenly spread over the run, or over what is
    left after the start's."""
    k_prof = max(2, min(int(profiles), MAX_PROFILES, ts.size))
    if start is None:
        kept = np.zeros(0, dtype=np.int64)
        picks = np.unique(np.round(np.linspace(0, ts.size - 1, k_prof)).astype(np.int64))
        return picks, kept
    kept = np.flatnonzero(start.record.profile_t < ts[k0])
    before = np.searchsorted(ts[:k0], start.record.profile_t[kept])
    rest = max(2, min(k_prof - kept.size, ts.size - k0))
    after = np.unique(np.round(np.linspace(k0, ts.size - 1, rest)).astype(np.int64))
    return np.concatenate([before, after]).astype(np.int64), kept


def _check(status: int, max_steps: int, counters: np.ndarray) -> None:
    if status == BUDGET:
        raise SolverError(f"solute transport: step budget exhausted ({max_steps} steps)",
                          {"steps": int(counters[0])})
    if status == BAD:
        raise SolverError("solute transport: unphysical state (a cell without fluid or a "
                          "non-finite error)", {"steps": int(counters[0])})


def simulate_release(gel: Any, t_start: float, solute: Solute, *, t_end: float | None = None,
                     until: float | None = None,
                     protocol: Sequence[tuple[float, float]] | None = None,
                     samples: int = 2000, solute_rtol: float = DEFAULT_RTOL,
                     profiles: int = 51, **options: Any) -> tuple[FullResult, ReleaseResult]:
    """The mechanical run (Lagrangian grid, ``samples`` outputs; ``options`` are
    ``simulate``'s, default n = 200 cells, rtol 1e-6, ell = 0) and the solute on it."""
    from ..full import simulate

    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or not (
            10 <= samples <= 100_000):
        raise ParameterError("samples", samples, "an integer 10-100000")
    if protocol is not None:
        total = float(sum(float(d) for d, _ in protocol))
    elif until is not None:
        total = _number("until", until)
    else:
        total = math.nan
    every = total / samples if math.isfinite(total) and total > 0 else None
    options = {"grid": "lagrangian", "n": 200, "rtol": 1e-6, **options}
    res = simulate(gel, t_start, t_end, until=until, protocol=protocol, every=every, **options)
    return res, release(res, solute, rtol=solute_rtol, profiles=profiles)
