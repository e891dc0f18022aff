"""Bead size distributions of a batch: lognormal, normal and a measured table (issue 26).

A batch of beads is described by its distribution of radii, stated as number- or
volume-weighted and as dry or swollen sizes (swollen at T_start: dry = swollen / a0, the
equilibrium stretch of eq. EqlEqn).  :meth:`SizeDistribution.resolve` turns a spec into a
:class:`DrySizes`, the number-weighted distribution of *dry* radii in micrometres, which
carries what the batch's answer needs: the quadrature nodes over sizes (with their volume
weights, since a bead's fluid is (4 pi/3)(a0^3 - 1) R^3: eq. FluidVolExpelled), the
number-weighted CDF and quantiles (the fraction of beads that have delivered, the 10th-90th
percentile bead) and samples (the brute-force check).

* ``lognormal``: by ``mean_um`` and ``cv`` (sigma^2 = ln(1 + CV^2)), or ``median_um`` and
  ``gsd`` (sigma = ln GSD).  A volume-weighted lognormal is the number-weighted one with
  mu shifted by 3 sigma^2 (Hatch-Choate); the quadrature is Gauss-Hermite in ln R over the
  volume-weighted law (scipy.special.roots_hermite).
* ``normal``: ``mean_um`` and ``cv`` (or ``sd_um``) of a normal truncated to
  R > ``NORMAL_CUT`` x mean (the cut keeps a volume-weighted normal's bead count finite: its
  number density ~ pdf / R^3 is not integrable at 0); Gauss-Legendre over the support.
* ``table``: measured sizes (radii or diameters), with counts or not (rows = beads);
  the sum over its distinct sizes is exact (no quadrature error).
"""

from __future__ import annotations

import csv
import functools
import io
import math
import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from solver.errors import ParameterError
from solver.limits import DRY_RADIUS_UM_RANGE, SIZE_UM_RANGE

from ..quantity import micrometres, number

KINDS = ("lognormal", "normal", "table")
WEIGHTINGS = ("number", "volume")
STATES = ("dry", "swollen")
MEASURES = ("radius", "diameter")
MAX_CV = 2.0
MAX_ROWS = 100_000
NORMAL_CUT = 0.01  # the normal's lower truncation, a fraction of its mean
NORMAL_SPAN = 8.0  # its quadrature span: mean -/+ this many SDs (tail mass < 1e-13)
F = "size_distribution"


def _pos(name: str, value: Any) -> float:
    x = micrometres(value, f"{F}.{name}")
    lo, hi = SIZE_UM_RANGE
    if not lo <= x <= hi:  # after the unit's conversion
        raise ParameterError(f"{F}.{name}", value, f"a size {lo:g}-{hi:g} um (or with a "
                             "unit)")
    return x


def _cv(name: str, value: Any) -> float:
    x = number(value)
    if not (math.isfinite(x) and 0.0 <= x <= MAX_CV):
        raise ParameterError(f"{F}.{name}", value, f"a finite number 0 <= CV <= {MAX_CV:g}")
    return x


def _choice(name: str, value: Any, allowed: tuple[str, ...]) -> str:
    v = str(value).strip().lower() if isinstance(value, str) else value
    if v not in allowed:
        raise ParameterError(f"{F}.{name}", value, " or ".join(f"'{a}'" for a in allowed))
    return v


