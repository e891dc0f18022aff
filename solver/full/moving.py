"""The moving Lagrangian grid: non-uniform dry-coordinate cells, adapted by rezoning.

The cells are those of the Lagrangian grid (``lagrangian.py``: nodes rho_k carry the
solid, cell c holds the dry volume rho_{c+1}^3 - rho_c^3, J_c = (r_{c+1}^3 - r_c^3) / w_c)
at arbitrary node positions 0 = rho_0 < ... < rho_n = 1; the kernels are the Lagrangian
grid's, which take every width from the geometry rows, so equal widths reproduce the
uniform grid bit for bit.  The Korteweg pressure is the same finite-volume Laplacian
(docs/interfacial.md, sec. 4) with non-uniform faces.

Adaptation (docs/interfacial.md, sec. 11).  Every few accepted steps the rezoner builds the
target mesh that equidistributes the monitor M = 1/h*, with the target spacing

    h*(rho) = min(h_bulk, delta / |d ln J / d rho|),   h*(1) <= ell / edge_cells,

limited to grow by at most ``grading`` per unit distance (h* Lipschitz, so neighbouring
cells differ by at most that fraction).  Each interface then gets about Delta ln J / delta
cells whatever its width (the steep side shrinks like Omega^-1/2 at large Omega), the edge,
where the front nucleates, stays resolved at the ell scale, and the rest of the cells go
to the bulk.  When a node is more than ``tolerance`` of its cell off its target, the state
is remapped: in the dry coordinate the solid is exact under any remap, and the cumulative
fluid volume W(s) = r^3 - s (s = rho^3) is interpolated monotonically (PCHIP, strictly
increasing since J > 1), so every new cell has 0 < phi < 1 and the total volume, a = r_n,
is unchanged.  The one-step Rosenbrock integrator then restarts with a fresh Jacobian.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from scipy.interpolate import PchipInterpolator

from ..errors import ParameterError


@dataclass(frozen=True)
class MeshOptions:
    """Options of the moving grid (all dimensionless; defaults from the convergence study,
    ``benchmarks/moving_mesh.py``).

    resolution: largest change of ln J per cell in an interface (delta).
    bulk: largest cell width relative to a uniform grid of the same size (h_bulk =
        bulk / n); the cells an interface does not need go to the bulk.
    edge_cells: cells per interfacial length at the edge (h*(1) = ell / edge_cells).
    grading: largest growth of the target spacing per unit distance (neighbour ratio).
    check_every: accepted steps between mesh checks.
    tolerance: remap when a node is further than this fraction of its cell from its target.
    rezone: False keeps the initial mesh (a fixed non-uniform grid).
    nodes: the initial node positions (n + 1 values from 0 to 1); None adapts them to the
        initial state.
    """

    resolution: float = 0.1
    bulk: float = 2.0
    edge_cells: float = 4.0
    grading: float = 0.1
    check_every: int = 4
    tolerance: float = 0.3
    rezone: bool = True
    nodes: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        for name, lo, hi in (("resolution", 1e-3, 2.0), ("bulk", 1.0, 100.0),
                             ("edge_cells", 0.1, 100.0), ("grading", 1e-3, 1.0),
                             ("tolerance", 1e-3, 10.0)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not (
                    math.isfinite(v) and lo <= v <= hi):
                raise ParameterError(f"mesh.{name}", v, f"{lo:g} to {hi:g}")
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


def geometry_from_nodes(nodes: np.ndarray) -> np.ndarray:
    """Lagrangian geometry rows for arbitrary nodes: nodes rho_k, cell volume midpoints,
    dry shell volumes (the same arithmetic as ``lagrangian.geometry`` for k/n)."""
    nodes = np.asarray(nodes, dtype=float)
    n = nodes.size - 1
    geo = np.zeros((4, n + 1))
    geo[0] = nodes
    geo[1, :n] = np.cbrt(0.5 * (nodes[:-1] ** 3 + nodes[1:] ** 3))
    geo[2, :n] = np.diff(nodes**3)
    return geo


def set_nodes(geo: np.ndarray, nodes: np.ndarray) -> None:
    """Overwrite the geometry rows in place (the integrator's arrays keep their identity)."""
    geo[:, :] = geometry_from_nodes(nodes)


def state_from_profile(radius: float, phi: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """Node radii from cell porosities on the given nodes: r_k^3 = sum_{c<k} w_c/(1 - phi_c)."""
    w = np.diff(np.asarray(nodes, dtype=float) ** 3)
    return np.cbrt(np.cumsum(w / (1.0 - np.asarray(phi, dtype=float))))


def remap(y: np.ndarray, old: np.ndarray, new: np.ndarray) -> np.ndarray:
    """Node radii on the ``new`` nodes from state ``y`` on ``old``: the cumulative fluid
    volume W(s) = r^3 - s, s = rho^3, interpolated by PCHIP (monotone, so J > 1 in every new
    cell); W(1), the radius and the solid are exact."""
    s_old = old**3
    w_old = np.concatenate([[0.0], y**3]) - s_old
    w_old[0] = 0.0
    s_new = new**3
    w_new = PchipInterpolator(s_old, w_old)(s_new[1:])
    w_new[-1] = w_old[-1]
    out = np.cbrt(w_new + s_new[1:])
    out[-1] = y[-1]
    return out


def log_jac(y: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """ln J of every cell."""
    r3 = np.concatenate([[0.0], y**3])
    return np.log(np.diff(r3) / np.diff(nodes**3))


def target_nodes(y: np.ndarray, nodes: np.ndarray, opts: MeshOptions, ell: float) -> np.ndarray:
    """Nodes that equidistribute the monitor of the state y (module doc)."""
    n = nodes.size - 1
    centre = 0.5 * (nodes[:-1] + nodes[1:])
    lj = log_jac(y, nodes)
    # |d ln J / d rho| at the interior nodes, then at the cell centres (max of the two faces)
    grad = np.abs(np.diff(lj) / np.diff(centre))
    g_cell = np.zeros(n)
    g_cell[:-1] = grad
    g_cell[1:] = np.maximum(g_cell[1:], grad)
    h_bulk = opts.bulk / n
    h = np.minimum(h_bulk, opts.resolution / np.maximum(g_cell, 1e-300))
    if ell > 0.0:
        h_edge = ell / opts.edge_cells
        h = np.minimum(h, h_edge + opts.grading * (1.0 - centre))
    _lipschitz(centre, h, opts.grading)
    # density 1/h between the samples (piecewise linear in 1/h), equidistributed over n cells
    xs = np.concatenate([[0.0], centre, [1.0]])
    dens = 1.0 / np.concatenate([[h[0]], h, [h[-1]]])
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (dens[1:] + dens[:-1]) * np.diff(xs))])
    out = np.interp(np.linspace(0.0, cum[-1], n + 1), cum, xs)
    out[0], out[-1] = 0.0, 1.0
    return out


