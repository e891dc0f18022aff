"""Seconds, micrometres and microlitres: the timescale of eq. timescale and volume conversions.

The solver is dimensionless (lengths by the dry radius R, time by tau = eta Omega_p R^2 /
(k0 k_B T_end), eq. timescale).  The default Omega_p = Omega Omega_f is consistent with the
gel's Omega of eq. EqlEqn; ``PhysicalConstants.paper()`` gives the paper's; every constant is
settable.  Why: docs/fitting.md, "The constants (decision)"."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace
from typing import Any

from solver.errors import ParameterError, require_finite_positive
from solver.gel import check_temperature

BOLTZMANN = 1.380649e-23  # J/K (exact, SI 2019)
UM3_PER_UL = 1.0e9  # 1 uL = 1 mm^3 = 1e9 um^3
WATER = "water"
REFERENCE_TEMPERATURE_K = 298.15  # 25 degC: where a drug's D0 is given unless stated
WATER_MOLECULAR_VOLUME_M3 = 3.0e-29  # Omega_f: 18 cm^3/mol / N_A = 2.99e-29 m^3
# the paper's constants (after eq. timescale; k0 printed "m^3", a slip)
PAPER_VISCOSITY_PA_S = 1.0e-3
PAPER_POLYMER_VOLUME_M3 = 3.0e-25
PAPER_PERMEABILITY_M2 = 8.0e-20

# Vogel equation for liquid water, mu = A 10^(B / (T - C)); within 2.5 % over 0-370 C.
_VOGEL_A, _VOGEL_B, _VOGEL_C = 2.414e-5, 247.8, 140.0


def water_viscosity(temperature: float) -> float:
    """Dynamic viscosity of liquid water at T (Pa s), Vogel's correlation."""
    t = check_temperature(temperature, "temperature")
    return _VOGEL_A * 10.0 ** (_VOGEL_B / (t - _VOGEL_C))


