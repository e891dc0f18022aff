"""A batch of drug-loaded beads releasing into one shared, well-mixed medium (issue 26): the
planner's side.

The coupled solve (every size class's solute and the medium's drug, one TR-BDF2 march) is
physics and dimensionless, so it lives in the solver: ``solver.solute.medium``, reached
through its public :func:`coupled_release` and its result :class:`MediumRelease` (times in
tau of the reference bead, volumes in units of the batch's dry volume).  The planner turns
a dose request into that solve and back: ``batch_drug`` (a medium in mL for a bead count ->
v0, the classes' rho and load shares, seconds via tau) and ``batch_drug_protocol`` (each
size node's own mechanics of a protocol) call it by these names.
"""

from __future__ import annotations

from solver.solute import MediumRelease, coupled_release

__all__ = ["MediumRelease", "coupled_release"]
