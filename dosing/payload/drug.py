"""The drug: physical parameters, their dimensionless solute, and full-solver drug runs.

A passive solute in the pore fluid (solver/solute): D0 carried to T_end by Stokes-Einstein and
scaled by the gel's D = R^2 / tau (eq. timescale), so one dimensionless run serves every bead
size.  Hindrance, sieving, partition, the mesh, what is neglected, and how drug runs are run
and cached: docs/drug.md (sec. 8 for this module)."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from solver.errors import ParameterError
from solver.limits import T_MAX, T_MIN
from solver.solute import Hindrance, Solute, crank_sphere

from ..quantity import number
from ..units import (
    BOLTZMANN,
    REFERENCE_TEMPERATURE_K,
    PhysicalConstants,
    volume_to_ul,
    water_viscosity,
)

D_RANGE_CM2_S = (0.0, 1e-3)
HINDRANCE_LAWS = ("free-volume", "ogston", "amsden", "none")
T_REF_RANGE = (T_MIN, T_MAX)  # solver.limits


def _opt_positive(name: str, value: Any) -> float | None:
    if value is None:
        return None
    x = number(value)
    if not (math.isfinite(x) and x > 0.0):
        raise ParameterError(name, value, "a finite number > 0")
    return x


@dataclass(frozen=True)
class DrugModel:
    """A drug dissolved in the pore fluid, in physical units (validated on construction):
    ``diffusivity_cm2_s`` D0 at ``reference_temperature_k`` or ``solute_radius_nm``; ``hindrance``,
    ``mesh_size_nm``, ``fiber_radius_nm``, ``free_volume_y``, ``sieving``, ``partition`` K0,
    ``release_volume_ul`` (None: a sink), ``load_ug`` or ``loading_concentration_ug_per_ul``
    (each field: docs/drug.md sec. 8)."""

    diffusivity_cm2_s: float | None = None
    solute_radius_nm: float | None = None
    hindrance: str = "free-volume"
    mesh_size_nm: float | None = None
    fiber_radius_nm: float | None = None
    free_volume_y: float = 1.0
    partition: float = 1.0
    release_volume_ul: float | None = None
    load_ug: float | None = None
    loading_concentration_ug_per_ul: float | None = None
    reference_temperature_k: float = REFERENCE_TEMPERATURE_K
    sieving: bool = True
    partition_law: str | None = None
    mesh_stretch: str = "smallest"

    def __post_init__(self) -> None:
        d = self.diffusivity_cm2_s
        if d is not None:
            x = number(d)
            if not (math.isfinite(x) and D_RANGE_CM2_S[0] <= x <= D_RANGE_CM2_S[1]):
                raise ParameterError("drug.diffusivity_cm2_s", d,
                                     f"a finite number {D_RANGE_CM2_S[0]:g} <= D0 <= "
                                     f"{D_RANGE_CM2_S[1]:g} cm^2/s (0: no diffusion)")
            object.__setattr__(self, "diffusivity_cm2_s", x)
        for name in ("solute_radius_nm", "mesh_size_nm", "fiber_radius_nm", "release_volume_ul",
                     "load_ug", "loading_concentration_ug_per_ul"):
            object.__setattr__(self, name, _opt_positive(f"drug.{name}", getattr(self, name)))
        if self.hindrance not in HINDRANCE_LAWS:
            raise ParameterError("drug.hindrance", self.hindrance,
                                 " or ".join(map(repr, HINDRANCE_LAWS)))
        y = _opt_positive("drug.free_volume_y", self.free_volume_y)
        if y is None or y > 100.0:
            raise ParameterError("drug.free_volume_y", self.free_volume_y, "0 < Y <= 100")
        object.__setattr__(self, "free_volume_y", y)
        k = _opt_positive("drug.partition", self.partition)
        if k is None or not 1e-6 <= k <= 1e6:
            raise ParameterError("drug.partition", self.partition, "1e-6 <= K <= 1e6 (> 0)")
        object.__setattr__(self, "partition", k)
        if self.load_ug is not None and self.loading_concentration_ug_per_ul is not None:
            raise ParameterError("drug.loading_concentration_ug_per_ul",
                                 self.loading_concentration_ug_per_ul,
                                 "None when drug.load_ug is given (give one of them)")
        if self.hindrance in ("ogston", "amsden") and self.fiber_radius_nm is None:
            raise ParameterError("drug.fiber_radius_nm", None,
                                 f"a finite number > 0 (nm) for the {self.hindrance} law")
        tr = self.reference_temperature_k
        x = number(tr)
        if not (math.isfinite(x) and T_REF_RANGE[0] <= x <= T_REF_RANGE[1]):
            raise ParameterError("drug.reference_temperature_k", tr,
                                 f"{T_REF_RANGE[0]:g}-{T_REF_RANGE[1]:g} K (liquid water)")
        object.__setattr__(self, "reference_temperature_k", x)
        if not isinstance(self.sieving, bool):
            raise ParameterError("drug.sieving", self.sieving, "true or false")
        if self.partition_law not in (None, "constant", "ogston"):
            raise ParameterError("drug.partition_law", self.partition_law,
                                 "None (Ogston's with a fibre radius, else constant), "
                                 "'constant' or 'ogston'")
        if self.partition_law == "ogston" and self.fiber_radius_nm is None:
            raise ParameterError("drug.fiber_radius_nm", None,
                                 "a finite number > 0 (nm) for Ogston's partition")
        if self.mesh_stretch not in ("smallest", "volume"):
            raise ParameterError("drug.mesh_stretch", self.mesh_stretch,
                                 "'smallest' (default) or 'volume'")

    # ------------------------------------------------------------------ physical values
    def d0_cm2_s(self, t_end: float, constants: PhysicalConstants | None = None) -> float:
        """D0 in water at ``t_end``: the given D0(T_ref) carried by Stokes-Einstein with
        water's viscosity, or Stokes-Einstein from the solute radius, or 0 (``constants``
        is not used: the drug diffuses in water whatever the gel's timescale assumes)."""
        if self.diffusivity_cm2_s is not None:
            t_ref = self.reference_temperature_k
            return float(self.diffusivity_cm2_s) * (t_end / t_ref) * (
                water_viscosity(t_ref) / water_viscosity(t_end))
        if self.solute_radius_nm is not None:
            return (BOLTZMANN * t_end / (6.0 * math.pi * water_viscosity(t_end)
                                         * self.solute_radius_nm * 1e-9) * 1e4)
        return 0.0

    def solute_radius(self, t_end: float | None = None,
                      constants: PhysicalConstants | None = None) -> float | None:
        """r_s in nm: given, or Stokes-Einstein from D0 at the reference temperature with
        water's viscosity there (None without either)."""
        if self.solute_radius_nm is not None:
            return self.solute_radius_nm
        d = self.diffusivity_cm2_s
        if d is None or d <= 0.0:
            return None
        t_ref = self.reference_temperature_k
        return BOLTZMANN * t_ref / (6.0 * math.pi * water_viscosity(t_ref) * d * 1e-4) * 1e9

    def dry_mesh_nm(self, start_radius: float, constants: PhysicalConstants) -> float:
        """The dry mesh length xi_dry for the sieving: the gel's (the constants' mesh
        length, the interfacial length's) unless ``mesh_size_nm`` overrides it."""
        if self.mesh_size_nm is not None:
            return self.mesh_size_nm / start_radius
        return float(constants.mesh_length_nm)

    def mesh_note(self, start_radius: float, constants: PhysicalConstants) -> str:
        """The mesh the answer assumes, in words."""
        xi = self.dry_mesh_nm(start_radius, constants)
        rs = self.solute_radius()
        src = (f"drug.mesh_size_nm = {self.mesh_size_nm:g} nm at T_start (overrides, for the "
               f"drug only, the gel's mesh_length_nm = {constants.mesh_length_nm:g} nm of the "
               "interfacial length)" if self.mesh_size_nm is not None
               else "the gel's mesh_length_nm (the interfacial length's)")
        size = "no solute radius" if rs is None else f"r_s = {rs:.3g} nm (Stokes-Einstein at " \
            f"{self.reference_temperature_k:g} K)" if self.solute_radius_nm is None \
            else f"r_s = {rs:.3g} nm"
        return (f"Dry mesh xi_dry = {xi:.3g} nm from {src}, affine in the {self.mesh_stretch} "
                f"principal stretch (swollen start {xi * start_radius:.3g} nm); {size}; "
                + ("convective sieving W(r_s/xi) on" if self.sieving and
                   self.hindrance != "none" else "no convective sieving")
                + f"; partition {self.partition_law_used()}.")

    def partition_law_used(self) -> str:
        """'ogston' or 'constant' (the default: Ogston's with a fibre radius)."""
        if self.hindrance == "none":
            return "constant"
        if self.partition_law is not None:
            return self.partition_law
        return "ogston" if self.fiber_radius_nm is not None else "constant"

    def hindrance_law(self, start_radius: float, t_end: float,
                      constants: PhysicalConstants) -> Hindrance:
        """The dimensionless law: mesh r_s / xi_dry, fibre r_s / r_f (module
        ``solver.solute.hindrance``)."""
        if self.hindrance == "none":
            return Hindrance("none", convective=False)
        rs = self.solute_radius(t_end, constants)
        if rs is None and self.hindrance in ("ogston", "amsden"):
            raise ParameterError("drug.solute_radius_nm", None,
                                 f"a finite number > 0 (nm; or D0 > 0) for the "
                                 f"{self.hindrance} law")
        if rs is None and self.mesh_size_nm is not None:
            raise ParameterError("drug.solute_radius_nm", None, "a finite number > 0 "
                                 "(nm; or D0 > 0) for the sieving by drug.mesh_size_nm")
        mesh = 0.0 if rs is None else min(rs / self.dry_mesh_nm(start_radius, constants),
                                          100.0)
        fiber = 0.0 if rs is None or self.fiber_radius_nm is None else min(
            rs / self.fiber_radius_nm, 100.0)
        return Hindrance(self.hindrance, sieve=fiber if self.hindrance == "ogston" else mesh,
                         y=self.free_volume_y, mesh=mesh, fiber=fiber,
                         partition_law=self.partition_law_used(), convective=self.sieving,
                         mesh_stretch=self.mesh_stretch)

    def load(self, stored_fluid_ul: float | None, start_radius: float | None = None,
             constants: PhysicalConstants | None = None) -> float | None:
        """The drug per bead in ug: given, or K c_loading x the stored fluid with
        K = K0 K_s(phi0) (the steric part at the start state when ``start_radius`` and
        ``constants`` are given and the partition law is Ogston's; else K0), or None."""
        if self.load_ug is not None:
            return self.load_ug
        if self.loading_concentration_ug_per_ul is not None and stored_fluid_ul is not None:
            steric = 1.0
            if start_radius is not None and constants is not None:
                law = self.hindrance_law(start_radius, 298.15, constants)
                steric = float(law.steric_partition(1.0 - 1.0 / start_radius**3))
            return (self.partition * steric * self.loading_concentration_ug_per_ul
                    * stored_fluid_ul)
        return None

    def solute(self, start_radius: float, t_end: float, constants: PhysicalConstants,
               dry_radius_um: float | None) -> Solute:
        """The dimensionless solute (D0 in units of the gel's R^2 / tau, volumes in
        4 pi R^3 / 3); a release volume needs the bead size and must hold the bead."""
        d_gel = constants.diffusivity(t_end) * 1e4  # cm^2/s
        vol = None
        if self.release_volume_ul is not None:
            if dry_radius_um is None:
                raise ParameterError("dry_radius_um", None, "a finite number > 0 (um; or "
                                     "swollen_radius_um) to use drug.release_volume_ul")
            unit = volume_to_ul(4.0 * math.pi / 3.0, dry_radius_um)  # uL
            vol = self.release_volume_ul / unit
            if not vol > start_radius**3:
                raise ParameterError("drug.release_volume_ul", self.release_volume_ul,
                                     f"> {start_radius**3 * unit:.4g} uL (the swollen bead's "
                                     "volume: the medium must hold the bead)")
        return Solute(diffusivity=self.d0_cm2_s(t_end, constants) / d_gel,
                      hindrance=self.hindrance_law(start_radius, t_end, constants),
                      partition=self.partition, release_volume=vol)

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form."""
        return asdict(self)

    @classmethod
    def from_any(cls, value: DrugModel | dict[str, Any]) -> DrugModel:
        """A DrugModel from itself or a dict of its fields."""
        if isinstance(value, DrugModel):
            return value
        if isinstance(value, dict):
            try:
                return cls(**value)
            except TypeError as exc:
                raise ParameterError("drug", value, f"a dict of {', '.join(asdict(cls()))}"
                                     ) from exc
        raise ParameterError("drug", value, "a DrugModel or a dict of its fields")


def carried_by_fluid(solute: Solute) -> bool:
    """True if the drug leaves exactly with the fluid on one heating: no diffusion and no
    convective sieving (a D0 = 0 solute that the mesh sieves is retained, not carried)."""
    h = solute.hindrance
    return solute.diffusivity == 0.0 and not (h.convective and h.mesh_ratio > 0.0)


def leak_time(solute: Solute, start_radius: float, fraction: float = 0.1) -> float:
    """Dimensionless time a bead sitting at T_start (no flow, uniform) needs to leak
    ``fraction`` of its load into a perfect sink: Crank's series with D0 f(phi0) (exact for
    the isothermal bead; inf without diffusion)."""
    phi0 = 1.0 - 1.0 / start_radius**3
    d = solute.diffusivity * float(solute.hindrance.factor(phi0))
    if d <= 0.0:
        return math.inf
    if fraction <= 0.5:  # Crank 6.21 for D t / a^2 < 0.05, whose erfc terms are < 1e-8 there:
        # 6 x / sqrt(pi) - 3 x^2 = fraction, x = sqrt(D t) / a (a root, no bisection)
        x = (6.0 / math.sqrt(math.pi) - math.sqrt(36.0 / math.pi - 12.0 * fraction)) / 6.0
        return x * x * start_radius**2 / d
    lo, hi = 0.0, start_radius**2 / d
    while crank_sphere(np.array([hi]), d, start_radius)[0] < fraction:
        hi *= 2.0
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        if crank_sphere(np.array([mid]), d, start_radius)[0] < fraction:
            lo = mid
        else:
            hi = mid
    return hi


@dataclass(kw_only=True)
class StatedTruth:
    """What every drug answer states (issue 12): the interfacial length and bead size of its
    runs and the model in words; and its plain-data form."""

    interfacial_length: float = 0.0
    bead_dry_radius_um: float | None = None
    truth: str = ""

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form (JSON-ready)."""
        return asdict(self)