@dataclass(frozen=True)
class PhysicalConstants:
    """Constants of eq. timescale.  ``viscosity_pa_s="water"`` uses water at T_end.
    ``polymer_volume_m3`` (Omega_p) None: Omega Omega_f (eq. EqlEqn), resolved by :meth:`for_gel`;
    :meth:`paper`: 3e-25 m^3.  ``mesh_length_nm``: the dry mesh xi_dry, ell = xi_dry / a_d, and
    ``mesh_length_range_nm`` its range (default x2 either way): docs/interfacial.md sec. 9."""

    viscosity_pa_s: float | str = 1.0e-3
    # None: consistent with the gel, Omega_p = Omega Omega_f (resolved by ``for_gel``)
    polymer_volume_m3: float | None = None
    permeability_m2: float = 8.0e-20
    mesh_length_nm: float = 4.0
    mesh_length_range_nm: tuple[float, float] | None = None  # default (xi / 2, 2 xi)
    diffusivity_m2_s: float | None = None  # a kinetics fit's D at diffusivity_t_k (pins tau)
    diffusivity_t_k: float | None = None
    diffusivity_source: str | None = None  # e.g. "kinetics fit of stored gel 'mygel'"
    # k0's temperature law, entering the envelope only (the answer keeps k0 as given):
    # "constant" (the model's), or "tokita-tanaka" (friction falling near the transition)
    k0_law: str = "constant"
    k0_reference_t_k: float = REFERENCE_TEMPERATURE_K  # where k0 is given (uncalibrated)

    def __post_init__(self) -> None:
        v = self.viscosity_pa_s
        if isinstance(v, str):
            if v.strip().lower() != WATER:
                raise ParameterError("constants.viscosity_pa_s", v,
                                     "a finite number > 0 (Pa s) or 'water'")
            object.__setattr__(self, "viscosity_pa_s", WATER)
        else:
            object.__setattr__(self, "viscosity_pa_s",
                               require_finite_positive("constants.viscosity_pa_s", v))
        names = ("permeability_m2", "mesh_length_nm")
        if self.polymer_volume_m3 is not None:
            names = ("polymer_volume_m3", *names)
        for name in names:
            object.__setattr__(self, name,
                               require_finite_positive(f"constants.{name}", getattr(self, name)))
        if self.mesh_length_range_nm is None:
            object.__setattr__(self, "mesh_length_range_nm",
                               (self.mesh_length_nm / 2.0, 2.0 * self.mesh_length_nm))
        try:
            lo, hi = (float(x) for x in self.mesh_length_range_nm)
        except (TypeError, ValueError):
            lo = hi = math.nan
        if not (0.0 < lo <= self.mesh_length_nm <= hi < math.inf):
            raise ParameterError("constants.mesh_length_range_nm", self.mesh_length_range_nm,
                                 "two finite numbers 0 < lo <= mesh_length_nm <= hi (nm)")
        object.__setattr__(self, "mesh_length_range_nm", (lo, hi))
        if self.k0_law not in K0_LAWS:
            raise ParameterError("constants.k0_law", self.k0_law, " or ".join(map(repr, K0_LAWS)))
        object.__setattr__(self, "k0_reference_t_k", check_temperature(
            self.k0_reference_t_k, "constants.k0_reference_t_k"))
        if (self.diffusivity_m2_s is None) != (self.diffusivity_t_k is None):
            raise ParameterError("constants.diffusivity_t_k", self.diffusivity_t_k,
                                 "given together with constants.diffusivity_m2_s (the "
                                 "temperature at which a kinetics fit measured D)")
        if self.diffusivity_m2_s is not None:
            object.__setattr__(self, "diffusivity_m2_s", require_finite_positive(
                "constants.diffusivity_m2_s", self.diffusivity_m2_s))
            object.__setattr__(self, "diffusivity_t_k", check_temperature(
                self.diffusivity_t_k, "constants.diffusivity_t_k"))

    @classmethod
    def paper(cls, **changes: Any) -> PhysicalConstants:
        """The paper's constants (after eq. timescale): eta = 1e-3 Pa s, Omega_p = 3e-25 m^3,
        k0 = 8e-20 m^2 (printed "m^3", ../shared/DESIGN.md); D ~ 1.1e-8 cm^2/s at 308 K."""
        return cls(**{"viscosity_pa_s": PAPER_VISCOSITY_PA_S,
                      "polymer_volume_m3": PAPER_POLYMER_VOLUME_M3,
                      "permeability_m2": PAPER_PERMEABILITY_M2, **changes})

    def for_gel(self, omega: float) -> PhysicalConstants:
        """These constants with Omega_p resolved against a gel of ``omega``: the given value,
        else Omega Omega_f (water's molecular volume), consistent with eq. EqlEqn."""
        if self.polymer_volume_m3 is not None:
            return self
        omega = require_finite_positive("omega", omega)
        return replace(self, polymer_volume_m3=omega * WATER_MOLECULAR_VOLUME_M3)

    @property
    def resolved(self) -> bool:
        """True once Omega_p has a value (given, the paper's, or resolved by :meth:`for_gel`)."""
        return self.polymer_volume_m3 is not None

    def source(self, omega: float | None = None) -> str:
        """Which constants these are, in words (the timescale part's ``source``)."""
        if self.calibrated:
            return self.diffusivity_source or "kinetics fit"
        paper = self.paper(mesh_length_nm=self.mesh_length_nm,
                           mesh_length_range_nm=self.mesh_length_range_nm,
                           k0_law=self.k0_law, k0_reference_t_k=self.k0_reference_t_k)
        if self == paper:
            return ("the paper's constants (eta = 1e-3 Pa s, Omega_p = 3e-25 m^3, "
                    "k0 = 8e-20 m^2)")
        if (omega is not None and self.polymer_volume_m3 is not None
                and math.isclose(self.polymer_volume_m3, omega * WATER_MOLECULAR_VOLUME_M3,
                                 rel_tol=1e-12)
                and self.viscosity_pa_s == PAPER_VISCOSITY_PA_S
                and self.permeability_m2 == PAPER_PERMEABILITY_M2):
            return (f"default constants consistent with the gel: Omega_p = Omega Omega_f = "
                    f"{self.polymer_volume_m3:.3g} m^3 (the gel's Omega {omega:.4g}, water's "
                    "Omega_f 3.0e-29 m^3), eta = 1e-3 Pa s, k0 = 8e-20 m^2 (Bertrand et al.)")
        return "constants given"

    @property
    def calibrated(self) -> bool:
        """True when D (hence tau) comes from a kinetics fit, not from k0, eta and Omega_p."""
        return self.diffusivity_m2_s is not None

    def interfacial_lengths(self, dry_radius_um: float) -> tuple[float, float, float]:
        """(ell, ell_lo, ell_hi) = xi_dry / a_d over the mesh length and its range."""
        a = 1e3 * dry_radius_um  # nm
        lo, hi = self.mesh_length_range_nm
        return self.mesh_length_nm / a, lo / a, hi / a

    @property
    def mobility(self) -> str:
        """The mobility's temperature law under a heating program: 'water' (k_B T and water's
        viscosity) when the viscosity is water's, else 'kT' (dosing.heating.program)."""
        return "water" if self.viscosity_pa_s == WATER else "kT"

    def viscosity(self, t_end: float) -> float:
        """eta in Pa s: the given value, or water's at T_end."""
        if self.viscosity_pa_s == WATER:
            return water_viscosity(t_end)
        return float(self.viscosity_pa_s)

    def diffusivity(self, t_end: float) -> float:
        """Effective diffusivity D = k0 k_B T_end / (eta Omega_p) in m^2/s (after eq. timescale).
        Calibrated (``diffusivity_m2_s`` at ``diffusivity_t_k``, from a kinetics fit, which pins
        only this combination), D at another T_end is D_ref (T/T_ref) eta(T_ref)/eta(T)."""
        if self.diffusivity_m2_s is not None:
            t_ref = float(self.diffusivity_t_k)
            return (self.diffusivity_m2_s * (t_end / t_ref)
                    * self.viscosity(t_ref) / self.viscosity(t_end))
        if self.polymer_volume_m3 is None:
            raise ParameterError("constants.polymer_volume_m3", None,
                                 "a value in m^3, or the constants resolved against the gel "
                                 "first (PhysicalConstants.for_gel(gel.omega): Omega_p = "
                                 "Omega Omega_f), or PhysicalConstants.paper()")
        return (self.permeability_m2 * BOLTZMANN * t_end
                / (self.viscosity(t_end) * self.polymer_volume_m3))

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form."""
        d = asdict(self)
        d["mesh_length_range_nm"] = list(self.mesh_length_range_nm)
        return d

    @classmethod
    def from_dict(cls, data: dict[str, Any] | None) -> PhysicalConstants:
        """Inverse of :meth:`to_dict` (None gives the defaults; ``"paper": true`` starts from
        the paper's constants, the other fields given overriding them)."""
        d = dict(data or {})
        if d.pop("paper", False):
            return cls.paper(**{k: v for k, v in cls.from_dict(d).to_dict().items()
                                if k in d})
        if d.get("mesh_length_range_nm") is not None:
            d["mesh_length_range_nm"] = tuple(d["mesh_length_range_nm"])
        return cls(**d)


@dataclass(frozen=True)
class Timescale:
    """tau of eq. timescale for one bead, with the inputs and the formula written out."""

    seconds: float
    dry_radius_um: float
    t_end: float
    viscosity_pa_s: float
    polymer_volume_m3: float
    permeability_m2: float
    diffusivity_cm2_s: float
    calibrated_by: str | None = None  # a kinetics fit pinned D (then k0, Omega_p are moot)

    @property
    def formula(self) -> str:
        """The formula with the numbers substituted."""
        if self.calibrated_by:
            return (f"tau = R^2 / D(T_end) = ({self.dry_radius_um:.4g} um)^2 / "
                    f"({self.diffusivity_cm2_s:.4g} cm^2/s) = {self.seconds:.4g} s  [R = dry "
                    f"radius; D = k0 k_B T_end / (eta Omega_p) pinned by the "
                    f"{self.calibrated_by} (eq. timescale), not by the default constants]")
        return (f"tau = eta Omega_p R^2 / (k0 k_B T_end) = ({self.viscosity_pa_s:.4g} Pa s)"
                f"({self.polymer_volume_m3:.4g} m^3)({self.dry_radius_um:.4g} um)^2 / "
                f"(({self.permeability_m2:.4g} m^2)({BOLTZMANN:.6g} J/K)({self.t_end:.5g} K)) "
                f"= {self.seconds:.4g} s  [R = dry radius; effective diffusivity "
                f"D = R^2/tau = {self.diffusivity_cm2_s:.3g} cm^2/s]")

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form, including the formula text."""
        return {**asdict(self), "formula": self.formula}


SYMBOLIC_FORMULA = ("tau = eta Omega_p R^2 / (k0 k_B T_end) (eq. timescale; R = dry radius): "
                    "give a bead size to get seconds")


def timescale(dry_radius_um: float, t_end: float,
              constants: PhysicalConstants | None = None,
              omega: float | None = None) -> Timescale:
    """tau = eta Omega_p R^2 / (k0 k_B T_end) for a dry radius in micrometres (eq. timescale).

    Default constants need the gel's ``omega`` (Omega_p = Omega Omega_f) unless resolved.
    """
    c = constants or PhysicalConstants()
    if omega is not None:
        c = c.for_gel(omega)
    r_um = require_finite_positive("dry_radius_um", dry_radius_um)
    t1 = check_temperature(t_end, "t_end")
    d = c.diffusivity(t1)
    r_m = r_um * 1.0e-6
    return Timescale(seconds=r_m * r_m / d, dry_radius_um=r_um, t_end=t1,
                     viscosity_pa_s=c.viscosity(t1), polymer_volume_m3=c.polymer_volume_m3,
                     permeability_m2=c.permeability_m2, diffusivity_cm2_s=d * 1.0e4,
                     calibrated_by=(c.diffusivity_source or "kinetics fit")
                     if c.calibrated else None)


def stored_volume(start_radius: float) -> float:
    """Dimensionless pore (fluid) volume of the swollen bead, (4 pi/3)(a0^3 - 1)."""
    return 4.0 * math.pi / 3.0 * (start_radius**3 - 1.0)


def expelled_volume(start_radius: float, radius: float) -> float:
    """Dimensionless expelled volume (4 pi/3)(a(0)^3 - a^3) (eq. FluidVolExpelled)."""
    return 4.0 * math.pi / 3.0 * (start_radius**3 - radius**3)


def released_fraction(start_radius: Any, radius: Any) -> Any:
    """The fraction of the stored fluid expelled at radius a: (a0^3 - a^3) / (a0^3 - 1)
    (eq. FluidVolExpelled over the stored volume; arrays too)."""
    return (start_radius**3 - radius**3) / (start_radius**3 - 1.0)


def radius_after_dose(start_radius: float, fraction: float) -> float:
    """Radius once ``fraction`` of the stored fluid has left: a^3 = a0^3 - f (a0^3 - 1).

    For f = 0.8 this is a^3 = 0.2 a0^3 + 0.8 (the paper's printed dose formula is the
    remaining volume, not the dose; ../shared/DESIGN.md).
    """
    return (start_radius**3 - fraction * (start_radius**3 - 1.0)) ** (1.0 / 3.0)


def volume_to_ul(volume: float, dry_radius_um: float) -> float:
    """A dimensionless volume (in dry-radius^3 units) in microlitres."""
    return volume * dry_radius_um**3 / UM3_PER_UL


def ul_to_volume(volume_ul: float, dry_radius_um: float) -> float:
    """Microlitres to a dimensionless volume (in dry-radius^3 units)."""
    return volume_ul * UM3_PER_UL / dry_radius_um**3


# ------------------------------------------------------------------ k0's temperature law
K0_LAWS = ("constant", "tokita-tanaka")
# Tokita & Tanaka (Science 253, 1121, 1991): the friction between water and a PNIPAM network
# at constant volume falls reversibly by three orders of magnitude as the gel approaches its
# transition.  The stand-in: log10 of the friction falls linearly by TOKITA_DECADES between
# TOKITA_T_K[0] (20 degC) and TOKITA_T_K[1] (34 degC), constant outside (not a fit to their
# points: a bracket of the size and place of the effect).
TOKITA_DECADES = 3.0
TOKITA_T_K = (293.15, 307.15)


def k0_temperature_factor(law: str, temperature: float, reference: float) -> float:
    """k0(T) / k0(T_ref) of ``law`` ("constant": 1; "tokita-tanaka": the stand-in above;
    the friction is 1 / k0, so tau scales by the inverse)."""
    if law == "constant":
        return 1.0
    if law != "tokita-tanaka":
        raise ParameterError("constants.k0_law", law, " or ".join(map(repr, K0_LAWS)))
    lo, hi = TOKITA_T_K

    def decades(t: float) -> float:
        return TOKITA_DECADES * min(max((t - lo) / (hi - lo), 0.0), 1.0)

    return 10.0 ** (decades(temperature) - decades(reference))


# ---------------------------------------------------------------- the constants' range
TANAKA_FILLMORE_D_CM2_S = 3.0e-7  # the gel diffusivity the paper quotes (Tanaka 1979)
HOW_TO_PIN = ("pin it by a kinetics fit to a measured shrinking curve: thermogel fit kinetics "
              "FILE.csv --gel G --t-start T0 --t-end T1 --dry-radius-um R --save NAME, then "
              "--gel NAME (docs/fitting.md)")


def timescale_uncertainty(omega: float, t_end: float, constants: PhysicalConstants,
                          seconds: float | None = None,
                          calibrated_interval: tuple[float, float] | None = None
                          ) -> dict[str, Any]:
    """How far the seconds can be trusted: tau over three defensible diffusivities (eq. timescale;
    no swelling curve fixes k0 / Omega_p): the constants used, the paper's (Omega_p = 3e-25 m^3)
    and Tanaka & Fillmore's 3e-7 cm^2/s; calibrated (a kinetics fit), the fit's interval.
    docs/fitting.md, "The constants (decision)"."""
    c = constants.for_gel(omega)
    d_used = c.diffusivity(t_end) * 1e4  # cm^2/s
    if c.calibrated:
        lo, hi = calibrated_interval or (d_used, d_used)
        out: dict[str, Any] = {
            "calibrated": True, "source": c.source(omega),
            "diffusivity_cm2_s": d_used, "diffusivity_range_cm2_s": [lo, hi],
            "factor": hi / lo,
            "note": "tau from the effective diffusivity a kinetics fit measured (eq. "
                    "timescale: the fit pins D = k0 k_B T / (eta Omega_p), not k0 alone); the "
                    "range is its 95% interval"}
    else:
        omega_p = omega * WATER_MOLECULAR_VOLUME_M3
        d_consistent = d_used * float(c.polymer_volume_m3) / omega_p
        d_paper = d_used * float(c.polymer_volume_m3) / PAPER_POLYMER_VOLUME_M3
        ds = {"constants used": d_used,
              f"Omega_p = Omega Omega_f = {omega_p:.3g} m^3 (the gel's Omega {omega:.4g})":
                  d_consistent,
              "the paper's Omega_p = 3e-25 m^3": d_paper,
              "Tanaka & Fillmore's measured gel diffusivity": TANAKA_FILLMORE_D_CM2_S}
        ds = {k: v for i, (k, v) in enumerate(ds.items())
              if i == 0 or not math.isclose(v, d_used, rel_tol=1e-9)}
        lo, hi = min(ds.values()), max(ds.values())
        out = {"calibrated": False, "source": c.source(omega), "diffusivity_cm2_s": d_used,
               "diffusivity_range_cm2_s": [lo, hi], "candidates_cm2_s": ds,
               "factor": hi / lo,
               "note": f"UNCALIBRATED: the seconds are uncertain by a factor {hi / lo:.3g} "
                       f"(the timescale constants' range, D {lo:.2g}-{hi:.2g} cm^2/s); "
                       + HOW_TO_PIN}
    if seconds is not None:
        out["seconds_range"] = [seconds * d_used / hi, seconds * d_used / lo]
    out["how_to_pin"] = HOW_TO_PIN
    return out
