"""A moving-grid state part way into a jump, for the tests that probe its Jacobian."""

from __future__ import annotations

import numpy as np

from solver.equilibrium import equilibrium
from solver.full import moving
from solver.full.integrate import Segment, Stats, StepControl, Workspace, run_implicit
from solver.full.kernels import KernelParams
from solver.full.system import MOVING
from solver.gel import Gel


def running_state(gel: Gel, n: int, ell: float, until: float, rtol: float, atol: float,
                  perm: tuple[int, float] | None = None, t_start: float = 302.0,
                  t_end: float = 308.0) -> tuple[Workspace, np.ndarray, KernelParams]:
    """(workspace, state, kernel parameters) of ``gel`` on ``n`` moving cells at ``until``
    after the jump t_start -> t_end (``perm``: a permeability law (code, beta) instead of
    the gel's), the mesh checked once more at the end (so its node velocities are set)."""
    eq = equilibrium(gel, t_start, "swollen")
    opts = moving.MeshOptions()
    nodes = moving.initial_nodes(eq.stretch, lambda x: np.full(x.size - 1, eq.porosity), n,
                                 opts, ell)
    ws = Workspace(MOVING, moving.geometry(nodes), interfacial=True)
    code, beta = perm or (gel.permeability.code, gel.permeability.beta)
    par = KernelParams(gel.omega, gel.chi0(t_end), gel.chi1(t_end), code, beta, ell**2)
    y0 = moving.state(moving.state_from_profile(eq.stretch, np.full(n, eq.porosity), nodes))
    rz = moving.Rezoner(opts, ell)
    y = run_implicit(ws, y0, [Segment(0.0, until, t_end, par)], np.array([until]),
                     lambda t, y: None, StepControl(rtol, atol, 100000), None,
                     Stats(), rezoner=rz)
    rz(y, ws.geo)
    return ws, y, par
