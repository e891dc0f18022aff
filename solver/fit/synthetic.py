"""Synthetic measurements from a known gel, for coverage tests and benchmarks."""

from __future__ import annotations

import numpy as np

from ..equilibrium import equilibrium
from ..gel import Gel
from .equilibrium import SIZE_POWER, SwellingData


def synthetic_swelling(gel: Gel, *, n: int = 30, t_range: tuple[float, float] = (290.0, 320.0),
                       scale: float = 1.0, kind: str = "radius", size_noise: float = 0.01,
                       temperature_noise: float = 0.05, branch: str = "swollen",
                       seed: int = 0) -> SwellingData:
    """``n`` equilibria (eq. EqlEqn) evenly spread over ``t_range`` on ``branch`` (the stable
    state reached by heating, for ``swollen``), size = scale lambda^m with relative Gaussian
    noise ``size_noise`` and temperature noise ``temperature_noise`` K."""
    rng = np.random.default_rng(seed)
    t = np.linspace(*t_range, n)
    lam = np.array([equilibrium(gel, float(x), branch).stretch for x in t])
    size = scale * lam ** SIZE_POWER[kind] * (1.0 + size_noise * rng.standard_normal(n))
    return SwellingData(t + temperature_noise * rng.standard_normal(n), size, kind)
