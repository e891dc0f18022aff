"""Hindered transport of a solute in the gel: diffusion D0 f, convective sieving W, partition K.

``phi`` is the porosity (fluid fraction); the polymer volume fraction is v = 1 - phi.  The
gel's mesh is affine in the network's stretch: xi = xi_dry * lam with lam the *mesh
stretch* of a cell, and the solute-to-mesh ratio is x = r_s / xi = ``mesh`` / lam with the
one parameter ``mesh`` = r_s / xi_dry (xi_dry the gel's dry mesh length, the same length that
sets the interfacial length: ``dosing.units.PhysicalConstants.mesh_length_nm``).
In an isotropic state lam = J^(1/3) = v^(-1/3).  The collapsed shell is strongly
anisotropic (radial stretch ~0.3-0.5, tangential ~2); ``mesh_stretch`` says which length a
solute meets:

- ``"smallest"`` (default): lam = the smallest principal stretch, min(dr/drho, r/rho).  A
  compact (spherical) solute sits in a cage of the network whose sides are xi_dry times the
  principal stretches; it fits in the cage, and passes its windows, only if it fits the
  cage's shortest side, so the shortest side is the mesh it meets (the conservative choice:
  a flattened cage holds no sphere larger than its thickness).
- ``"volume"``: lam = J^(1/3) (the isotropic mesh of the same swelling; the cage's
  geometric mean side), the optimistic bound.

Diffusion, D = D0 f (``Hindrance.law``):

- ``"free-volume"`` (default): Lustig & Peppas, J. Appl. Polym. Sci. 36 (1988) 735,
  f = (1 - r_s / xi) exp(-Y v / (1 - v)); 0 once the mesh is smaller than the solute.
  Y ~ 1 (the ratio of the solute's critical volume to the free volume of water).
- ``"ogston"``: the obstruction law of Ogston, Preston & Wells, Proc. R. Soc. Lond. A 333
  (1973) 297, in the form reviewed by Amsden (Macromolecules 31 (1998) 8382):
  f = exp(-sqrt(v) (1 + r_s / r_f)), r_f the fibre radius (``fiber`` = r_s / r_f).  It
  has no mesh cut-off (random fibres), so it never excludes a solute by size alone.
- ``"amsden"``: Amsden's obstruction law (Polym. Gels Networks 6 (1998) 13; reviewed in
  Macromolecules 31 (1998) 8382),
  f = exp(-pi ((r_s + r_f) / (xi + 2 r_f))^2), here with the affine local mesh xi above
  (Amsden's own closure is the scaling xi = k_s r_f v^(-1/2); affine is ours, stated).
- ``"none"``: f = 1 (free diffusion in the pore fluid; the analytic tests).

Convective sieving (``convective``, on by default): the fluid carries the solute between
cages through windows of the local mesh size, each treated as a cylindrical pore of radius
xi (the free-volume law's exclusion threshold r_s = xi); the solute crossing a face with the
fluid flux Q is W(x) Q c_upwind with the convective hindrance of a sphere in a cylindrical
pore, W = Phi K_c, Phi = (1 - x)^2 and K_c = (1 + 3.867 x - 1.907 x^2 - 0.834 x^3) /
(1 + 1.867 x - 0.741 x^2) (Dechadilok & Deen, Ind. Eng. Chem. Res. 45 (2006) 6953; the
reflection coefficient is sigma = 1 - W, Deen, AIChE J. 33 (1987) 1409).  W = 1 at x = 0
and falls to 0 (full retention) as the solute reaches the mesh (x -> 1).  A face's W is
taken at the tighter of its two cells (where the mesh is smallest).

Partition (``partition_law``): the pore concentration in equilibrium with a medium at c is
K c with K = K0 K_s(phi): K0 the solute's own affinity (``Solute.partition``) and the steric
part ``"constant"`` K_s = 1, or ``"ogston"``, Ogston's partition of spheres among random
fibres, K_s = exp(-v (1 + r_s / r_f)^2) (Ogston, Trans. Faraday Soc. 54 (1958) 1754).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numba import njit

from ..errors import ParameterError

LAWS = {"none": 0, "free-volume": 1, "ogston": 2, "amsden": 3}
PARTITION_LAWS = {"constant": 0, "ogston": 1}
MESH_STRETCHES = {"smallest": 0, "volume": 1}
SIEVE_MAX = 100.0
Y_MAX = 100.0


@njit(cache=True)
def diffusion_factor(phi, lam, code, mesh, fiber, y):
    """f of law ``code`` at porosity ``phi`` and mesh stretch ``lam`` (xi = xi_dry lam);
    ``mesh`` = r_s / xi_dry, ``fiber`` = r_s / r_f; 0 <= f <= 1."""
    if code == 0:
        return 1.0
    v = 1.0 - phi
    if v <= 0.0:
        return 1.0
    if code == 1:
        if phi <= 0.0:
            return 0.0
        s = 1.0 - mesh / lam if lam > 0.0 else 0.0
        if s <= 0.0:
            return 0.0
        return s * np.exp(-y * v / phi)
    if code == 2:
        return np.exp(-np.sqrt(v) * (1.0 + fiber))
    # amsden: (r_s + r_f) / (xi + 2 r_f) = (x + x / F) / (1 + 2 x / F), x = r_s / xi
    if mesh <= 0.0 or lam <= 0.0:
        return 1.0
    x = mesh / lam
    if fiber <= 0.0:
        t = x
    else:
        t = (x + x / fiber) / (1.0 + 2.0 * x / fiber)
    return np.exp(-np.pi * t * t)


@njit(cache=True)
def sieving_factor(lam, mesh):
    """W(x), x = ``mesh`` / ``lam`` = r_s / xi: the convective hindrance of a sphere in a
    cylindrical pore (Dechadilok & Deen 2006); 1 at x = 0, 0 for x >= 1."""
    if mesh <= 0.0:
        return 1.0
    if lam <= 0.0:
        return 0.0
    x = mesh / lam
    if x >= 1.0:
        return 0.0
    kc = (1.0 + 3.867 * x - 1.907 * x * x - 0.834 * x * x * x) / (1.0 + 1.867 * x
                                                                   - 0.741 * x * x)
    w = (1.0 - x) * (1.0 - x) * kc
    return min(w, 1.0)


@njit(cache=True)
def partition_factor(phi, code, fiber):
    """The steric partition K_s(phi) of the pore fluid (``code`` 0: 1; 1: Ogston 1958).

    Ogston's exp(-v (1 + r_s/r_f)^2) is the fraction of the *total* volume open to the
    solute's centre (exp(-v) for a point solute, the random-fibre model's void fraction);
    the kernels hold the solute in the pore fluid (phi c), so the partition per pore volume
    is that over exp(-v): exp(-v ((1 + r_s/r_f)^2 - 1)), 1 for a point solute (issue 36:
    taken per total volume it counted the polymer's excluded volume twice, x0.49 in a
    collapsed ANB shell)."""
    if code == 0:
        return 1.0
    v = 1.0 - phi
    if v <= 0.0:
        return 1.0
    return np.exp(-v * fiber * (2.0 + fiber))


@njit(cache=True)
def isotropic_stretch(phi):
    """The mesh stretch of an isotropic state, J^(1/3) = v^(-1/3)."""
    v = 1.0 - phi
    return np.inf if v <= 0.0 else 1.0 / np.cbrt(v)


@njit(cache=True)
def hindrance_factor(phi, code, sieve, y):
    """f(phi) of law ``code`` in an isotropic state with the one ratio ``sieve`` (the
    free-volume or Amsden law's r_s / xi_dry, Ogston's r_s / r_f): the pre-issue-28 form."""
    lam = isotropic_stretch(phi)
    return diffusion_factor(phi, lam, code, sieve, sieve, y)


def _ratio(name: str, value: Any) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        x = math.nan
    if isinstance(value, bool) or not (math.isfinite(x) and 0.0 <= x <= SIEVE_MAX):
        raise ParameterError(f"hindrance.{name}", value, f"0 <= {name} <= {SIEVE_MAX:g}")
    return x


@dataclass(frozen=True)
class Hindrance:
    """A hindrance law and its parameters (module docstring).

    ``sieve``: the law's own ratio (free-volume and Amsden: ``mesh`` r_s / xi_dry; Ogston:
    ``fiber`` r_s / r_f), kept for the pre-issue-28 callers; ``mesh`` and ``fiber`` set the
    two ratios explicitly (None: from ``sieve`` where the law uses it, else 0); ``y`` the
    free-volume Y; ``partition_law`` the steric partition; ``convective`` the sieving of the
    advective flux; ``mesh_stretch`` which stretch sets the local mesh."""

    law: str = "free-volume"
    sieve: float = 0.0
    y: float = 1.0
    mesh: float | None = None
    fiber: float | None = None
    partition_law: str = "constant"
    convective: bool = True
    mesh_stretch: str = "smallest"

    def __post_init__(self) -> None:
        if self.law not in LAWS:
            raise ParameterError("hindrance.law", self.law, " or ".join(map(repr, LAWS)))
        if self.partition_law not in PARTITION_LAWS:
            raise ParameterError("hindrance.partition_law", self.partition_law,
                                 " or ".join(map(repr, PARTITION_LAWS)))
        if self.mesh_stretch not in MESH_STRETCHES:
            raise ParameterError("hindrance.mesh_stretch", self.mesh_stretch,
                                 " or ".join(map(repr, MESH_STRETCHES)))
        if not isinstance(self.convective, bool):
            raise ParameterError("hindrance.convective", self.convective, "true or false")
        object.__setattr__(self, "sieve", _ratio("sieve", self.sieve))
        for name in ("mesh", "fiber"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, _ratio(name, getattr(self, name)))
        y = self.y
        try:
            x = float(y)
        except (TypeError, ValueError):
            x = math.nan
        if isinstance(y, bool) or not (math.isfinite(x) and 0.0 <= x <= Y_MAX):
            raise ParameterError("hindrance.y", y, f"0 <= y <= {Y_MAX:g}")
        object.__setattr__(self, "y", x)

    @property
    def code(self) -> int:
        """The law's kernel code."""
        return LAWS[self.law]

    @property
    def mesh_ratio(self) -> float:
        """r_s / xi_dry (sieving, and the free-volume and Amsden laws)."""
        if self.mesh is not None:
            return self.mesh
        return self.sieve if self.law in ("free-volume", "amsden") else 0.0

    @property
    def fiber_ratio(self) -> float:
        """r_s / r_f (Ogston's laws, Amsden's)."""
        if self.fiber is not None:
            return self.fiber
        return self.sieve if self.law == "ogston" else 0.0

    def factor(self, phi: float | np.ndarray, stretch: float | np.ndarray | None = None
               ) -> float | np.ndarray:
        """f at porosities ``phi`` (and mesh stretches ``stretch``; default isotropic)."""
        arr = np.asarray(phi, dtype=float)
        lam = (np.broadcast_to(np.asarray(stretch, dtype=float), arr.shape) if stretch
               is not None else None)
        out = np.array([diffusion_factor(float(p), float(isotropic_stretch(float(p)))
                                         if lam is None else float(lam.ravel()[i]), self.code,
                                         self.mesh_ratio, self.fiber_ratio, self.y)
                        for i, p in enumerate(arr.ravel())]).reshape(arr.shape)
        return float(out) if out.ndim == 0 else out

    def sieving(self, phi: float | np.ndarray, stretch: float | np.ndarray | None = None
                ) -> float | np.ndarray:
        """The convective transmission W (1 - the reflection coefficient); 1 when off."""
        arr = np.asarray(phi, dtype=float)
        lam = (np.broadcast_to(np.asarray(stretch, dtype=float), arr.shape) if stretch
               is not None else None)
        out = np.array([1.0 if not self.convective else sieving_factor(
            float(isotropic_stretch(float(p))) if lam is None else float(lam.ravel()[i]),
            self.mesh_ratio) for i, p in enumerate(arr.ravel())]).reshape(arr.shape)
        return float(out) if out.ndim == 0 else out

    def steric_partition(self, phi: float | np.ndarray) -> float | np.ndarray:
        """K_s(phi) of the partition law (multiplies the solute's own K0)."""
        arr = np.asarray(phi, dtype=float)
        code = PARTITION_LAWS[self.partition_law]
        out = np.array([partition_factor(float(p), code, self.fiber_ratio)
                        for p in arr.ravel()]).reshape(arr.shape)
        return float(out) if out.ndim == 0 else out

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form."""
        return asdict(self)
