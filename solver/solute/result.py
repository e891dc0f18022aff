"""The plain-data outcomes of the solute's runs (arrays plus diagnostics): ``ReleaseResult``
(one bead, module ``transport``) and ``MediumRelease`` (a batch in one medium, module
``medium``)."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..json_safe import json_safe

# a release result's arrays (its .npz, and a drug run's in the run store)
RELEASE_ARRAYS = ("t", "radius", "released_fraction", "advected_fraction",
                  "expelled_fraction", "in_gel_fraction", "medium_concentration",
                  "temperature", "profile_t", "profiles", "profile_radii",
                  "squeezed_fraction", "state_index", "states")


@dataclass
class ReleaseResult:
    """A passive solute carried by the pore fluid (module ``transport``), dimensionless.

    Per mechanics sample t: radius a(t), ``released_fraction`` of the loaded solute now in
    the medium (its ``advected_fraction`` part crossed the edge with the fluid: squeezed
    out; the rest diffused), ``expelled_fraction`` of the stored fluid (a0^3 - a^3) /
    (a0^3 - 1) (negative while the gel takes up fluid), ``in_gel_fraction``,
    ``medium_concentration`` (per loaded mass and per volume of 4 pi R^3 / 3; 0 for a perfect
    sink) and temperature.  ``profiles`` (len(profile_t), n): pore concentrations c / c0
    (c0 the loaded concentration) at cell-centre radii ``profile_radii``.
    ``mass_balance_error`` is max |in gel + released - 1| over the run (and its D0 = 0
    twin's).  ``squeezed_fraction``: the release of the same mechanics with D0 = 0 (what
    the fluid's motion alone releases; grid-independent, unlike ``advected_fraction``, the
    released mass that crossed the edge with the fluid); ``start_partition`` K at the start
    state.  ``states`` (one row per sample index in ``state_index``, the protocol's step
    boundaries): the march's whole state there (cell masses and the medium's, step size,
    advected mass), from which a run of a protocol sharing those steps continues
    (``transport.SoluteStart``).
    """

    t: np.ndarray
    radius: np.ndarray
    released_fraction: np.ndarray
    advected_fraction: np.ndarray
    expelled_fraction: np.ndarray
    in_gel_fraction: np.ndarray
    medium_concentration: np.ndarray
    temperature: np.ndarray
    profile_t: np.ndarray
    profiles: np.ndarray
    profile_radii: np.ndarray
    mass_balance_error: float = 0.0
    effective_diffusivity: float = 0.0
    diagnostics: dict[str, Any] = field(default_factory=dict)
    squeezed_fraction: np.ndarray = field(default_factory=lambda: np.zeros(0))
    start_partition: float = 1.0
    state_index: np.ndarray = field(default_factory=lambda: np.zeros(0))
    states: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))

    def squeezed_at(self, time: float) -> float:
        """The D0 = 0 twin's release at ``time`` (the advected part if no twin was run)."""
        s = self.squeezed_fraction if np.size(self.squeezed_fraction) == np.size(self.t) \
            else self.advected_fraction
        return float(np.interp(time, self.t, s))

    def peclet(self, start: float, end: float) -> float | None:
        """The heating's Peclet number between ``start`` and ``end``: the mean shrinking
        speed (a(start) - a(end)) / (end - start) times the swollen radius a(0) over the
        start state's hindered diffusivity D0 f(phi0) (``effective_diffusivity``); None
        without diffusion or without a span (Pe >> 1: the fluid's motion outruns diffusion,
        the release is squeezed out; Pe << 1: diffusion dominates)."""
        if not (end > start) or self.effective_diffusivity <= 0.0:
            return None
        a = np.interp([start, end], self.t, self.radius)
        return float(abs(a[0] - a[1]) / (end - start) * self.radius[0]
                     / self.effective_diffusivity)

    @property
    def diffused_fraction(self) -> np.ndarray:
        """The released solute that left by diffusion (released minus advected)."""
        return self.released_fraction - self.advected_fraction

    def released_at(self, time: float) -> float:
        """Released fraction at ``time`` (linear between samples)."""
        return float(np.interp(time, self.t, self.released_fraction))

    def advected_at(self, time: float) -> float:
        """Advected (squeezed-out) part of the released fraction at ``time``."""
        return float(np.interp(time, self.t, self.advected_fraction))

    def time_to_release(self, amount: float, after: float = 0.0) -> float:
        """First time >= ``after`` at which released(t) - released(after) reaches ``amount``
        (linear between samples); ValueError if never."""
        base = self.released_at(after)
        i0 = int(np.searchsorted(self.t, after, side="right"))
        rel = self.released_fraction[i0:] - base
        hit = np.nonzero(rel >= amount)[0]
        if hit.size == 0:
            raise ValueError(f"a release of {amount:.6g} is not reached by t = "
                             f"{self.t[-1]:.6g} (at most {float(rel.max(initial=0.0)):.6g})")
        j = i0 + int(hit[0])
        t0, r0 = (after, 0.0) if j == i0 else (float(self.t[j - 1]),
                                               float(self.released_fraction[j - 1] - base))
        t1, r1 = float(self.t[j]), float(self.released_fraction[j] - base)
        return t1 if r1 == r0 else t0 + (amount - r0) / (r1 - r0) * (t1 - t0)

    def to_json_dict(self, profiles: bool = True) -> dict[str, Any]:
        """JSON-ready dict (NaN -> None); ``profiles=False`` drops the profiles.  The march's
        states (a restart's, not an outcome) are left out."""
        out: dict[str, Any] = {}
        for name in RELEASE_ARRAYS:
            if name in ("state_index", "states") or (
                    name in ("profiles", "profile_radii") and not profiles):
                continue
            out[name] = getattr(self, name)
        out["mass_balance_error"] = self.mass_balance_error
        out["effective_diffusivity"] = self.effective_diffusivity
        out["start_partition"] = self.start_partition
        out["diagnostics"] = self.diagnostics
        return json_safe(out)

    def save(self, path: str | Path) -> Path:
        """Write to an .npz file (arrays plus scalars and diagnostics as JSON)."""
        p = Path(path)
        arrays = {name: np.asarray(getattr(self, name)) for name in RELEASE_ARRAYS}
        extra = {"mass_balance_error": self.mass_balance_error,
                 "effective_diffusivity": self.effective_diffusivity,
                 "start_partition": self.start_partition,
                 "diagnostics": self.diagnostics}
        np.savez_compressed(p, extra=np.array(json.dumps(json_safe(extra))), **arrays)
        return p if p.suffix == ".npz" else p.with_name(p.name + ".npz")

    @classmethod
    def load(cls, path: str | Path) -> ReleaseResult:
        """Read a file written by :meth:`save`."""
        with np.load(Path(path), allow_pickle=False) as data:
            kwargs: dict[str, Any] = {k: np.array(data[k]) for k in RELEASE_ARRAYS if k in data}
            kwargs.update(json.loads(str(data["extra"])))
        return cls(**kwargs)


