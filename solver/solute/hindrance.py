"""Hindered diffusion of a solute in the gel: D(phi) = D0 f(phi).

``phi`` is the porosity (fluid fraction); the polymer volume fraction is v = 1 - phi.
Laws (``Hindrance.law``):

- ``"free-volume"`` (default): Lustig & Peppas, J. Appl. Polym. Sci. 36 (1988) 735,
  f = (1 - r_s / xi) exp(-Y v / (1 - v)), with the mesh size of an affinely swollen network
  xi = xi_dry v^(-1/3) (Peppas' xi = v^(-1/3) (r0^2)^(1/2)), so r_s / xi = s v^(1/3) with
  the one sieving parameter s = r_s / xi_dry; f = 0 once the mesh is smaller than the solute.
  Y ~ 1 (the ratio of the solute's critical volume to the free volume of water).  The
  collapsed shell (v ~ 0.5-0.8) hinders strongly: exp(-Y v / (1 - v)) = 0.37 at v = 0.5 and
  0.018 at v = 0.8, and any sieving term falls further.
- ``"ogston"``: Ogston's obstruction model (Trans. Faraday Soc. 54 (1958) 1754),
  f = exp(-sqrt(v) r_s / r_f) with s = r_s / r_f (solute over fibre radius).
- ``"none"``: f = 1 (free diffusion in the pore fluid; the analytic tests).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numba import njit

from ..errors import ParameterError

LAWS = {"none": 0, "free-volume": 1, "ogston": 2}
SIEVE_MAX = 100.0
Y_MAX = 100.0


@njit(cache=True)
def hindrance_factor(phi, code, sieve, y):
    """f(phi) of law ``code`` (see the module docstring); 0 <= f <= 1."""
    if code == 0:
        return 1.0
    v = 1.0 - phi
    if v <= 0.0:
        return 1.0
    if code == 1:
        if phi <= 0.0:
            return 0.0
        s = 1.0 - sieve * np.cbrt(v)
        if s <= 0.0:
            return 0.0
        return s * np.exp(-y * v / phi)
    return np.exp(-sieve * np.sqrt(v))


@dataclass(frozen=True)
class Hindrance:
    """A hindrance law and its parameters: ``sieve`` s (r_s / xi_dry for free-volume,
    r_s / r_f for Ogston) and ``y`` (Y of the free-volume law)."""

    law: str = "free-volume"
    sieve: float = 0.0
    y: float = 1.0

    def __post_init__(self) -> None:
        if self.law not in LAWS:
            raise ParameterError("hindrance.law", self.law, " or ".join(map(repr, LAWS)))
        for name, top in (("sieve", SIEVE_MAX), ("y", Y_MAX)):
            v = getattr(self, name)
            try:
                x = float(v)
            except (TypeError, ValueError):
                x = math.nan
            if isinstance(v, bool) or not (math.isfinite(x) and 0.0 <= x <= top):
                raise ParameterError(f"hindrance.{name}", v, f"0 <= {name} <= {top:g}")
            object.__setattr__(self, name, x)

    @property
    def code(self) -> int:
        """The law's kernel code."""
        return LAWS[self.law]

    def factor(self, phi: float | np.ndarray) -> float | np.ndarray:
        """f(phi) for a porosity or an array of them."""
        arr = np.asarray(phi, dtype=float)
        out = np.array([hindrance_factor(float(p), self.code, self.sieve, self.y)
                        for p in arr.ravel()]).reshape(arr.shape)
        return float(out) if out.ndim == 0 else out

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form."""
        return asdict(self)
