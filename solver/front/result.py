"""The front model's result: sampled series plus the exact curve behind them for fast queries."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import ParameterError
from .evolve import FrontCurve


def fraction_radius(a0: float, fraction: np.ndarray | float) -> np.ndarray | float:
    """The radius once ``fraction`` of the stored fluid (4 pi/3)(a0^3 - 1) has left a bead of
    initial radius a0: a^3 = (1 - f) a0^3 + f (eq. FluidVolExpelled)."""
    f = np.asarray(fraction, dtype=float)
    if not np.all((f >= 0.0) & (f <= 1.0)):
        raise ParameterError("fraction", fraction, "0 <= f <= 1")
    return np.cbrt((1.0 - f) * a0**3 + f)


@dataclass
class FrontResult:
    """A front trajectory: samples ``t``, ``radius`` a, ``front`` R_f and ``flux`` A.

    ``flux`` is A of eq. ChemPotential_Const (a^2 da/dt = k(phi_+) A); it is -inf at a start
    from the bare equilibrium, where the shell has zero thickness (A ~ 1/d).  Queries
    (:meth:`time_to_radius`, :meth:`state_at`) use the exact curve, not the samples.
    """

    t: np.ndarray
    radius: np.ndarray
    front: np.ndarray
    flux: np.ndarray
    phi_minus: float
    phi_plus: float
    model: str
    start: str
    diagnostics: dict[str, Any]
    curve: FrontCurve = field(repr=False)
    t_stop: float = 0.0
    front_stop: float = 0.0

    @property
    def radius_range(self) -> tuple[float, float]:
        """(smallest, largest) radius the trajectory covers."""
        return float(self.curve.radius(self.front_stop)), float(self.radius[0])

    def time_to_radius(self, a_target: float) -> float:
        """The time at which the radius reaches ``a_target``; ParameterError (a ValueError)
        naming the reachable range when it never does."""
        lo, hi = self.radius_range
        try:
            a = float(a_target)
        except (TypeError, ValueError):
            a = float("nan")
        if not (np.isfinite(a) and lo <= a <= hi):
            raise ParameterError("radius", a_target, f"{lo:.6g} <= a <= {hi:.6g} (the radii "
                                 "this front trajectory reaches)")
        x = min(max(float(self.curve.front(a)), self.front_stop), self.curve.x_start)
        return float(min(self.curve.time_of_front(x), self.t_stop))

    def time_to_fraction(self, fraction: float) -> float:
        """The time at which ``fraction`` of the initially stored fluid has been expelled."""
        return self.time_to_radius(float(fraction_radius(self.curve.levels.a0, fraction)))

    def state_at(self, t: float) -> tuple[float, float]:
        """(a, R_f) at time t in [t[0], t_stop]."""
        tt = float(t)
        if not (np.isfinite(tt) and self.t[0] <= tt <= self.t_stop):
            raise ParameterError("t", t, f"{self.t[0]:.6g} <= t <= {self.t_stop:.6g}")
        x = float(self.curve.front_at(np.array([tt]))[0])
        return float(self.curve.radius(x)), x

    def to_json_dict(self) -> dict[str, Any]:
        """Plain JSON-ready data (non-finite floats become None when printed)."""
        return {
            "model": self.model, "start": self.start,
            "phi_minus": self.phi_minus, "phi_plus": self.phi_plus,
            "t": self.t.tolist(), "radius": self.radius.tolist(),
            "front": self.front.tolist(),
            "flux": [float(v) if np.isfinite(v) else None for v in self.flux],
            "diagnostics": self.diagnostics,
        }
