"""The sharp-interface limit of the regularized model from a ladder of interfacial lengths.

Richardson extrapolation of the dose time t(ell), or of s = t - t_nuc where every rung's front
nucleated before the dose, from grid-converged runs at ell, ell/2, ell/4, with a GCI error
bound (``SAFETY``); outside the asymptotic range (``ORDER_RANGE``) the finest run and the
ladder's spread.  Formulas and measured orders: docs/interfacial.md sec. 7."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

SAFETY = 1.25  # grid convergence index factor for three-level studies (Roache 1998)
ORDER_RANGE = (0.5, 4.0)  # orders outside this range are not trusted


@dataclass(frozen=True)
class Limit:
    """The extrapolated ell -> 0 time, its absolute error bound, the order and how."""

    time: float
    error: float
    order: float | None
    method: str

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form."""
        return asdict(self)


def observed_order(values: Sequence[float], ratio: float = 2.0) -> float:
    """Order p from the last three values at h, h/ratio, h/ratio^2:
    |v0 - v1| / |v1 - v2| = ratio^p (NaN when a difference vanishes)."""
    d1, d2 = abs(values[-3] - values[-2]), abs(values[-2] - values[-1])
    return math.log(d1 / d2, ratio) if d1 > 0 and d2 > 0 else math.nan


def richardson(values: Sequence[float], order: float, ratio: float = 2.0) -> float:
    """Limit h -> 0 from the last two values, with error ~ h^order."""
    return values[-1] - (values[-2] - values[-1]) / (ratio**order - 1.0)


def dose_limit(ells: Sequence[float], times: Sequence[float],
               delays: Sequence[float | None]) -> Limit:
    """The limit ell -> 0 of the dose ``times`` at ``ells``, given each run's nucleation
    delay (None: no front nucleated): after nucleation where every rung has nucleated
    before its dose, else of the times themselves (module doc)."""
    plain = extrapolate(ells, times)
    if all(d is not None and 0.0 <= d <= t for d, t in zip(delays, times, strict=True)):
        after = [t - d for t, d in zip(times, delays, strict=True)]  # type: ignore[operator]
        lim = extrapolate(ells, after)
        if lim.time > 0.0:
            # two estimates of one limit: where both have an order, their gap bounds the error
            gap = abs(lim.time - plain.time) if plain.order is not None else 0.0
            return Limit(lim.time, max(lim.error, gap), lim.order,
                         f"{lim.method}, applied to the time after the front nucleates at the "
                         "edge, a delay that vanishes as ell -> 0"
                         + (f" (bound: its gap to {plain.time:.5g}, the extrapolation of the "
                            "dose time itself)" if gap > lim.error else ""))
    return plain


def extrapolate(ells: Sequence[float], times: Sequence[float]) -> Limit:
    """The limit ell -> 0 of ``times`` measured at ``ells`` = (ell, ell/2, ell/4)."""
    if len(ells) != 3 or len(times) != 3:
        raise ValueError("extrapolation needs three rungs")
    ratio = ells[0] / ells[1]
    if not math.isclose(ratio, ells[1] / ells[2], rel_tol=1e-9) or ratio <= 1.0:
        raise ValueError(f"rungs must shrink by one constant ratio, got {list(ells)}")
    t0, t1, t2 = (float(t) for t in times)
    d1, d2 = t0 - t1, t1 - t2
    spread = max(times) - min(times)
    if d2 == 0.0 and d1 == 0.0:
        return Limit(t2, 0.0, None, "the rungs agree exactly")
    if d1 * d2 > 0.0 and abs(d2) < abs(d1):
        p = observed_order(times, ratio)
        limit = richardson(times, p, ratio)
        if ORDER_RANGE[0] <= p <= ORDER_RANGE[1] and limit * t2 > 0.0:
            return Limit(limit, SAFETY * abs(limit - t2), p,
                         f"Richardson extrapolation with the observed order {p:.2f}")
    return Limit(t2, max(spread, abs(d2)), None,
                 "the rungs are not in the asymptotic range (no trustworthy order): "
                 "the finest rung, with the ladder's spread as its error")