def _table(sizes: Any, counts: Any) -> tuple[np.ndarray, np.ndarray]:
    if sizes is None or isinstance(sizes, (str, bytes)) or not hasattr(sizes, "__len__"):
        raise ParameterError(f"{F}.sizes_um", sizes, "a non-empty list of sizes > 0 (um)")
    n = len(sizes)
    if n == 0:
        raise ParameterError(f"{F}.sizes_um", [], "a non-empty list of sizes > 0 (um)")
    if n > MAX_ROWS:
        raise ParameterError(f"{F}.sizes_um", f"{n} rows", f"at most {MAX_ROWS} rows")
    try:
        r = np.asarray(sizes, dtype=float)
    except (TypeError, ValueError):
        r = np.array([_pos(f"sizes_um[{i}]", s) for i, s in enumerate(sizes)])
    lo, hi = SIZE_UM_RANGE
    bad = np.flatnonzero(~(np.isfinite(r) & (r >= lo) & (r <= hi)))
    if bad.size:
        i = int(bad[0])
        raise ParameterError(f"{F}.sizes_um[{i}]", sizes[i], f"a size {lo:g}-{hi:g} um")
    if counts is None:
        return r, np.ones_like(r)
    if isinstance(counts, (str, bytes)) or not hasattr(counts, "__len__") or len(counts) != n:
        raise ParameterError(f"{F}.counts", counts, f"None or {n} numbers >= 0 (one per size)")
    try:
        c = np.asarray(counts, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"{F}.counts", counts, "numbers >= 0") from None
    bad = np.flatnonzero(~(np.isfinite(c) & (c >= 0.0)))
    if bad.size:
        i = int(bad[0])
        raise ParameterError(f"{F}.counts[{i}]", counts[i], "a finite number >= 0")
    if not c.sum() > 0.0:
        raise ParameterError(f"{F}.counts", "all zero", "at least one count > 0")
    return r, c


