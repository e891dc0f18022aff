"""The moving Lagrangian grid: non-uniform dry-coordinate cells that follow the interface.

The cells are those of the Lagrangian grid (``lagrangian.py``: nodes rho_k carry the
solid, cell c holds the dry volume rho_{c+1}^3 - rho_c^3, J_c = (r_{c+1}^3 - r_c^3) / w_c)
at arbitrary node positions 0 = rho_0 < ... < rho_n = 1; the kernels are the Lagrangian
grid's, which take every width from the geometry rows, so equal widths reproduce the
uniform grid bit for bit.  The Korteweg pressure is the same finite-volume Laplacian
(docs/interfacial.md, sec. 4) with non-uniform faces.

Adaptation (docs/moving_mesh.md).  Every few accepted steps the rezoner builds the
target mesh that equidistributes the monitor M = 1/h*, with the target spacing

    h*(rho) = min(h_bulk, delta / |d ln J / d rho|),   h*(1) <= ell / edge_cells,
    h* >= ell / finest,

limited to grow by at most ``grading`` per unit distance (h* Lipschitz, so neighbouring
cells differ by at most that fraction), iterated twice towards its fixed point so it does
not depend on the current mesh. Between checks the nodes move at the target's velocity
(``ale.py``: the ALE term keeps the unknowns the radii of the moving nodes; its mean over
the last interval, extrapolated by the change since the one before), used only while two
successive estimates agree in cells per unit time. Each interface then gets about Delta ln J
/ delta cells whatever its width (the steep side shrinks like Omega^-1/2 at large Omega),
the edge, where the front nucleates, stays resolved at the ell scale, and the rest of the
cells go to the bulk. When a node is more than ``tolerance`` of its cell off its target, the
state is remapped: in the dry coordinate the solid is exact under any remap, and the
cumulative fluid volume W(s) = r^3 - s (s = rho^3) is interpolated monotonically (PCHIP,
strictly increasing since J > 1), so every new cell has 0 < phi < 1 and the total volume, a
= r_n, is unchanged. After every check the one-step Rosenbrock integrator restarts with a
fresh Jacobian.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from ..errors import ParameterError
from . import ale, rezone


@dataclass(frozen=True)
class MeshOptions:
    """Options of the moving grid (all dimensionless; defaults from the convergence study,
    ``benchmarks/moving_mesh.py``).

    resolution: largest change of ln J per cell in an interface (delta).
    bulk: largest cell width relative to a uniform grid of the same size (h_bulk =
        bulk / n); the cells an interface does not need go to the bulk.
    edge_cells: cells per interfacial length at the edge (h*(1) = ell / edge_cells).
    finest: most cells per interfacial length anywhere (h* >= ell / finest): structures
        much finer than ell (a stiff gel's spinodal burst at the edge) are not chased.
    grading: largest growth of the target spacing per unit distance (neighbour ratio).
    check_every: accepted steps between mesh checks.
    tolerance: remap when a node is further than this fraction of its cell from its target
        (1.0: at 0.3 the 200-cell HHT run at ell = 3e-5 remapped at 2,182 of 2,696 checks, a
        limit cycle of the target that cost 3x the steps; docs/moving_mesh.md sec. 7.2).
    rezone: False keeps the initial mesh (a fixed non-uniform grid).
    nodes: the initial node positions (n + 1 values from 0 to 1); None adapts them to the
        initial state.
    front: move the band around a thin front with the front's own motion
        (docs/moving_mesh.md sec. 7.2); False: the equidistributed target's motion only.
    land: every output time ends a step (the planner's fluid runs: landing also caps the
        steps, which their bounds were measured with); False reads outputs between steps
        from RODASP's continuous output (a drug run's dense outputs; docs/moving_mesh.md
        sec. 8).
    """

    resolution: float = 0.1
    bulk: float = 4.0
    edge_cells: float = 4.0
    finest: float = 50.0
    grading: float = 0.1
    check_every: int = 2
    tolerance: float = 1.0
    rezone: bool = True
    nodes: tuple[float, ...] | None = None
    front: bool = True
    land: bool = True

    def __post_init__(self) -> None:
        for name, lo, hi in (("resolution", 1e-3, 2.0), ("bulk", 1.0, 100.0),
                             ("edge_cells", 0.1, 100.0), ("finest", 1.0, 1e4),
                             ("grading", 1e-3, 1.0),
                             ("tolerance", 1e-3, 10.0)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not (
                    math.isfinite(v) and lo <= v <= hi):
                raise ParameterError(f"mesh.{name}", v, f"{lo:g} to {hi:g}")
        for name in ("front", "land"):
            if not isinstance(getattr(self, name), bool):
                raise ParameterError(f"mesh.{name}", getattr(self, name), "True or False")
        ce = self.check_every
        if isinstance(ce, bool) or not isinstance(ce, (int, np.integer)) or not 1 <= ce <= 10_000:
            raise ParameterError("mesh.check_every", ce, "an integer 1-10000")
        if self.nodes is not None:
            x = np.asarray(self.nodes, dtype=float)
            if x.ndim != 1 or x.size < 11 or x[0] != 0.0 or x[-1] != 1.0 or not np.all(
                    np.diff(x) > 0.0):
                raise ParameterError("mesh.nodes", "nodes",
                                     "n + 1 >= 11 increasing dry radii from 0 to 1")
            object.__setattr__(self, "nodes", tuple(float(v) for v in x))

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form (the node list summarised by its size)."""
        out = asdict(self)
        out["nodes"] = None if self.nodes is None else len(self.nodes)
        return out