@dataclass
class MediumRelease:
    """A batch's coupled release into one medium (module ``medium``), dimensionless, on the
    output ``t`` (units of tau_ref): the batch's released fraction of its load, each class's
    own (net: what left minus what it took back), the medium's concentration (per load /
    batch dry volume), the classes' load shares ``nu`` and time ratios ``rho``, the medium's
    volume v0 (units of the batch's dry volume; None: a perfect sink), the mass-balance
    error (max |gel + medium - 1|) and the steps taken."""

    t: np.ndarray
    released: np.ndarray
    class_released: np.ndarray  # (classes, times)
    concentration: np.ndarray
    nu: np.ndarray
    rho: np.ndarray
    medium_volume: float | None
    mass_balance_error: float
    steps: int
    diagnostics: dict[str, Any] = field(default_factory=dict)

    def released_at(self, time: float) -> float:
        """The batch's released fraction at ``time`` (linear between outputs)."""
        return float(np.interp(time, self.t, self.released))

    def time_to_release(self, fraction: float) -> float:
        """The first time the batch has released ``fraction`` of its load (ValueError when
        it does not within the outputs)."""
        r = self.released
        hit = np.nonzero(r >= fraction)[0]
        if hit.size == 0:
            raise ValueError(f"the batch releases at most {r.max():.6g} of its load by "
                             f"t = {self.t[-1]:.6g}")
        i = int(hit[0])
        if i == 0:
            return float(self.t[0])
        t0, t1, r0, r1 = self.t[i - 1], self.t[i], r[i - 1], r[i]
        return float(t0 + (fraction - r0) * (t1 - t0) / (r1 - r0))