@dataclass(frozen=True)
class SizeDistribution:
    """A batch's bead sizes as given (module doc): ``kind`` lognormal / normal / table, its
    parameters in um (or strings with a unit), ``weighting`` number / volume, ``state``
    dry / swollen (at T_start), ``measure`` radius / diameter.

    A lognormal or normal without a size (``mean_um`` / ``median_um``) takes the dose
    request's bead size as its number-weighted mean (``with_mean``).
    """

    kind: str = "lognormal"
    mean_um: Any = None
    cv: Any = None
    median_um: Any = None
    gsd: Any = None
    sd_um: Any = None
    sizes_um: Any = None
    counts: Any = None
    weighting: str = "number"
    state: str = "dry"
    measure: str = "radius"
    # what a table read from a file was read as (read_sizes_csv), and once resolved, what
    # it was converted to: stated in describe(), not part of the spec's value
    read: str | None = field(default=None, repr=False, compare=False)
    _table: tuple[np.ndarray, np.ndarray] | None = field(default=None, init=False,
                                                         repr=False, compare=False)

    def __post_init__(self) -> None:
        k = _choice("kind", self.kind, KINDS)
        set_ = object.__setattr__
        set_(self, "kind", k)
        set_(self, "weighting", _choice("weighting", self.weighting, WEIGHTINGS))
        set_(self, "state", _choice("state", self.state, STATES))
        set_(self, "measure", _choice("measure", self.measure, MEASURES))
        given = {n for n in ("mean_um", "cv", "median_um", "gsd", "sd_um", "sizes_um", "counts")
                 if getattr(self, n) is not None}
        allowed = {"lognormal": {"mean_um", "cv", "median_um", "gsd"},
                   "normal": {"mean_um", "cv", "sd_um"},
                   "table": {"sizes_um", "counts"}}[k]
        for n in sorted(given - allowed):
            raise ParameterError(f"{F}.{n}", getattr(self, n),
                                 f"None for a {k} distribution (it takes "
                                 f"{', '.join(sorted(allowed))})")
        for n in ("mean_um", "median_um", "sd_um"):
            if getattr(self, n) is not None:
                set_(self, n, _pos(n, getattr(self, n)))
        if self.cv is not None:
            set_(self, "cv", _cv("cv", self.cv))
        if self.gsd is not None:
            g = number(self.gsd)
            top = math.exp(math.sqrt(math.log1p(MAX_CV**2)))
            if not (math.isfinite(g) and 1.0 <= g <= top):
                raise ParameterError(f"{F}.gsd", self.gsd, f"a finite number 1 <= GSD <= "
                                     f"{top:.4g} (CV <= {MAX_CV:g})")
            set_(self, "gsd", g)
        if k == "table":
            r, c = _table(self.sizes_um, self.counts)
            set_(self, "_table", (r, c))
            set_(self, "sizes_um", tuple(r.tolist()))
            set_(self, "counts", None if self.counts is None else tuple(c.tolist()))
            return
        if k == "lognormal":
            if "median_um" in given or "gsd" in given:
                if given & {"mean_um", "cv"}:
                    raise ParameterError(f"{F}.median_um", self.median_um,
                                         "None when mean_um and cv are given (a lognormal by "
                                         "mean and CV, or by median and GSD)")
                if self.gsd is None:
                    raise ParameterError(f"{F}.gsd", None, "a number >= 1 with median_um")
            elif self.cv is None:
                raise ParameterError(f"{F}.cv", None, f"a number 0 <= CV <= {MAX_CV:g}")
        else:
            if (self.cv is None) == (self.sd_um is None):
                raise ParameterError(f"{F}.cv", self.cv,
                                     "a number 0 <= CV <= 2, or sd_um (give one of them)")

    @property
    def has_size(self) -> bool:
        """True when the spec carries its own size (mean, median or table)."""
        return self.kind == "table" or self.mean_um is not None or self.median_um is not None

    def with_mean(self, mean_um: float) -> SizeDistribution:
        """The same spread with the number-weighted mean ``mean_um`` (in its state)."""
        if self.kind == "table" or self.median_um is not None:
            raise ParameterError(f"{F}.mean_um", mean_um, "only for a lognormal or normal "
                                 "given by its CV")
        if self.weighting != "number":
            raise ParameterError(f"{F}.weighting", self.weighting, "'number' without mean_um "
                                 "(the request's bead size is the number-weighted mean); give "
                                 "mean_um for a volume-weighted law")
        d = self.to_dict()
        d.update(mean_um=mean_um)
        return SizeDistribution.from_dict(d)

    def number_mean_um(self) -> float:
        """The number-weighted mean radius (um) in the spec's own state (dry / swollen)."""
        return self._number_law(1.0).mean()

    def _number_law(self, scale: float) -> Any:
        """The number-weighted law of radii (um) times ``scale`` (a scipy-like object
        with mean, cdf, ppf, rvs, and the quadrature's nodes)."""
        half = 0.5 if self.measure == "diameter" else 1.0
        s = scale * half
        if self.kind == "table":
            r, c = self._table
            w = c / r**3 if self.weighting == "volume" else c
            return _TableLaw(r * s, w)
        if self.kind == "lognormal":
            if self.median_um is not None:
                mu, sig = math.log(self.median_um), math.log(self.gsd)
            else:
                sig = math.sqrt(math.log1p(self.cv**2))
                mu = math.log(self.mean_um) - 0.5 * sig**2
            if self.weighting == "volume":
                mu -= 3.0 * sig**2  # Hatch-Choate: volume -> number
                return _LognormalLaw(mu + math.log(s), sig)
            exact = None if self.mean_um is None else self.mean_um * s
            return _LognormalLaw(mu + math.log(s), sig, exact)
        sd = self.sd_um if self.sd_um is not None else self.cv * self.mean_um
        return _NormalLaw(self.mean_um * s, sd * s, self.weighting == "volume")

    def resolve(self, start_radius: float, t_start: float | None = None) -> DrySizes:
        """The number-weighted dry radii (um): swollen sizes over a0 (eq. EqlEqn), the
        swelling at ``t_start``; a table says what it read and what it became ('3 swollen
        diameters (um) ... at 302 K, converted to dry radii 40-60 um')."""
        if not self.has_size:
            raise ParameterError(f"{F}.mean_um", None,
                                 "a size > 0 (um), or a bead size on the request")
        scale = 1.0 / start_radius if self.state == "swollen" else 1.0
        law = self._number_law(scale)
        spec = self
        if self.kind == "table":
            r = law.r
            at = (f" at {t_start:g} K (swollen {start_radius:.4g} x dry)"
                  if self.state == "swollen" and t_start is not None else
                  f" (swollen {start_radius:.4g} x dry)" if self.state == "swollen" else "")
            done = ("" if self.state == "dry" and self.measure == "radius"
                    else ", converted to dry radii")
            read = (self.read or self.describe_plain()) + at
            read += f"{done} {r.min():.4g}-{r.max():.4g} um" if done else \
                f": dry radii {r.min():.4g}-{r.max():.4g} um"
            spec = SizeDistribution(**{**self.to_dict(), "read": read})
        return DrySizes(spec, law)

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form (the fields given)."""
        return {"kind": self.kind, "mean_um": self.mean_um, "cv": self.cv,
                "median_um": self.median_um, "gsd": self.gsd, "sd_um": self.sd_um,
                "sizes_um": None if self.sizes_um is None else list(self.sizes_um),
                "counts": None if self.counts is None else list(self.counts),
                "weighting": self.weighting, "state": self.state, "measure": self.measure}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> SizeDistribution:
        """Inverse of :meth:`to_dict` (unknown fields refused, naming them)."""
        names = {"kind", "mean_um", "cv", "median_um", "gsd", "sd_um", "sizes_um", "counts",
                 "weighting", "state", "measure"}
        for k in d:
            if k not in names:
                raise ParameterError(f"{F}.{k}", d[k], f"one of {', '.join(sorted(names))}")
        return cls(**{k: v for k, v in d.items() if v is not None})

    def describe_plain(self) -> str:
        """A table's sizes in words ('3 dry radii (um)')."""
        n = len(self.sizes_um or ())
        return SizeHeader(self.state, self.measure, "um", "").describe(n)

    def describe(self) -> str:
        """The distribution in words (a table read from a file: what it was read as)."""
        w, st = self.weighting, self.state
        m = "diameters" if self.measure == "diameter" else "radii"
        if self.kind == "table" and self.read:
            return (f"a measured table: {self.read}"
                    + ("" if self.counts is None else ", with counts") + f" ({w}-weighted)")
        if self.kind == "table":
            n = len(self.sizes_um)
            return (f"a measured table of {n} {st} {m}"
                    + ("" if self.counts is None else " with counts")
                    + f" ({w}-weighted)")
        if self.kind == "lognormal":
            if self.median_um is not None:
                return (f"a {w}-weighted lognormal of {st} {m}, median {self.median_um:.4g} um,"
                        f" geometric SD {self.gsd:.4g}")
            return (f"a {w}-weighted lognormal of {st} {m}, mean {self.mean_um:.4g} um, "
                    f"CV {self.cv:.3g}")
        sd = self.sd_um if self.sd_um is not None else self.cv * self.mean_um
        return (f"a {w}-weighted normal of {st} {m}, mean {self.mean_um:.4g} um, SD "
                f"{sd:.4g} um (truncated to > {NORMAL_CUT:g} x mean)")