def geometry(nodes: np.ndarray) -> np.ndarray:
    """The moving grid's geometry rows (``ale.py``) for a mesh at rest at ``nodes``."""
    return ale.geometry_rows(np.asarray(nodes, dtype=float))


def state(radii: np.ndarray, t: float = 0.0) -> np.ndarray:
    """The moving grid's state: the node radii and the time."""
    return np.append(radii, t)


def state_from_profile(radius: float, phi: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """Node radii from cell porosities on the given nodes: r_k^3 = sum_{c<k} w_c/(1 - phi_c)."""
    w = np.diff(np.asarray(nodes, dtype=float) ** 3)
    return np.cbrt(np.cumsum(w / (1.0 - np.asarray(phi, dtype=float))))


def remap(y: np.ndarray, old: np.ndarray, new: np.ndarray) -> np.ndarray:
    """Node radii on the ``new`` nodes from state ``y`` on ``old``: the cumulative fluid
    volume W(s) = r^3 - s, s = rho^3, interpolated by PCHIP (monotone, so J > 1 in every new
    cell); W(1), the radius and the solid are exact."""
    out = np.empty_like(y)
    rezone.remap(y, old, new, out)
    return out


def target_nodes(y: np.ndarray, nodes: np.ndarray, opts: MeshOptions, ell: float) -> np.ndarray:
    """Nodes that equidistribute the monitor of the state y (module doc)."""
    n = nodes.size - 1
    out = np.empty(n + 1)
    h_edge = ell / opts.edge_cells if ell > 0.0 else 0.0
    h_min = ell / opts.finest if ell > 0.0 else 0.0
    rezone.target_nodes(y, nodes, opts.resolution, opts.bulk / n, h_edge, h_min, opts.grading,
                        out)
    return out


def initial_nodes(radius: float, phi_of: Any, n: int, opts: MeshOptions,
                  ell: float) -> np.ndarray:
    """The first mesh: ``opts.nodes``, or the target mesh of the initial state, iterated
    (``phi_of(nodes)`` gives the initial cell porosities on given nodes)."""
    if opts.nodes is not None:
        nodes = np.asarray(opts.nodes, dtype=float)
        if nodes.size != n + 1:
            raise ParameterError("mesh.nodes", nodes.size - 1, f"n = {n} cells")
        return nodes
    nodes = np.arange(n + 1) / n
    for _ in range(4):
        y = state_from_profile(radius, phi_of(nodes), nodes)
        nodes = target_nodes(y, nodes, opts, ell)
    return nodes


def _agree(raw: np.ndarray, prev: np.ndarray, nodes: np.ndarray, agreement: float) -> bool:
    """Whether two successive estimates of the target's node velocities agree: their largest
    difference is at most ``agreement`` of the largest velocity, both measured in cells per
    unit time (each node's velocity over its smaller adjacent cell).

    In cells, not in the dry coordinate: a bulk node's target wanders by a thousandth of its
    (large) cell between checks, which in absolute terms is as fast as the front's nodes in
    their cells 1e-3 times smaller; compared absolutely, that noise vetoed the front's
    velocity every other check (Omega = 300, ell = 1e-4: three remaps in four checks).
    """
    h = np.diff(nodes)
    cell = np.empty(nodes.size)
    cell[1:-1] = np.minimum(h[:-1], h[1:])
    cell[0], cell[-1] = h[0], h[-1]
    speed = np.abs(raw) / cell
    big = max(speed.max(), 1e-300)
    return bool((np.abs(raw - prev) / cell).max() <= agreement * big)


class Rezoner:
    """Every ``check_every`` accepted steps: the target mesh of the current state, the
    node velocity that follows it (the change of the target since the last check), and a
    remap onto it when the nodes are more than ``tolerance`` of a cell off."""

    HORIZON = 4.0  # check intervals over which no cell may shrink below half its width
    ITERATIONS = 2  # fixed-point iterations of the target mesh
    AGREEMENT = 0.5  # largest change of the target's velocity between checks (in cells, _agree)

    def __init__(self, opts: MeshOptions, ell: float) -> None:
        self.opts, self.ell = opts, ell
        self.every = opts.check_every if opts.rezone else 0
        self.land = opts.land
        self.checks = 0
        self.remaps = 0
        self._last: tuple[float, np.ndarray] | None = None
        self._raw: tuple[np.ndarray, float] | None = None
        self._hist: np.ndarray | None = None  # the compiled check's history (rezone.mesh_check)
        self._scal = np.zeros(rezone.SCAL_SIZE)

    def reset(self, y: np.ndarray, geo: np.ndarray) -> None:
        """Stop the nodes where they are and forget the target's history (at a protocol
        step, where the interface's motion changes abruptly)."""
        n = geo.shape[1] - 1
        t = float(y[n])
        ale.refresh(geo, t)
        ale.set_mesh(geo, geo[0].copy(), np.zeros(n + 1), t)
        self._last = None
        self._raw = None
        self._scal[:] = 0.0

    def __call__(self, y: np.ndarray, geo: np.ndarray) -> bool:
        """Update the mesh motion (and remap y in place when the mesh is off); True when
        the right-hand side changed (the integrator restarts).  One compiled call
        (``rezone.mesh_check``: the target mesh, the remap, the node velocity), the same
        arithmetic as :meth:`check_python`."""
        self.checks += 1
        n = geo.shape[1] - 1
        t = float(y[n])
        ale.refresh(geo, t)
        if self._hist is None or self._hist.shape[1] != n + 1:
            self._hist = np.zeros((2, n + 1))
            self._scal[:] = 0.0
        o = self.opts
        mesh = np.empty(n + 1)
        velocity = np.empty(n + 1)
        accel = np.empty(n + 1)
        jerk = np.empty(n + 1)
        params = rezone.mesh_params(
            o.resolution, o.bulk / n, self.ell / o.edge_cells if self.ell > 0.0 else 0.0,
            self.ell / o.finest if self.ell > 0.0 else 0.0, o.grading, self.ITERATIONS,
            o.tolerance, self.AGREEMENT, self.HORIZON, self.ell if o.front else 0.0)
        off = rezone.mesh_check(y, geo[0].copy(), params, self._hist, self._scal, mesh,
                                velocity, accel, jerk)
        if off:
            self.remaps += 1
        ale.set_mesh(geo, mesh, velocity, t, (accel, jerk, float(self._scal[rezone.S_SPAN])))
        return True

    def check_python(self, y: np.ndarray, geo: np.ndarray) -> bool:
        """:meth:`__call__` step by step in Python (the reference the compiled check is
        tested against; it keeps its own history)."""
        self.checks += 1
        n = geo.shape[1] - 1
        t = float(y[n])
        ale.refresh(geo, t)
        nodes = geo[0].copy()
        new = target_nodes(y[:n], nodes, self.opts, self.ell)
        for _ in range(self.ITERATIONS):  # towards the fixed point, independent of the mesh
            new = target_nodes(remap(y[:n], nodes, new), new, self.opts, self.ell)
        velocity = np.zeros(n + 1)
        accel = np.zeros(n + 1)
        jerk = np.zeros(n + 1)
        off = rezone.offset(nodes, new) > self.opts.tolerance
        before = y[:n].copy()
        if off:
            y[:n] = remap(y[:n], nodes, new)
            self.remaps += 1
        base = new if off else nodes
        last = None if self._last is None else self._last[0]
        if last is not None and t > last:
            dt = t - last
            raw = (new - self._last[1]) / dt
            # follow the target only while it translates steadily: two successive estimates
            # agree (a nucleating front makes the target jump, not move)
            prev = self._raw
            self._raw = (raw, dt)
            if prev is not None and _agree(raw, prev[0], new, self.AGREEMENT):
                # the target's mean velocity over the next interval (as long as the last),
                # extrapolated linearly from the last two intervals' means
                velocity = raw + (raw - prev[0]) * (2.0 * dt) / (dt + prev[1])
        # the band around the front moves with the front (sec. 7.2)
        rezone.follow_front(before, y[:n], nodes, base, t,
                            self.ell if self.opts.front else 0.0, rezone.FRONT_AGREEMENT,
                            velocity, accel, jerk, self._scal)
        span = 0.0
        if last is not None and t > last:
            span = rezone.SPAN * (t - last)
            rezone.shrink(velocity, accel, jerk, base, self.HORIZON * (t - last), span)
        self._last = (t, new)
        if off:
            nodes = new
        ale.set_mesh(geo, nodes, velocity, t, (accel, jerk, span))
        return True