def _lipschitz(x: np.ndarray, h: np.ndarray, slope: float) -> None:
    """In place: the largest h' <= h with |h'(x_i) - h'(x_j)| <= slope |x_i - x_j|."""
    for i in range(1, h.size):
        h[i] = min(h[i], h[i - 1] + slope * (x[i] - x[i - 1]))
    for i in range(h.size - 2, -1, -1):
        h[i] = min(h[i], h[i + 1] + slope * (x[i + 1] - x[i]))


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


class Rezoner:
    """Checks the mesh every ``check_every`` accepted steps and remaps when it is off."""

    def __init__(self, opts: MeshOptions, ell: float) -> None:
        self.opts, self.ell = opts, ell
        self.every = opts.check_every if opts.rezone else 0
        self.checks = 0
        self.remaps = 0

    def __call__(self, y: np.ndarray, geo: np.ndarray) -> bool:
        """Remap y (in place) and the geometry rows when the mesh is off its target."""
        self.checks += 1
        nodes = geo[0].copy()
        new = target_nodes(y, nodes, self.opts, self.ell)
        width = np.diff(nodes)
        cell = np.minimum(np.concatenate([[width[0]], width]), np.concatenate([width, [width[-1]]]))
        if np.max(np.abs(new - nodes) / cell) <= self.opts.tolerance:
            return False
        y[:] = remap(y, nodes, new)
        set_nodes(geo, new)
        self.remaps += 1
        return True