def sieved_out(solute: Any, start_radius: float, released: float | None = None,
               expelled: float | None = None) -> str | None:
    """A warning when the gel's mesh holds the solute in (issue 37), else None: at the swollen
    start (stretch ``start_radius``) neither diffusion nor the fluid carries it out (r_s >= xi), or
    the run released < 0.1 % of the load (``released``) while expelling > 1 % of the stored fluid
    (``expelled``): the mesh, tighter still in the collapsed shell, sieved it out."""
    h = solute.hindrance
    if h.code == 0 and not h.convective:
        return None
    phi0 = 1.0 - 1.0 / start_radius**3
    f = float(h.factor(phi0, start_radius))
    w = float(h.sieving(phi0, start_radius)) if h.convective else 1.0
    ratio = h.mesh_ratio / start_radius
    got = "" if released is None else f"; it released {released:.4f} of its load"
    fix = ("A larger mesh (--mesh-size-nm / drug.mesh_size_nm), a smaller drug "
           "(--solute-radius-nm) or hindrance 'none' lets it out")
    if f <= 0.0 and w <= 0.0:
        return (f"the drug is sieved out: its radius is {ratio:.2f} x the swollen mesh at "
                f"T_start (r_s / xi >= 1), so neither diffusion nor the expelled fluid can "
                f"carry it out of the gel{got}.  {fix}")
    if released is not None and expelled is not None and released < 1e-3 and expelled > 0.01:
        return (f"the drug is sieved out: it released {released:.4f} of its load while the "
                f"bead expelled {expelled:.0%} of its fluid (its radius is {ratio:.2f} x the "
                f"swollen mesh at T_start, hindered {f:.2g} x D0 there; the collapsed shell's "
                f"tighter mesh holds it in).  {fix}")
    return None