def as_distribution(value: Any) -> SizeDistribution:
    """A :class:`SizeDistribution` from itself or a dict of its fields."""
    if isinstance(value, SizeDistribution):
        return value
    if isinstance(value, dict):
        return SizeDistribution.from_dict(value)
    raise ParameterError(F, value, "a SizeDistribution or a dict of its fields")


Z_SPAN = 8.0  # the lognormal's quadrature span in standard deviations (tail mass 1e-15)


@functools.lru_cache(maxsize=32)
def legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights on [-1, 1] (scipy.special.roots_legendre)."""
    from scipy.special import roots_legendre

    return roots_legendre(n)


class _Continuous:
    """A continuous law in a quadrature variable z on [zlo, zhi]: the radius R(z), its
    inverse, and the volume-weighted density in z (unnormalised)."""

    zlo: float
    zhi: float

    def nodes_between(self, n: int, cuts: tuple[float, ...] = ()) -> tuple[np.ndarray,
                                                                         np.ndarray]:
        """(radii, volume weights summing to 1): Gauss-Legendre with ``n`` nodes on each
        panel of [zlo, zhi] split at the radii ``cuts`` (where the integrand has a kink)."""
        zs = sorted(z for z in (float(self.z_of(c)) for c in cuts) if self.zlo < z < self.zhi)
        edges = [self.zlo, *zs, self.zhi]
        x, w = legendre(n)
        z = np.concatenate([0.5 * (b - a) * x + 0.5 * (a + b)
                            for a, b in zip(edges[:-1], edges[1:], strict=True)])
        ww = np.concatenate([0.5 * (b - a) * w for a, b in zip(edges[:-1], edges[1:],
                                                              strict=True)])
        v = ww * self.vdensity(z)
        return self.r_of(z), v / v.sum()


class _LognormalLaw(_Continuous):
    """ln R ~ N(mu, sig) (number-weighted); z the volume-weighted law's standard normal
    variable, ln R = mu + 3 sig^2 + sig z (Hatch-Choate)."""

    def __init__(self, mu: float, sig: float, mean: float | None = None) -> None:
        self.mu, self.sig, self._mean = mu, sig, mean
        self.zlo, self.zhi = -Z_SPAN, Z_SPAN

    @property
    def degenerate(self) -> bool:
        return self.sig == 0.0

    def r_of(self, z: Any) -> Any:
        return np.exp(self.mu + 3.0 * self.sig**2 + self.sig * np.asarray(z))

    def z_of(self, r: float) -> float:
        return (math.log(r) - self.mu - 3.0 * self.sig**2) / self.sig

    def vdensity(self, z: Any) -> Any:
        return np.exp(-0.5 * np.asarray(z) ** 2)

    def mean(self) -> float:
        return self._mean if self._mean is not None else math.exp(self.mu + 0.5 * self.sig**2)

    def cdf(self, r: Any) -> Any:
        if self.degenerate:
            return np.where(np.asarray(r) >= self.mean(), 1.0, 0.0)
        from scipy.special import ndtr

        with np.errstate(divide="ignore"):
            return ndtr((np.log(r) - self.mu) / self.sig)

    def ppf(self, p: Any) -> Any:
        from scipy.special import ndtri

        return np.exp(self.mu + self.sig * ndtri(p)) if self.sig > 0 else (
            np.full(np.shape(p), self.mean()))

    def rvs(self, n: int, rng: np.random.Generator) -> np.ndarray:
        return np.exp(self.mu + self.sig * rng.standard_normal(n))

    def nodes(self, n: int, cuts: tuple[float, ...] = ()) -> tuple[np.ndarray, np.ndarray]:
        """Split Gauss-Legendre in ln R (``nodes_between``), or the single size."""
        if self.degenerate:
            return np.array([self.mean()]), np.ones(1)
        return self.nodes_between(n, cuts)

    def hermite(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """Gauss-Hermite in ln R over the volume-weighted law (the unsplit rule; it
        converges slowly where the integrand has a kink: the convergence table's check)."""
        from scipy.special import roots_hermite

        x, w = roots_hermite(n)
        return self.r_of(math.sqrt(2.0) * x), w / math.sqrt(math.pi)


class _NormalLaw(_Continuous):
    """A normal of radii truncated to [NORMAL_CUT mean, mean + NORMAL_SPAN sd]; the normal
    is the number-weighted law, or (``volume``) the volume-weighted one; z = R."""

    def __init__(self, mean: float, sd: float, volume: bool) -> None:
        self.m, self.sd, self.volume = mean, sd, volume
        self.cut = NORMAL_CUT * mean
        self.zlo, self.zhi = max(self.cut, mean - NORMAL_SPAN * sd), mean + NORMAL_SPAN * sd
        self._grid: tuple[np.ndarray, np.ndarray] | None = None

    @property
    def degenerate(self) -> bool:
        return self.sd == 0.0

    def r_of(self, z: Any) -> Any:
        return np.asarray(z, dtype=float)

    def z_of(self, r: float) -> float:
        return r

    def _pdf(self, r: Any) -> Any:
        return np.exp(-0.5 * ((np.asarray(r) - self.m) / self.sd) ** 2)

    def vdensity(self, z: Any) -> Any:
        return self._pdf(z) * (1.0 if self.volume else np.asarray(z) ** 3)

    def _table(self) -> tuple[np.ndarray, np.ndarray]:
        """The number-weighted CDF on a fine grid (trapezoid; volume-weighted: pdf / R^3)."""
        if self._grid is None:
            r = np.linspace(self.cut, self.zhi, 40001)
            dens = self._pdf(r) / (r**3 if self.volume else 1.0)
            c = np.concatenate([[0.0], np.cumsum(0.5 * (dens[1:] + dens[:-1]) * np.diff(r))])
            self._grid = (r, c / c[-1])
        return self._grid

    def _below(self) -> float:
        from scipy.special import ndtr

        return float(ndtr((self.cut - self.m) / self.sd))

    def mean(self) -> float:
        if self.degenerate:
            return self.m
        if not self.volume:  # the normal truncated below at the cut
            a = (self.cut - self.m) / self.sd
            return self.m + self.sd * math.exp(-0.5 * a * a) / math.sqrt(2 * math.pi) / (
                1.0 - self._below())
        r, c = self._table()
        return float(np.sum(0.5 * (r[1:] + r[:-1]) * np.diff(c)))

    def cdf(self, r: Any) -> Any:
        if self.degenerate:
            return np.where(np.asarray(r) >= self.m, 1.0, 0.0)
        if not self.volume:
            from scipy.special import ndtr

            lo = self._below()
            rr = np.maximum(np.asarray(r, dtype=float), self.cut)
            return (ndtr((rr - self.m) / self.sd) - lo) / (1.0 - lo)
        g, c = self._table()
        return np.interp(r, g, c)

    def ppf(self, p: Any) -> Any:
        if self.degenerate:
            return np.full(np.shape(p), self.m)
        if not self.volume:
            from scipy.special import ndtri

            lo = self._below()
            return self.m + self.sd * ndtri(lo + np.asarray(p) * (1.0 - lo))
        g, c = self._table()
        return np.interp(p, c, g)

    def rvs(self, n: int, rng: np.random.Generator) -> np.ndarray:
        return np.asarray(self.ppf(rng.uniform(size=n)))

    def nodes(self, n: int, cuts: tuple[float, ...] = ()) -> tuple[np.ndarray, np.ndarray]:
        """Split Gauss-Legendre over the support (``nodes_between``), or the single size."""
        if self.degenerate:
            return np.array([self.m]), np.ones(1)
        return self.nodes_between(n, cuts)


class _TableLaw:
    """A measured table: distinct radii and their number weights."""

    degenerate = False

    def __init__(self, r: np.ndarray, w: np.ndarray) -> None:
        u, inv = np.unique(r, return_inverse=True)
        ww = np.bincount(inv, weights=w)
        keep = ww > 0
        self.r, self.w = u[keep], ww[keep] / ww[keep].sum()
        self._c = np.cumsum(self.w)

    def mean(self) -> float:
        return float(np.sum(self.r * self.w))

    def cdf(self, r: Any) -> Any:
        i = np.searchsorted(self.r, r, side="right")
        return np.where(i > 0, self._c[np.maximum(i - 1, 0)], 0.0)

    def ppf(self, p: Any) -> Any:
        i = np.searchsorted(self._c, np.asarray(p) - 1e-12, side="left")
        return self.r[np.minimum(i, len(self.r) - 1)]

    def rvs(self, n: int, rng: np.random.Generator) -> np.ndarray:
        return rng.choice(self.r, size=n, p=self.w)

    def nodes(self, n: int, cuts: tuple[float, ...] = ()) -> tuple[np.ndarray, np.ndarray]:
        v = self.w * self.r**3
        return self.r, v / v.sum()


@dataclass(frozen=True)
class DrySizes:
    """A resolved batch: the number-weighted distribution of dry radii (um)."""

    spec: SizeDistribution
    law: Any

    @property
    def exact(self) -> bool:
        """True when the nodes are the batch itself (a table, or a single size)."""
        return self.spec.kind == "table" or self.law.degenerate

    @functools.cached_property
    def mean_um(self) -> float:
        """The number-weighted mean dry radius (the reference bead)."""
        return float(self.law.mean())

    def nodes(self, n: int, cuts: tuple[float, ...] = ()) -> tuple[np.ndarray, np.ndarray]:
        """(dry radii in um, volume weights summing to 1): ``n`` Gauss-Legendre nodes per
        panel over the volume-weighted law, panels split at the radii ``cuts`` (the batch
        itself when ``exact``)."""
        return self.law.nodes(n, cuts)

    def cdf(self, r_um: Any) -> Any:
        """Fraction of beads (by number) with dry radius <= r_um."""
        return self.law.cdf(r_um)

    def quantile(self, p: Any) -> Any:
        """The number-weighted p-quantile of the dry radius (um)."""
        return self.law.ppf(p)

    def sample(self, n: int, seed: int = 0) -> np.ndarray:
        """``n`` beads' dry radii (um) drawn by number."""
        return self.law.rvs(n, np.random.default_rng(seed))


# ---------------------------------------------------------------------- a measured CSV
# the words a size column's header may use (any order, any case, separated by spaces,
# underscores or hyphens; the unit in brackets or as the last word)
STATE_WORDS = {"dry": "dry", "swollen": "swollen", "wet": "swollen", "hydrated": "swollen"}
MEASURE_WORDS = {"radius": "radius", "radii": "radius", "r": "radius",
                 "diameter": "diameter", "diameters": "diameter", "diam": "diameter",
                 "d": "diameter", "dia": "diameter"}
UNIT_WORDS = ("um", "µm", "μm", "micron", "microns", "micrometre", "micrometer",
              "micrometres", "micrometers", "nm", "mm", "cm", "m")
IGNORED_WORDS = ("bead", "beads", "size", "sizes", "measured", "mean", "of", "the", "in",
                 "at", "t_start", "tstart", "start")
ACCEPTED = ("'dry' or 'swollen' (optional: default dry, or the request's), 'radius' or "
            "'diameter' (also r, d, radii, diameters), and a length unit in brackets or as the "
            "last word (um, nm, mm; default um): e.g. 'dry radius (um)', 'radius_um', "
            "'swollen diameter (um)'")


@dataclass(frozen=True)
class SizeHeader:
    """What a size column's header says: the state (None: not said), radius or diameter,
    the unit, and the header itself."""

    state: str | None
    measure: str
    unit: str
    column: str

    def describe(self, n: int) -> str:
        """'3 swollen diameters (um)'."""
        m = "diameters" if self.measure == "diameter" else "radii"
        if n == 1:
            m = self.measure
        st = "" if self.state is None else f"{self.state} "
        return f"{n} {st}{m} ({self.unit})"


def read_header(name: str, field_name: str = f"{F}.sizes_um") -> SizeHeader:
    """The state (dry | swollen), measure (radius | diameter) and unit a size column's
    header names ('dry radius (um)', 'radius_um', 'swollen diameter (mm)', 'd_nm'); a header
    that names no measure, or a word it does not know, is refused naming the column and
    the words it accepts (:data:`ACCEPTED`)."""
    low = name.strip().lower()
    unit = None
    m = re.search(r"[\(\[]\s*([^\)\]]+?)\s*[\)\]]", low)
    if m:
        unit = m.group(1).strip()
        low = (low[:m.start()] + " " + low[m.end():]).strip()
    words = [w for w in re.split(r"[\s_\-/.,:]+", low) if w]
    if unit is None and len(words) > 1 and words[-1] in UNIT_WORDS:
        unit = words.pop()
    states = {STATE_WORDS[w] for w in words if w in STATE_WORDS}
    measures = {MEASURE_WORDS[w] for w in words if w in MEASURE_WORDS}
    unknown = [w for w in words if w not in STATE_WORDS and w not in MEASURE_WORDS
               and w not in IGNORED_WORDS and w not in UNIT_WORDS]
    if len(measures) != 1 or len(states) > 1 or unknown:
        why = ("it names both radius and diameter" if len(measures) > 1
               else "it names both dry and swollen" if len(states) > 1
               else f"unknown word '{unknown[0]}'" if unknown
               else "it names neither radius nor diameter")
        raise ParameterError(f"{field_name} (column '{name.strip()}')", name.strip(),
                             "a header naming " + ACCEPTED, why)
    return SizeHeader(next(iter(states)) if states else None, measures.pop(), unit or "um",
                      name.strip())


def read_sizes_csv(source: str, field_name: str = f"{F}.sizes_um",
                   **spec: Any) -> SizeDistribution:
    """A table distribution from CSV text or a file path: a column of sizes, read as its
    header says (:func:`read_header`: dry or swollen, radius or diameter, the unit; e.g.
    ``dry radius (um)``, ``radius_um``, ``swollen diameter (mm)``; no header: radii in um,
    dry unless ``state`` says) and an optional second column of counts.  ``spec`` sets
    ``weighting`` and ``state`` (a header that names the other state is refused, naming
    the column), and ``measure`` for a headerless file.  The distribution says what was
    read (``describe()``: '3 swollen diameters (um) from the column ...')."""
    text = source
    if "\n" not in source:  # a path (CSV text has at least one line break)
        try:
            with open(source, encoding="utf-8-sig") as fh:
                text = fh.read()
        except OSError as exc:
            raise ParameterError(field_name, source, "a readable CSV file") from exc
    rows = [r for r in csv.reader(io.StringIO(text)) if r and any(c.strip() for c in r)]
    if not rows:
        raise ParameterError(field_name, source, "a CSV with at least one size")
    given_state = spec.pop("state", None)
    head = SizeHeader(None, spec.pop("measure", "radius"), "um", "")
    try:
        float(rows[0][0])
    except ValueError:
        head = read_header(rows[0][0], field_name)
        rows = rows[1:]
    if given_state is not None and head.state is not None and head.state != given_state:
        raise ParameterError(f"{field_name} (column '{head.column}')", head.column,
                             f"{given_state} sizes (the request's bead size is {given_state})"
                             f", or a header without '{head.state}'",
                             f"the column says {head.state}")
    state = head.state or given_state or "dry"
    if len(rows) > MAX_ROWS:
        raise ParameterError(field_name, f"{len(rows)} rows", f"at most {MAX_ROWS} rows")
    if not rows:
        raise ParameterError(field_name, source, "a CSV with at least one size")
    factor = micrometres(f"1 {head.unit}", f"{field_name} (the header's unit)")
    sizes, counts = [], []
    for i, r in enumerate(rows):
        try:
            sizes.append(float(r[0]) * factor)
            if len(r) > 1 and r[1].strip():
                counts.append(float(r[1]))
        except ValueError:
            raise ParameterError(f"{field_name}[{i}]", r, "numbers (a size, optionally a "
                                 "count)") from None
    if counts and len(counts) != len(sizes):
        raise ParameterError(f"{F}.counts", f"{len(counts)} of {len(sizes)} rows",
                             "a count on every row or on none")
    read = SizeHeader(state, head.measure, head.unit, head.column).describe(len(sizes))
    read += f" from the column '{head.column}'" if head.column else " (no header)"
    return SizeDistribution(kind="table", sizes_um=sizes, counts=counts or None,
                            measure=head.measure, state=state, read=read, **spec)


def request_sizes(req: Any) -> None:
    """The dose request's hook (before its checks): resolve ``req.size_distribution`` and
    set the request's bead size to the batch's number-weighted mean (the reference bead:
    its ell and tau), or take a spread without a size around the request's bead size."""
    value = req.size_distribution
    if value is None:
        return
    d = as_distribution(value)
    if req.dose_fraction is None:
        raise ParameterError("dose_fraction", None, "a fraction of the batch's stored fluid "
                             "(with a size_distribution: volumes and masses need a bead count)")
    own, other = (("dry_radius_um", "swollen_radius_um") if d.state == "dry"
                  else ("swollen_radius_um", "dry_radius_um"))
    if getattr(req, other) is not None:
        raise ParameterError(other, getattr(req, other),
                             f"None with a {d.state} size_distribution (its number-weighted "
                             f"mean goes in {own})")
    size = getattr(req, own)
    if not d.has_size:
        if size is None:
            raise ParameterError(f"{F}.mean_um", None, f"a size > 0 (um), or {own} as the "
                                 "batch's number-weighted mean")
        d = d.with_mean(micrometres(size, own))
    else:
        mean = d.number_mean_um()
        lo, hi = DRY_RADIUS_UM_RANGE if d.state == "dry" else SIZE_UM_RANGE
        if not (math.isfinite(mean) and lo <= mean <= hi):  # the reference bead's size
            where = next((f"{F}.{n}" for n in ("mean_um", "median_um", "sizes_um")
                          if getattr(d, n) is not None), F)
            raise ParameterError(where, f"a number-weighted mean of {mean:.4g} um",
                                 f"a {d.state} mean size {lo:g}-{hi:g} um")
        if size is None:
            object.__setattr__(req, own, mean)
        elif not math.isclose(micrometres(size, own), mean, rel_tol=1e-9):
            raise ParameterError(own, size, f"None or the size_distribution's number-weighted "
                                 f"mean {mean:.6g} um")
    object.__setattr__(req, "size_distribution", d)
