"""The step answer under slow heating: the delayed-jump estimate (docs/heating.md).

Measured with the full solver (benchmarks/heating.py), a bead heated by a ramp or a bath
hardly releases until the temperature reaches the coexistence onset of its start state,
T_c(a0) (the lowest T at which the start stretch a0 lies in the two-phase region, eq.
Coexistence: the edge can then form a front), and from there it releases about as after a
jump.  So a dose under a program is estimated as

    t(f) = t_c + t_jump(f),   t_c = first time T(t) >= T_c(a0),

with t_jump(f) the step answer (the front model's, in milliseconds, or the full solver's).
It ignores the smooth shrinking below T_c (which the full solver shows for slow heating:
early small doses) and the slower release while T is still below T_end (a bath's tail):
its error, measured against the full solver, is the table of docs/heating.md.
"""

from __future__ import annotations

import numpy as np

from ..errors import NotApplicableError
from ..gel import Gel
from ..heating import Program
from ..phase import in_coexistence

ONSET_STEP = 0.01  # K: the scan for T_c, then bisection to 1e-6 K


def onset_temperature(gel: Gel, stretch: float, t_from: float, t_to: float) -> float | None:
    """T_c: the lowest temperature in [t_from, t_to] at which ``stretch`` is in the two-phase
    region (eq. Coexistence), or None if it never is."""
    temps = np.arange(t_from, t_to + ONSET_STEP, ONSET_STEP)
    temps[-1] = min(temps[-1], t_to)
    prev = t_from
    for temp in temps:
        if in_coexistence(gel, float(temp), stretch):
            lo, hi = prev, float(temp)
            for _ in range(20):
                mid = 0.5 * (lo + hi)
                lo, hi = (lo, mid) if in_coexistence(gel, mid, stretch) else (mid, hi)
            return hi
        prev = float(temp)
    return None


def onset_time(program: Program, t_start: float, t_onset: float) -> float:
    """First time the program's T(t) (from ``t_start``) reaches ``t_onset`` (heating), on
    its pieces exactly (a lag piece by its logarithm, a linear one by its slope)."""
    for piece in program.pieces(t_start):
        t0, t1 = piece.temperature(piece.t0), piece.temperature(piece.t1)
        if t0 >= t_onset:
            return piece.t0
        if t1 >= t_onset:
            if piece.kind == 0:
                return piece.t0 + (t_onset - t0) / piece.p
            return piece.t0 + piece.p * float(np.log((piece.q - t0) / (piece.q - t_onset)))
    end = program.pieces(t_start)
    if end and end[-1].q > t_onset and end[-1].kind == 1:  # a bath held: its limit
        piece = end[-1]
        t0 = piece.temperature(piece.t0)
        return piece.t0 + piece.p * float(np.log((piece.q - t0) / (piece.q - t_onset)))
    raise NotApplicableError(f"the program never reaches the onset temperature {t_onset:.4g} K")
