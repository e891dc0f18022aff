"""Gel parameters, presets and the Flory interaction parameter chi(T, phi).

Parameters follow eq. FloryParam: chi0 = A0 + B0 T, chi1 = A1 + B1 T and
chi(T, phi) = chi0 + chi1 (1 - phi).  Presets: ANB (eq. Params_CaiSuo) and HHT
(eq. Params_Fitted).  The permeability law is either constant (k = 1) or
k = phi / (1 - phi)^beta (eq. Permeability).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace
from typing import Any, Literal

from .errors import ParameterError, require_finite, require_finite_positive
from .limits import T_MAX, T_MIN

BETA_RANGE = (0.0, 10.0)

PermeabilityLaw = Literal["constant", "power"]


def check_temperature(value: float, field_name: str = "temperature") -> float:
    """Validate a temperature in kelvin: liquid water, 273.15-373.15 K."""
    try:
        t = float(value)
    except (TypeError, ValueError):
        raise ParameterError(field_name, value, f"{T_MIN}-{T_MAX} K (liquid water)") from None
    if not math.isfinite(t) or not (T_MIN <= t <= T_MAX):
        raise ParameterError(field_name, value, f"{T_MIN}-{T_MAX} K (liquid water)")
    return t


@dataclass(frozen=True)
class Permeability:
    """Dimensionless permeability law: ``constant`` (k = 1) or ``power`` (eq. Permeability)."""

    law: PermeabilityLaw = "constant"
    beta: float = 0.0

    def __post_init__(self) -> None:
        if self.law not in ("constant", "power"):
            raise ParameterError("permeability.law", self.law, "'constant' or 'power'")
        if self.law == "power":
            try:
                b = float(self.beta)
            except (TypeError, ValueError):
                b = math.nan
            if not (BETA_RANGE[0] < b < BETA_RANGE[1]):
                raise ParameterError("permeability.beta", self.beta, "0 < beta < 10")
            object.__setattr__(self, "beta", b)

    @property
    def code(self) -> int:
        """Integer code used by numba kernels: 0 constant, 1 power law."""
        return 0 if self.law == "constant" else 1

    def __call__(self, phi: Any) -> Any:
        """k(phi); works on floats and numpy arrays."""
        if self.law == "constant":
            return 1.0 + 0.0 * phi
        return phi / (1.0 - phi) ** self.beta


@dataclass(frozen=True)
class Gel:
    """A thermo-responsive gel: Omega, the chi coefficients (eq. FloryParam), permeability."""

    omega: float
    a0: float
    b0: float
    a1: float
    b1: float
    permeability: Permeability = field(default_factory=Permeability)
    name: str = "custom"

    def __post_init__(self) -> None:
        object.__setattr__(self, "omega", require_finite_positive("omega", self.omega))
        for f in ("a0", "b0", "a1", "b1"):
            object.__setattr__(self, f, require_finite(f, getattr(self, f)))
        if isinstance(self.permeability, dict):
            object.__setattr__(self, "permeability", Permeability(**self.permeability))
        if not isinstance(self.permeability, Permeability):
            raise ParameterError("permeability", self.permeability, "a Permeability")

    def chi0(self, temperature: float) -> float:
        """chi_0(T) = A0 + B0 T (eq. FloryParam)."""
        return self.a0 + self.b0 * temperature

    def chi1(self, temperature: float) -> float:
        """chi_1(T) = A1 + B1 T (eq. FloryParam)."""
        return self.a1 + self.b1 * temperature

    def chi(self, temperature: float, phi: Any) -> Any:
        """chi(T, phi) = chi_0(T) + chi_1(T) (1 - phi) (eq. FloryParam)."""
        return self.chi0(temperature) + self.chi1(temperature) * (1.0 - phi)

    def with_permeability(self, law: PermeabilityLaw, beta: float = 0.0) -> Gel:
        """A copy of this gel with another permeability law."""
        return replace(self, permeability=Permeability(law, beta))

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form (JSON-serialisable)."""
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Gel:
        """Inverse of :meth:`to_dict`."""
        d = dict(data)
        perm = d.pop("permeability", None) or {}
        return cls(permeability=Permeability(**perm), **d)

    def key(self) -> tuple[float, ...]:
        """The dimensionless parameters that define the physics (not the name)."""
        p = self.permeability
        return (self.omega, self.a0, self.b0, self.a1, self.b1, float(p.code), p.beta)


ANB = Gel(omega=100.0, a0=-12.947, b0=0.04496, a1=17.92, b1=-0.0569, name="ANB")
HHT = Gel(omega=720.0, a0=-62.22, b0=0.20470, a1=-58.28, b1=0.19044, name="HHT")
PRESETS: dict[str, Gel] = {"ANB": ANB, "HHT": HHT}


def as_gel(gel: Gel | str) -> Gel:
    """A Gel, or the preset of that name: every public physics function accepts both."""
    if isinstance(gel, Gel):
        return gel
    if isinstance(gel, str):
        return preset(gel)
    raise ParameterError("gel", gel, "a Gel or a preset name (" + ", ".join(sorted(PRESETS)) + ")")


def preset(name: str) -> Gel:
    """Look up a preset gel by name (case-insensitive)."""
    g = PRESETS.get(str(name).upper())
    if g is None:
        raise ParameterError("gel", name, "one of " + ", ".join(sorted(PRESETS)))
    return g
