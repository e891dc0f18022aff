"""Pydantic v2 models of the HTTP service: every field states its unit and its bounds.

Temperatures are in kelvin (liquid water, 273.15-373.15 K); stretches, porosities, radii
and times without a unit suffix are dimensionless as in the paper (lengths by the dry
radius, time by tau of eq. timescale).  Fields ending in ``_um``, ``_ul``, ``_ug`` or
``seconds`` carry SI-derived units.  These models are shared by the server
(:mod:`api.http`) and the client (:mod:`api.client`); they import no physics.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Annotated, Any, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Discriminator,
    Field,
    StringConstraints,
    Tag,
    ValidationInfo,
    field_validator,
    model_validator,
)

from dosing.quantity import from_edge
from dosing.request import ScheduleRequest as PlannerSchedule
from dosing.runs.scenario import DEFAULT_INTERFACIAL_LENGTH
from dosing.units import REFERENCE_TEMPERATURE_K
from solver.limits import (
    BEAD_COUNT_RANGE,
    DRUG_STEP_MAX,
    DRY_RADIUS_UM_RANGE,
    MEDIUM_VOLUME_ML_RANGE,
    REST_RANGE,
    T_MAX,
    T_MIN,
    TRUTH_DIRECT_ELL_RANGE,
    TRUTH_LADDER_START_RANGE,
)

from .outputs import EnvelopeFields, UncertaintyOut, UncertaintyPart
from .outputs import Out as _Out

# the ranges are solver.limits' (one definition): temperatures, the ladder's coarsest ell
# (its rungs go down to ell / 4) and a direct run's ell
ELL_DEFAULT = DEFAULT_INTERFACIAL_LENGTH
ELL_RANGE = TRUTH_LADDER_START_RANGE
DIRECT_ELL_RANGE = TRUTH_DIRECT_ELL_RANGE
Method = Literal["direct", "ladder"]

# a preset ('ANB', 'HHT') or a stored fitted gel (dosing.fits.gel_store; an unknown name is a 422)
GelName = Annotated[str, StringConstraints(pattern=r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$")]
Branch = Literal["swollen", "shrunken"]



MIN_RADIUS_UM = DRY_RADIUS_UM_RANGE[0]  # 1 nm: a subnormal radius made tau 0 (issue 22)

def interfacial_length_field() -> Any:
    """The validation truth's interfacial length: None (the bead's own), 0 (the paper's
    model) or a given ell."""
    return Field(None, ge=0.0, le=DIRECT_ELL_RANGE[1], examples=[None, 0.0], description=(
        "interfacial length ell of the validation truth in dry radii: null (default) for "
        "the bead's own, ell = xi_dry / a_d from constants.mesh_length_nm and the bead size "
        "(1e-4, standing for the limit ell -> 0, without a bead size; with validation_method "
        f"'ladder': {ELL_DEFAULT}); 0 for the paper's model (no interfacial energy; checked "
        f"on two grids); or a given ell, {DIRECT_ELL_RANGE[0]}-{DIRECT_ELL_RANGE[1]} (direct) "
        f"or {ELL_RANGE[0]}-{ELL_RANGE[1]} (ladder: the limit ell -> 0 extrapolated from runs "
        "at ell, ell/2, ell/4)"))


def method_field() -> Any:
    """How the regularized truth is computed: 'direct' (default) or 'ladder'."""
    return Field("direct", description=(
        "'direct' (default): the regularized model at the interfacial length itself on the "
        "moving grid (400 cells, checked at 200); 'ladder': the limit ell -> 0 extrapolated "
        "from three uniform Lagrangian runs at ell, ell/2, ell/4"))


def check_interfacial_length(value: float | None, info: ValidationInfo) -> float | None:
    """None, 0 or within DIRECT_ELL_RANGE, or ELL_RANGE with validation_method 'ladder'
    (declared before interfacial_length; a ValueError names the range)."""
    ladder = (info.data or {}).get("validation_method") == "ladder"
    lo, hi = ELL_RANGE if ladder else DIRECT_ELL_RANGE
    if value is not None and value != 0.0 and not lo <= value <= hi:
        raise ValueError(f"interfacial_length must be null (the bead's own), 0 (the paper's "
                         f"model) or {lo}-{hi} dry radii"
                         + (" (the ladder goes down to ell / 4)" if ladder else ""))
    return value


def _has_non_finite(value: Any) -> bool:
    if isinstance(value, float):
        return not math.isfinite(value)
    if isinstance(value, (list, tuple)):
        return any(_has_non_finite(x) for x in value)
    if isinstance(value, dict):
        return any(_has_non_finite(x) for x in value.values())
    return False


def check_finite_steps(steps: list[Any] | None) -> list[Any] | None:
    """A protocol's structured steps hold finite numbers only (JSON's NaN and Infinity are
    refused here, with the body's other errors: the steps' own parser names the rest)."""
    for i, step in enumerate(steps or []):
        if _has_non_finite(step):
            raise ValueError(f"protocol step {i} holds a number that is not finite (NaN or "
                             "Infinity)")
    return steps


def temperature_field(what: str, example: float) -> Any:
    """A temperature field in kelvin bounded to liquid water."""
    return Field(ge=T_MIN, le=T_MAX, examples=[example],
                 description=f"{what} in K; liquid water, {T_MIN}-{T_MAX} K")


FREE_FORM = ("protocol",)  # request fields whose items are free-form JSON (no typed floats)


def _has_non_finite(value: Any) -> bool:
    """True when a JSON value holds NaN or an infinite number at any depth."""
    if isinstance(value, float):
        return not math.isfinite(value)
    if isinstance(value, dict):
        return any(_has_non_finite(v) for v in value.values())
    if isinstance(value, list):
        return any(_has_non_finite(v) for v in value)
    return False


def _positive_zero(value: Any) -> Any:
    """-0.0 -> 0.0, also inside lists and dicts (a request never echoes a negative zero)."""
    if isinstance(value, float):
        return value + 0.0  # IEEE: -0.0 + 0.0 == +0.0
    if isinstance(value, list):
        return [_positive_zero(v) for v in value]
    return value


class RequestModel(BaseModel):
    """Base of requests: strict and finite.

    Unknown fields are rejected (a typo is a 422, not a silent default); no coercion
    (``"0.8"`` is not a number, ``"yes"`` not a boolean); NaN, +-Infinity and overflowing
    literals such as ``1e309`` are refused by every float field; -0.0 becomes 0.0.
    """

    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False)

    @field_validator("*")
    @classmethod
    def _no_negative_zero(cls, value: Any) -> Any:
        return _positive_zero(value)

    @field_validator("*", mode="before")
    @classmethod
    def _finite_inside(cls, value: Any, info: ValidationInfo) -> Any:
        """NaN and +-Infinity are refused inside a free-form field too (a protocol's
        structured steps: typed fields refuse them themselves), naming the field, before
        any check across fields."""
        if info.field_name in FREE_FORM and _has_non_finite(value):
            raise ValueError("NaN and Infinity are not numbers here (give finite numbers)")
        return value

    @field_validator("*", mode="before")
    @classmethod
    def _units(cls, value: Any, info: ValidationInfo) -> Any:
        """A physical field (named by its unit: t_start, dry_radius_um, ...) also takes a
        string with a unit ("50 um", "29 degC", "10 min"), converted to its documented
        unit by dosing.quantity; a wrong unit is a 422 naming the field."""
        return from_edge(info.field_name or "", value)




# ----------------------------------------------------------------------------- gels

class GelParameters(RequestModel):
    """A custom gel: a preset with any of its parameters replaced (eq. FloryParam)."""

    base: GelName = Field("ANB", description="preset ('ANB', 'HHT') or stored fitted gel whose "
                                             "parameters fill any left unset")
    omega: float | None = Field(None, gt=0.0, le=1.0e4, examples=[100.0],
                                description="Omega = Omega_p / Omega_f, dimensionless, 0 < Omega "
                                            "<= 1e4 (default: the preset's)")
    a0: float | None = Field(None, ge=-1.0e3, le=1.0e3, examples=[-12.947],
                             description="A0 in chi0 = A0 + B0 T, dimensionless, |A0| <= 1000")
    b0: float | None = Field(None, ge=-10.0, le=10.0, examples=[0.04496],
                             description="B0 in chi0 = A0 + B0 T, per K, |B0| <= 10")
    a1: float | None = Field(None, ge=-1.0e3, le=1.0e3, examples=[17.92],
                             description="A1 in chi1 = A1 + B1 T, dimensionless, |A1| <= 1000")
    b1: float | None = Field(None, ge=-10.0, le=10.0, examples=[-0.0569],
                             description="B1 in chi1 = A1 + B1 T, per K, |B1| <= 10")
    permeability: Literal["constant", "power"] | None = Field(
        None, description="permeability law: 'constant' (k = 1) or 'power' "
                          "(k = phi/(1-phi)^beta, eq. Permeability); default: the preset's")
    beta: float | None = Field(None, gt=0.0, lt=10.0, examples=[1.0],
                               description="exponent of the power law, 0 < beta < 10; "
                                           "required when permeability is 'power'")

    @model_validator(mode="after")
    def _beta_with_power(self) -> GelParameters:
        if self.permeability == "power" and self.beta is None:
            raise ValueError("beta is required when permeability is 'power' (0 < beta < 10)")
        if self.beta is not None and self.permeability != "power":
            raise ValueError("beta applies only with permeability 'power'")
        return self


def _gel_kind(value: Any) -> str:
    """Tag of a gel spec: a preset name (a string) or custom parameters (an object)."""
    return "preset" if isinstance(value, str) else "custom"


GelSpec = Annotated[
    Annotated[GelName, Tag("preset")] | Annotated[GelParameters, Tag("custom")],
    Discriminator(_gel_kind),
    Field(description="a preset name ('ANB' or 'HHT'), a stored fitted gel's name (thermogel "
                      "fit ... --save NAME) or custom parameters", examples=["ANB"]),
]


class PermeabilityOut(_Out):
    """The permeability law of a gel."""

    law: Literal["constant", "power"] = Field(description="'constant' (k = 1) or 'power'")
    beta: float = Field(description="power-law exponent, dimensionless (0 for 'constant')")


class GelOut(_Out):
    """A gel's parameters (eq. FloryParam)."""

    name: str = Field(description="preset name, or 'custom'")
    omega: float = Field(description="Omega = Omega_p / Omega_f, dimensionless, > 0")
    a0: float = Field(description="A0 in chi0 = A0 + B0 T, dimensionless")
    b0: float = Field(description="B0 in chi0 = A0 + B0 T, per K")
    a1: float = Field(description="A1 in chi1 = A1 + B1 T, dimensionless")
    b1: float = Field(description="B1 in chi1 = A1 + B1 T, per K")
    permeability: PermeabilityOut = Field(description="permeability law (eq. Permeability)")


class FoldOut(_Out):
    """A fold (volume-phase transition) of the equilibrium curve."""

    temperature: float = Field(description="fold temperature in K, 273.15-373.15")
    stretch: float = Field(description="isotropic stretch lambda at the fold, dimensionless, > 1")
    kind: Literal["shrink", "swell"] = Field(
        description="'shrink': heating past it loses the swollen branch; 'swell': cooling past "
                    "it loses the shrunken branch")


class GelPreset(_Out):
    """A preset gel with its fold temperatures."""

    gel: GelOut
    folds: list[FoldOut] = Field(description="folds in 273.15-373.15 K, ascending in T")


class GelsResponse(_Out):
    """Every preset gel."""

    gels: list[GelPreset] = Field(description="the presets (ANB, HHT)")
    fitted: list[dict[str, Any]] = Field(
        default_factory=list, description="the stored fitted gels (thermogel fit ... --save "
        "NAME): name, gel parameters, folds, every fitted parameter with its 95% interval, "
        "and the timescale a kinetics fit pinned (null: uncalibrated)")


# ----------------------------------------------------------------------------- physics

class EquilibriumRequest(RequestModel):
    """Every free-swelling equilibrium of a gel at one temperature (eq. EqlEqn)."""

    gel: GelSpec = "ANB"
    temperature: float = temperature_field("temperature", 305.0)

    model_config = ConfigDict(
        extra="forbid", json_schema_extra={"examples": [{"gel": "ANB", "temperature": 305.0}]})


class EquilibriumOut(_Out):
    """One free-swelling equilibrium."""

    temperature: float = Field(description="temperature in K")
    stretch: float = Field(description="isotropic stretch lambda = a / a_dry, dimensionless, > 1")
    porosity: float = Field(description="porosity phi = 1 - lambda^-3, dimensionless, 0-1")
    stable: bool = Field(description="true when linearly stable")


class EquilibriumResponse(_Out):
    """Equilibria at T (smallest stretch first) and the gel's folds."""

    gel: GelOut
    temperature: float = Field(description="temperature in K")
    equilibria: list[EquilibriumOut] = Field(
        description="every equilibrium (stable and unstable), smallest stretch first")
    folds: list[FoldOut] = Field(description="folds in 273.15-373.15 K, ascending in T")


class ClassifyRequest(RequestModel):
    """What an instant temperature jump T_start -> T_end does to a uniform bead."""

    gel: GelSpec = "ANB"
    t_start: float = temperature_field("start temperature", 302.0)
    t_end: float = temperature_field("end temperature", 308.0)
    branch: Branch | None = Field(
        None, description="start branch: 'swollen' or 'shrunken' (default: swollen when "
                          "heating, shrunken when cooling)")

    model_config = ConfigDict(extra="forbid", json_schema_extra={
        "examples": [{"gel": "ANB", "t_start": 302.0, "t_end": 308.0}]})


class ClassifyResponse(_Out):
    """The jump's class (sec. Comparison of results)."""

    t_start: float = Field(description="start temperature in K")
    t_end: float = Field(description="end temperature in K")
    branch: Branch = Field(description="start branch")
    start_stretch: float = Field(description="start stretch, dimensionless, > 1")
    final_stretch: float = Field(description="final equilibrium stretch, dimensionless, > 1")
    direction: Literal["swell", "shrink", "none"] = Field(description="what the bead does")
    behaviour: Literal["smooth", "front", "delayed_front", "spinodal"] = Field(
        description="'front': a sharp front forms at once; 'delayed_front': after a delay; "
                    "'smooth': no front; 'spinodal': spinodal decomposition")
    reason: str = Field(description="one sentence on why")


# ----------------------------------------------------------------------------- dosing

class ConstantsIn(RequestModel):
    """Constants of the timescale tau = eta Omega_p R^2 / (k0 k_B T_end) (eq. timescale, R the
    dry radius); unset fields keep the defaults (Omega_p consistent with the gel's Omega), or
    the paper's with ``paper``."""

    paper: bool = Field(
        False, description="start from the paper's constants (eta 1e-3 Pa s, Omega_p 3e-25 "
                           "m^3, k0 8e-20 m^2) instead of the default Omega_p = Omega Omega_f; "
                           "the fields given still override them")

    viscosity_pa_s: float | Literal["water"] | None = Field(
        None, examples=[0.001, "water"],
        description="fluid viscosity eta in Pa s, 0 < eta <= 10, or 'water' for the viscosity "
                    "of water at T_end (default 1e-3 Pa s)")
    polymer_volume_m3: float | None = Field(
        None, gt=0.0, le=1.0e-20, examples=[3.0e-25],
        description="polymer molecular volume Omega_p in m^3, 0 < Omega_p <= 1e-20 "
                    "(default Omega Omega_f, consistent with the gel's Omega: 3e-27 m^3 for "
                    "ANB; the paper's 3e-25 m^3)")
    permeability_m2: float | None = Field(
        None, gt=0.0, le=1.0e-10, examples=[8.0e-20],
        description="permeability scale k0 in m^2, 0 < k0 <= 1e-10 (default 8e-20 m^2; the "
                    "paper prints m^3)")
    k0_law: Literal["constant", "tokita-tanaka"] | None = Field(
        None, description="k0's temperature law, entering the envelope only (default "
                          "'constant'; 'tokita-tanaka': the network-water friction falling "
                          "by three decades toward the transition, Tokita & Tanaka 1991)")
    k0_reference_t_k: float | None = Field(
        None, ge=T_MIN, le=T_MAX, description=f"the temperature at which k0 is given, K, "
                                              f"{T_MIN}-{T_MAX} (default 298.15)")
    mesh_length_nm: float | None = Field(
        None, gt=0.0, le=1.0e3, examples=[4.0],
        description="the gel's dry mesh (interfacial) length xi_dry in nm, 0 < xi <= 1000: "
                    "the truth's interfacial length is xi_dry / a_d (default 4 nm, "
                    "docs/interfacial.md sec. 1)")
    mesh_length_range_nm: list[float] | None = Field(
        None, min_length=2, max_length=2, examples=[[2.0, 8.0]],
        description="plausible range [lo, hi] of mesh_length_nm in nm, over which the "
                    "answer's interfacial-length uncertainty is measured (default [2, 8])")

    @field_validator("viscosity_pa_s")
    @classmethod
    def _viscosity_range(cls, v: float | str | None) -> float | str | None:
        if isinstance(v, float) and not (0.0 < v <= 10.0):
            raise ValueError("viscosity_pa_s must satisfy 0 < eta <= 10 Pa s, or be 'water'")
        return v


class SizeDistributionIn(RequestModel):
    """A batch of beads (dosing.population.sizes; docs/batch.md): a lognormal by mean_um
    and cv (or median_um and gsd), a normal by mean_um and cv (or sd_um; truncated to > 1 %
    of the mean), or a measured table of sizes_um (with counts or not); number- or
    volume-weighted; dry or swollen (at T_start) sizes; radii or diameters.  Without a
    size, the request's dry_radius_um (swollen_radius_um) is the number-weighted mean."""

    kind: Literal["lognormal", "normal", "table"] = Field(
        "lognormal", description="the law: 'lognormal' (default), 'normal' or 'table'")
    mean_um: float | None = Field(None, gt=0.0, le=1.0e6, examples=[50.0],
                                  description="mean size in um (lognormal, normal)")
    cv: float | None = Field(None, ge=0.0, le=2.0, examples=[0.2],
                             description="coefficient of variation, 0 <= CV <= 2")
    median_um: float | None = Field(None, gt=0.0, le=1.0e6,
                                    description="median size in um (lognormal, with gsd)")
    gsd: float | None = Field(None, ge=1.0, le=10.0,
                              description="geometric standard deviation >= 1 (lognormal)")
    sd_um: float | None = Field(None, ge=0.0, le=1.0e6,
                                description="standard deviation in um (normal)")
    sizes_um: list[float] | None = Field(
        None, min_length=1, max_length=100_000,
        description="measured sizes in um, > 0 each, 1-100000 rows (table)")
    counts: list[float] | None = Field(
        None, min_length=1, max_length=100_000,
        description="beads (or, volume-weighted, volume fractions) per size, >= 0 (table; "
                    "default one per row)")
    weighting: Literal["number", "volume"] = Field(
        "number", description="'number' (default) or 'volume'-weighted sizes")
    state: Literal["dry", "swollen"] = Field(
        "dry", description="'dry' (default) sizes or 'swollen' at T_start")
    measure: Literal["radius", "diameter"] = Field(
        "radius", description="'radius' (default) or 'diameter'")


class QuadratureOut(_Out):
    """The quadrature over sizes of a batch's answer."""

    rule: str = Field(description="the rule, in words")
    nodes: int = Field(description="the nodes needed (in all)")
    error: float = Field(description="relative change of the dose time from the previous "
                                     "rung (0: an exact sum)")
    converged: bool = Field(description="whether the change fell below the tolerance")
    table: list[tuple[int, float]] = Field(description="(nodes, dose time) per rung")


class BatchOut(_Out):
    """A batch's dose (dosing.population.front.BatchAnswer): times in the reference (number-weighted
    mean) bead's tau and in seconds."""

    distribution: dict[str, Any] = Field(description="the size distribution as resolved")
    description: str = Field(description="the distribution in words")
    model: str = Field(description="the model of the one dimensionless trajectory")
    dose_fraction: float = Field(description="dose / the batch's stored fluid")
    reference_dry_radius_um: float = Field(
        description="the number-weighted mean dry radius (the reference bead), um")
    time: float = Field(description="the batch's dose time, dimensionless (reference tau)")
    seconds: float | None = Field(None, description="the batch's dose time in s")
    timescale_seconds: float | None = Field(None, description="the reference bead's tau, s")
    mean_bead_time: float = Field(description="the reference bead's own dose time")
    mean_bead_seconds: float | None = Field(None, description="... in s")
    delay: float = Field(description="batch time / reference bead's time - 1")
    fraction_delivered: float = Field(
        description="fraction of the beads (by number) that have delivered their own dose "
                    "by the batch's dose time")
    percentile_radii_um: list[float] = Field(description="10th, 50th, 90th percentile dry "
                                                         "radius (by number), um")
    percentile_times: list[float] = Field(description="their own dose times, dimensionless")
    percentile_seconds: list[float] | None = Field(None, description="... in s")
    quadrature: QuadratureOut = Field(description="the quadrature over sizes")
    note: str = Field(description="the batch's answer in words")


class DrugIn(RequestModel):
    """A drug dissolved in the pore fluid: diffusion D0 f(phi), partition, release medium,
    load.  Give ``diffusivity_cm2_s`` or ``solute_radius_nm`` (Stokes-Einstein); neither
    means D0 = 0 (carried by the fluid only)."""

    model_config = ConfigDict(json_schema_extra={
        "examples": [{"diffusivity_cm2_s": 1e-7, "mesh_size_nm": 23.0, "load_ug": 1.0}]})

    diffusivity_cm2_s: float | None = Field(
        None, ge=0.0, le=1e-3, examples=[1e-7],
        description="the drug's diffusivity in water D0 in cm^2/s, 0 <= D0 <= 1e-3 (0: no "
                    "diffusion, the drug leaves with the fluid only)")
    solute_radius_nm: float | None = Field(
        None, gt=0.0, le=1e4, description="Stokes-Einstein radius in nm, 0 < r <= 1e4 (gives "
                                          "D0 when diffusivity_cm2_s is not set)")
    hindrance: Literal["free-volume", "ogston", "amsden", "none"] = Field(
        "free-volume", description="hindrance law D = D0 f: 'free-volume' (Lustig & "
        "Peppas 1988: (1 - r_s/xi) exp(-Y v/(1-v)), v the polymer fraction), 'ogston' "
        "(Ogston, Preston & Wells 1973: exp(-sqrt(v) (1 + r_s/r_f))), 'amsden' (1998: "
        "exp(-pi ((r_s + r_f)/(xi + 2 r_f))^2)) or 'none' (no hindrance, no sieving)")
    mesh_size_nm: float | None = Field(
        None, gt=0.0, le=1e4, description="mesh size xi of the swollen gel at t_start in nm, "
        "overriding for the drug the gel's dry mesh (constants.mesh_length_nm, the "
        "interfacial length's); unset: the gel's mesh, affine in the local stretch")
    reference_temperature_k: float = Field(
        REFERENCE_TEMPERATURE_K, ge=T_MIN, le=T_MAX,
        description="temperature at which diffusivity_cm2_s is "
        "given, K (default 25 degC); carried to t_end by Stokes-Einstein with water's "
        "viscosity")
    sieving: bool = Field(True, description="convective sieving of the expelled fluid's "
                                            "solute by the local mesh (Dechadilok & Deen 2006)")
    partition_law: Literal["constant", "ogston"] | None = Field(
        None, description="steric partition K_s(phi) multiplying partition: Ogston 1958 "
        "exp(-v (1 + r_s/r_f)^2) or constant; unset: Ogston's with a fibre radius")
    mesh_stretch: Literal["smallest", "volume"] = Field(
        "smallest", description="which stretch sets the local mesh: the smallest principal "
        "stretch (default) or J^(1/3)")
    fiber_radius_nm: float | None = Field(
        None, gt=0.0, le=1e3, description="polymer fibre radius r_f in nm (Ogston's law)")
    free_volume_y: float = Field(1.0, gt=0.0, le=100.0,
                                 description="Y of the free-volume law, 0 < Y <= 100 (1)")
    partition: float = Field(1.0, ge=1e-6, le=1e6, description=(
        "equilibrium partition K = c_pore / c_medium, 1e-6 <= K <= 1e6 (> 0; default 1)"))
    release_volume_ul: float | None = Field(
        None, gt=0.0, le=1e9, description="volume of a well-mixed release medium in uL, larger "
        "than the swollen bead (needs a bead size); unset: a perfect sink")
    load_ug: float | None = Field(None, gt=0.0, le=1e9,
                                  description="drug loaded per bead in ug, 0 < m <= 1e9")
    loading_concentration_ug_per_ul: float | None = Field(
        None, gt=0.0, le=1e6, description="drug concentration of the loading solution in "
        "ug/uL (the pore fluid holds partition x it; needs a bead size)")
    wait: float | None = Field(None, ge=REST_RANGE[0], le=DRUG_STEP_MAX, description=(
        "time in the medium at t_start before the first heating, dimensionless (units of tau; "
        f"default 0; {REST_RANGE[0]:g}-{DRUG_STEP_MAX:g}, a drug run's longest step): the "
        "bead leaks by diffusion meanwhile"))
    wait_seconds: float | None = Field(None, ge=REST_RANGE[0], description=(
        "the wait in seconds (needs a bead size), within the wait's range once in tau"))

    @model_validator(mode="after")
    def _one_load(self) -> DrugIn:
        if self.load_ug is not None and self.loading_concentration_ug_per_ul is not None:
            raise ValueError("give load_ug or loading_concentration_ug_per_ul, not both")
        if self.wait is not None and self.wait_seconds is not None:
            raise ValueError("give wait or wait_seconds, not both")
        return self

    def model_kwargs(self) -> dict[str, Any]:
        """The fields of dosing.payload.drug.DrugModel (the wait excluded)."""
        return self.model_dump(exclude={"wait", "wait_seconds"}, exclude_none=True)


class DoseTimeRequest(RequestModel):
    """How long to hold a bead at T_end to release a dose.

    Give exactly one dose (``dose_fraction``, ``dose_volume_ul``, or ``drug_mass_ug`` with
    ``concentration_ug_per_ul``) and at most one bead size (``dry_radius_um`` or
    ``swollen_radius_um``; none gives dimensionless answers only).  The stored fluid is the
    pore volume of the swollen bead, (4 pi / 3)(a0^3 - 1) dry volumes.
    """

    gel: GelSpec = "ANB"
    t_start: float = temperature_field("start (loading) temperature", 302.0)
    t_end: float | None = Field(  # required unless a protocol is given
        None, ge=T_MIN, le=T_MAX, examples=[308.0],
        description=f"end (actuation) temperature in K; liquid water, {T_MIN}-{T_MAX} K "
                    "(required, unless a protocol is given in its place)")
    dose_fraction: float | None = Field(
        None, gt=0.0, le=1.0, examples=[0.8],
        description="dose as a fraction of the stored fluid, dimensionless, 0 < f <= 1 "
                    "(reachable doses stop at the final equilibrium's volume)")
    dose_volume_ul: float | None = Field(
        None, gt=0.0, le=1.0e6, examples=[0.05],
        description="dose as a fluid volume in microlitres, 0 < V <= 1e6 (needs a bead size)")
    drug_mass_ug: float | None = Field(
        None, gt=0.0, le=1.0e9, examples=[0.1],
        description="dose as a drug mass in micrograms, 0 < m <= 1e9 (needs a bead size and "
                    "concentration_ug_per_ul)")
    concentration_ug_per_ul: float | None = Field(
        None, gt=0.0, le=1.0e6, examples=[2.0],
        description="drug concentration of the loaded fluid in ug/uL, 0 < c <= 1e6")
    dry_radius_um: float | None = Field(
        None, ge=MIN_RADIUS_UM, le=1.0e5, examples=[50.0],
        description="dry bead radius in micrometres, 1e-3 <= r <= 1e5")
    swollen_radius_um: float | None = Field(
        None, ge=MIN_RADIUS_UM, le=1.0e6, examples=[114.6],
        description="bead radius swollen at T_start in micrometres, 1e-3 <= r <= 1e6")
    branch: Branch | None = Field(
        None, description="start branch at T_start (default: swollen)")
    constants: ConstantsIn | None = Field(
        None, description="timescale constants (default: the paper's values)")
    validation_method: Method = method_field()
    interfacial_length: float | None = interfacial_length_field()
    drug: DrugIn | None = Field(None, description="a drug in the pore fluid: doses are drug")
    size_distribution: SizeDistributionIn | None = Field(
        None, description="a batch of beads: the answer adds 'batch' (its dose time, the "
                          "fraction of beads delivered, the 10th-90th percentile bead; "
                          "docs/batch.md); dose_fraction only. With a drug: the batch's "
                          "drug dose into medium_volume_ml shared by bead_count beads "
                          "(a perfect sink without them; a stored job)")
    medium_volume_ml: float | str | None = Field(
        None, examples=[10.0], description="with a drug and a size_distribution: the release "
        f"medium the batch shares, mL ({MEDIUM_VOLUME_ML_RANGE[0]:g}-"
        f"{MEDIUM_VOLUME_ML_RANGE[1]:g}; or with a unit, '250 uL'); null: a perfect sink")
    bead_count: float | None = Field(
        None, ge=BEAD_COUNT_RANGE[0], le=BEAD_COUNT_RANGE[1], examples=[1e6],
        description="with medium_volume_ml: the number of beads in the batch")
    validate_full: bool = Field(
        False, alias="validate",
        description="also queue a full-solver validation of this dose (poll "
                    "/v1/validations/{id})")
    protocol: list[str | dict[str, Any]] | None = Field(
        None, min_length=1, max_length=1000,
        examples=[["Heat to 308 K at 5 K/min"]],
        description="a heating protocol in place of t_end (docs/heating.md): steps as text "
                    "('Heat to 308 K at 5 K/min', 'Hold at 308 K until 30 % released', "
                    "'Rest at 302 K for 10 min', 'Bath at 308 K with a time constant of 30 s') "
                    "or structured ({'step': 'heat', 'to': '308 K', 'rate': '5 K/min'}; a "
                    "measured trace as {'step': 'trace', 'csv': 'time (s),T (degC)\\n...'}); "
                    "the answer is the time from the protocol's start (full solver: 202 "
                    "until its runs are cached)")

    model_config = ConfigDict(extra="forbid", populate_by_name=True, json_schema_extra={
        "examples": [{"gel": "ANB", "t_start": 302.0, "t_end": 308.0, "dose_fraction": 0.8,
                      "dry_radius_um": 50.0}]})

    _ell = field_validator("interfacial_length")(check_interfacial_length)
    _steps = field_validator("protocol")(check_finite_steps)

    @model_validator(mode="after")
    def _heating(self) -> DoseTimeRequest:
        if (self.t_end is None) == (self.protocol is None):
            raise ValueError("give exactly one of t_end and protocol")
        return self


class RunCheck(_Out):
    """The full solver's answer in one validation run."""

    grid: str | None = Field(None, description="'eulerian', 'lagrangian' or 'moving'")
    n: int | None = Field(None, description="grid cells N")
    interfacial_length: float | None = Field(None, description="ell of this run, dry radii")
    role: Literal["truth", "check", "ell_range", "model_form"] | None = Field(
        None, description="direct truth only: 'truth' (the answer's run), 'check' (n / 2 "
                          "cells), 'ell_range' (an end of the mesh length's range) or "
                          "'model_form' (the ell = 0 lattice's delayed transition)")
    nucleation_time: float | None = Field(
        None, description="when the front nucleated at the edge (regularized runs; null: "
                          "none)")
    scenario_key: str | None = Field(None, description="cache key of this run")
    time: float | None = Field(None, description="full solver's actuation time, dimensionless")
    wall_seconds: float | None = Field(None, description="wall time of the run, s")
    front_volume_error: float | None = Field(
        None, description="relative error of the volume this run expels by the front "
                          "model's time, (V_full(t_front) - V_dose) / V_dose")
    warning: str | None = Field(None, description="what the run reports (spinodal collapse)")
    error: str | None = Field(None, description="why this run failed, if it did")


class LimitOut(_Out):
    """The regularized model's dose time extrapolated to ell -> 0."""

    time: float = Field(description="the limit, dimensionless")
    error: float = Field(description="its absolute error bound (1.25 x the extrapolation)")
    order: float | None = Field(None, description="observed order in ell (null: none trusted)")
    method: str = Field(description="how the limit was taken, in words")


class ValidationReport(_Out):
    """The truth's time for the same dose, every run behind it, and the front model's
    errors in time and in volume."""

    model: Literal["regularized", "paper"] | None = Field(
        None, description="'regularized' (limit ell -> 0 of the model with interfacial energy) "
                          "or 'paper' (no interfacial energy)")
    method: Literal["direct", "ladder", "paper"] | None = Field(
        None, description="'direct' (the regularized model at ell itself, moving grid), "
                          "'ladder' (its limit ell -> 0 from three runs) or 'paper'")
    interfacial_length: float | None = Field(
        None, description="ell of the direct truth, or the coarsest ell of the ladder, dry "
                          "radii (0: the paper's model)")
    uncertainty: UncertaintyOut | None = Field(
        None, description="direct truth only: its uncertainty in three parts")
    time: float | None = Field(None, description="the truth's actuation time, dimensionless "
                                                 "(units of tau)")
    error: float | None = Field(
        None, description="the truth's own relative uncertainty: the direct run's numerical "
                          "bound, the limit's error bound, or the paper's model's grid "
                          "spread")
    settings: dict[str, Any] | None = Field(None, description="full-solver settings (grid, N, "
                                                              "integrator, rtol, ell)")
    runs: list[RunCheck] = Field(default_factory=list, description=(
        "the runs: direct (the truth, its check at n / 2, the ell range's ends, the ell = 0 "
        "lattice at N = 200/400/800), ell, ell/2, ell/4 (ladder) or the two grids (paper)"))
    limit: LimitOut | None = Field(None, description="the extrapolation (regularized only)")
    grid_spread: float | None = Field(
        None, description="(max - min) / truth of the grids' times (paper's model only): its "
                          "own uncertainty where a sharp front forms")
    front_time: float | None = Field(None, description="front model's time, dimensionless "
                                                       "(null where it does not apply)")
    front_time_error: float | None = Field(
        None, description="front model's relative time error against the truth")
    front_volume_error: float | None = Field(
        None, description="front model's relative volume error against the truth's run")


class PendingResponse(_Out):
    """HTTP 202: the request needs full-solver work not yet done; poll ``validation_url``
    (a dose: once that validation is done, the same request is answered at once)."""

    status: Literal["pending"] = Field("pending", description="always 'pending'")
    validation_id: str = Field(description="id to poll at /v1/validations/{id}")
    validation_url: str = Field(description="path of the validation to poll")
    note: str = Field(description="what is queued and what to do next, in words")
    hold: list[dict[str, Any]] | None = Field(
        None, description="a schedule's hold reading while its protocol check runs: a rough "
                          "reading (one continuous heating, doses read off cumulatively)")


class AnswerOut(EnvelopeFields):
    """What every dose and schedule answer states, fluid or drug: the truth behind it (its
    runs' model and interfacial length, in words and in numbers), tau and caveats."""

    status: Literal["answered"] = Field("answered", description="always 'answered'")
    truth: str = Field(description="what the answer is checked against (the model of its "
                                   "full-solver runs, their interfacial length and bead "
                                   "size), in words")
    interfacial_length: float = Field(
        description="interfacial length ell of the truth's runs, dry radii (0: the paper's "
                    "model; by default the bead's own xi_dry / a_d)")
    timescale_seconds: float | None = Field(
        None, description="tau in s (eq. timescale; under a protocol at its hottest "
                          "temperature)")
    note: str = Field(description="caveats, in words")


class StatedOut(AnswerOut):
    """An answer that states the bead size its truth assumes and the truth's uncertainty
    (every dose; a drug schedule)."""

    bead_dry_radius_um: float | None = Field(
        None, description="the dry bead radius the truth's ell = xi_dry / a_d assumes, um "
                          "(null: no bead size, ell stands for the limit ell -> 0)")
    uncertainty: UncertaintyOut | None = Field(
        None, description="the truth's uncertainty in three parts (numerical, interfacial "
                          "length range, model form) where measured: a validated direct "
                          "dose; a drug dose (numerical: its drug run at n / 2 cells); a "
                          "simulated drug schedule (numerical: the largest change of a "
                          "delivered dose on n / 2 cells; the other parts null, saying how "
                          "to measure them)")


class DoseOut(StatedOut):
    """A dose's answer, fluid or drug: when the dose is out."""

    time: float = Field(description="actuation time, dimensionless (units of tau), >= 0 "
                                    "(under a protocol: from its start)")
    seconds: float | None = Field(None, description="the time in s (with a bead size)")
    dose_fraction: float = Field(description="the dose, 0-1: a fraction of the stored fluid "
                                             "(a drug answer: of the loaded drug)")


class FluidDoseOut(DoseOut):
    """A fluid dose's bead: its radii, the volumes expelled and stored, the run's key."""

    start_radius: float = Field(description="radius at T_start, dry radii")
    final_radius: float = Field(description="radius after the dose, dry radii")
    final_radius_um: float | None = Field(None, description="radius after the dose in um")
    expelled_volume: float = Field(
        description="the dose: expelled fluid volume in dry-radius^3 units")
    expelled_volume_ul: float | None = Field(None, description="expelled volume in uL")
    stored_volume_ul: float | None = Field(None, description="stored fluid in uL")
    error_explanation: str = Field(description="the error estimate in words")
    scenario_key: str = Field(description="key of the (truth run's) dimensionless scenario")


class DoseTimeResponse(FluidDoseOut):
    """HTTP 200: the actuation time for a dose (the front model, or the full solver's
    cached runs).  A dose needing a new full-solver run is a :class:`PendingResponse`."""

    model: Literal["front-sharp", "front", "full"] = Field(
        description="'front-sharp' (reduced front model with the sharp-interface front "
                    "condition, milliseconds), 'front' (the paper's reduced model, with "
                    "interfacial_length 0) or 'full' (PDE solver)")
    method: Literal["direct", "ladder", "paper"] = Field(
        "direct", description="how the truth is computed: 'direct' (the regularized model "
                              "at this ell on the moving grid), 'ladder' or 'paper'")
    behaviour: str = Field(
        description="the jump's class: 'front', 'delayed_front', 'smooth', 'spinodal'")
    timescale_formula: str = Field(description="how tau was computed")
    timescale_uncertainty: dict[str, Any] | None = Field(
        None, description="the seconds' uncertainty: uncalibrated, the range over the "
                          "timescale constants (one to two orders of magnitude) and how to "
                          "pin it (a kinetics fit); calibrated, the kinetics fit's interval")
    parameter_interval: dict[str, Any] | None = Field(
        None, description="a stored fitted gel's 95% interval of the time from its fit")
    stored_volume: float = Field(
        description="stored fluid (4 pi/3)(a0^3 - 1) in dry-radius^3 units")
    error_estimate: float = Field(
        description="estimated relative error of the time, dimensionless")
    validation: ValidationReport | None = Field(
        None, description="the full solver's verdict when already known")
    validation_id: str | None = Field(
        None, description="with validate: id of the queued validation, poll "
                          "/v1/validations/{id}")
    validation_url: str | None = Field(None, description="with validate: path to poll")
    batch: BatchOut | None = Field(
        None, description="with a size_distribution: the batch's dose (the fields above are "
                          "its number-weighted mean bead's)")


class UntilStepOut(_Out):
    """When an until-step of a protocol ended (tau and seconds from the protocol's start)."""

    step: int = Field(description="index of the step in the protocol")
    text: str = Field(description="the step as text")
    start: float = Field(description="start, tau")
    end: float = Field(description="end (the condition met), tau")
    start_seconds: float | None = Field(None, description="start in s")
    end_seconds: float | None = Field(None, description="end in s")


class ProtocolDoseResponse(FluidDoseOut):
    """HTTP 200: the time from a heating protocol's start at which the dose is out (the
    reduced model for slow heating inside its measured region, else the full solver at the
    truth's settings; docs/heating.md)."""

    model: Literal["full", "front-slow-sharp", "front-slow-sharp+full"] = Field(
        description="'front-slow-sharp': the reduced model for slow heating (inside its "
                    "region); 'full': the PDE solver; 'front-slow-sharp+full': a batch "
                    "whose beads inside the region ran on the reduced model and the others "
                    "on the PDE solver (its batch.uncertainty.nodes says which)")
    protocol: list[str] = Field(description="the protocol's steps as text")
    protocol_steps: list[dict[str, Any]] = Field(description="the steps, structured")
    t_start: float = Field(description="start temperature, K")
    reference_temperature: float = Field(
        description="tau's reference temperature: the protocol's hottest, K")
    reference: str = Field(description="how seconds become tau, in words")
    timescale_formula: str | None = Field(None, description="how tau was computed")
    program: str = Field(description="how the protocol ran in the solver, in words")
    temperature_at_dose: float = Field(description="the protocol's temperature then, K")
    until_steps: list[UntilStepOut] = Field(description="when each until-step ended")
    error_estimate: float | None = Field(
        None, description="relative numerical error (truth vs its n/2 check run)")
    validation: dict[str, Any] | None = Field(None, description="the runs' report")
    curve: dict[str, list[float]] = Field(
        description="time (tau), seconds, temperature_k and released_fraction on one axis")
    model_reason: str = Field("", description="which model answered and why, in words")


class ValidationResponse(_Out):
    """A full-solver job: a dose validation or a schedule check.  When done, ``result`` is a
    :class:`ValidationReport` (dose) or a :class:`ScheduleResponse` (schedule)."""

    id: str = Field(description="validation id")
    kind: Literal["dose", "schedule", "drug-dose", "batch-schedule"] = Field(
        "dose", description="what was checked ('drug-dose': a drug dose's runs; "
                        "'batch-schedule': a batch's schedule)")
    status: Literal["pending", "running", "done", "failed"] = Field(description="its state")
    result: dict[str, Any] | None = Field(
        None, description="when done: the truth's time for the dose, every run behind it and "
                          "the front model's errors (dose), or the schedule (schedule)")
    error: str | None = Field(None, description="when failed: why")


Fraction = Annotated[float, Field(gt=0.0, le=1.0)]
# a time at T_start (solver.limits.REST_RANGE, tau; in seconds bounded after the conversion
# by dosing.request.at_start, the one parser, which names the field and the range in s)
Rest = Annotated[float, Field(ge=REST_RANGE[0], le=REST_RANGE[1])]
RestSeconds = Annotated[float, Field(ge=REST_RANGE[0])]


# the planner's defaults, written once (dosing.request.ScheduleRequest): every way in agrees
_SCHEDULE_DEFAULTS = {f.name: f.default for f in dataclasses.fields(PlannerSchedule)}


class ScheduleRequest(RequestModel):
    """Several doses released one after another, resting at T_start between heatings.

    Answered at once under the hold assumption (the paper's reading: one continuous heating,
    doses read off cumulatively).  ``check_protocol`` simulates the real heat/rest protocol
    with the full solver and ``correct`` shoots for actuation times meeting every dose
    within ``tolerance``: both run as a job (HTTP 202, poll /v1/validations/{id}).
    """

    gel: GelSpec = "ANB"
    t_start: float = temperature_field("start (rest) temperature", 302.0)
    t_end: float | None = Field(  # 308 K unless a protocol is given in its place
        None, ge=T_MIN, le=T_MAX, examples=[308.0],
        description=f"end (actuation) temperature in K; liquid water, {T_MIN}-{T_MAX} K "
                    "(default 308 K; absent when a protocol is given)")
    protocol: list[str | dict[str, Any]] | None = Field(
        None, min_length=1, max_length=1000, examples=[["Heat to 308 K at 5 K/min"]],
        description="a heating protocol in place of t_end (docs/heating.md): every heating "
                    "of the schedule follows its steps from t_start, then holds at its last "
                    "temperature until the heating's actuation time ends (no until-steps)")
    doses: list[Fraction] = Field(
        min_length=1, max_length=20, examples=[[0.3, 0.3, 0.3]],
        description="1-20 doses, each a fraction of the stored fluid (0 < f <= 1); their sum "
                    "must stay below what the gel can expel at T_end")
    rests: list[Rest] | None = Field(
        None, max_length=19, examples=[[0.5, 0.5]],
        description="rests at T_start between consecutive doses (one fewer than doses), "
                    f"dimensionless (units of tau), {REST_RANGE[0]:g}-{REST_RANGE[1]:g} each "
                    f"(with a drug: up to {DRUG_STEP_MAX:g})")
    rests_seconds: list[RestSeconds] | None = Field(
        None, max_length=19, description="the rests in seconds instead (needs a bead size), "
                                         "each within the rests' range once in tau")
    dry_radius_um: float | None = Field(
        None, ge=MIN_RADIUS_UM, le=1.0e5, examples=[50.0],
        description="dry bead radius in micrometres, 1e-3 <= r <= 1e5")
    swollen_radius_um: float | None = Field(
        None, ge=MIN_RADIUS_UM, le=1.0e6,
        description="bead radius swollen at T_start in micrometres, 1e-3 <= r <= 1e6")
    branch: Branch | None = Field(None, description="start branch at T_start (default swollen)")
    constants: ConstantsIn | None = Field(None, description="timescale constants")
    check_protocol: bool = Field(
        _SCHEDULE_DEFAULTS["check_protocol"],
        description="simulate the heat/rest protocol with the full solver (a job; on by "
                    "default everywhere: the hold reading alone is rough)")
    correct: bool = Field(
        _SCHEDULE_DEFAULTS["correct"],
        description="shoot on the full solver for times meeting every dose (a job; on by "
                    "default everywhere)")
    tolerance: float = Field(0.01, gt=0.0, le=0.2,
                             description="relative tolerance of the corrected doses, 0-0.2")
    validation_method: Method = method_field()
    interfacial_length: float | None = interfacial_length_field()
    drug: DrugIn | None = Field(None, description="a drug in the pore fluid: doses are drug")
    size_distribution: SizeDistributionIn | None = Field(
        None, description="a batch of beads (fluid doses only; docs/batch.md): the actuation "
                          "times meet each dose of the batch's stored fluid, every size its "
                          "own full-solver run (a stored job; dosing.population.cycles); "
                          "dry_radius_um is the batch's number-weighted mean")

    _ell = field_validator("interfacial_length")(check_interfacial_length)
    _steps = field_validator("protocol")(check_finite_steps)

    model_config = ConfigDict(extra="forbid", json_schema_extra={"examples": [
        {"gel": "ANB", "t_start": 302.0, "t_end": 308.0, "dry_radius_um": 50.0,
         "doses": [0.3, 0.3, 0.3], "rests": [0.5, 0.5]}]})

    @model_validator(mode="after")
    def _heating(self) -> ScheduleRequest:
        if self.protocol is None and self.t_end is None:
            self.t_end = 308.0  # the documented default
        return self


class EventOut(_Out):
    """One step of a schedule as a lab runs it (dosing.question.events)."""

    step: int = Field(description="step number, 1 = first")
    kind: Literal["heat", "rest", "hold"] = Field(
        description="heat (a heating: a jump to T_end or the protocol's steps), rest (at "
                    "T_start between heatings), hold (a drug's wait at T_start before the "
                    "first heating)")
    start_s: float | None = Field(None, description="start on the protocol's clock, s (null "
                                                    "without a bead size)")
    duration_s: float | None = Field(None, description="duration, s (null without a bead "
                                                       "size)")
    temperature_K: float = Field(description="set temperature, K (a protocol heating: at "
                                             "its end)")
    dose_fraction: float | None = Field(
        None, description="what the step delivers: a fraction of the stored fluid (a drug: "
                          "of the load; a drug's rest or wait: what leaks)")
    released_fraction: float = Field(description="cumulative release at the step's end")
    amount_ul: float | None = Field(None, description="fluid the step delivers, uL")
    amount_ug: float | None = Field(None, description="drug the step delivers, ug")
    target_fraction: float | None = Field(None, description="the dose asked of a heating")
    dose_error: float | None = Field(
        None, description="delivered / asked - 1 on the full solver (the corrected reading: "
                          "the shooting residual); null for the hold reading")
    uptake_fraction: float | None = Field(
        None, description="fluid a rest takes back up, a fraction of the stored fluid")
    heating: int = Field(description="heating number (0: not a heating)")
    start_tau: float = Field(description="start, units of tau of the reference bead")
    duration_tau: float = Field(description="duration, units of tau of the reference bead")
    program: str | None = Field(None, description="a protocol heating's steps cut at its "
                                                  "time, in the step grammar's words")
    reading: Literal["corrected", "checked", "hold"] = Field(
        description="corrected (shot on the full solver), checked (the hold times as the "
                    "full solver runs them) or hold (one continuous heating)")
    rough: bool = Field(description="true for the hold reading (the check was off)")


EVENTS_DESCRIPTION = ("the schedule as a bath controller or a lab notebook takes it: one row "
                      "per step (heat, rest, a drug's wait), the corrected times when "
                      "corrected, else the checked hold times, else the hold reading "
                      "(rough)")


class ScheduleOut(AnswerOut):
    """A schedule's answer, fluid or drug: its actuation times under each reading."""

    events: list[EventOut] = Field(default_factory=list, description=EVENTS_DESCRIPTION)

    model: str = Field(description="which model(s) gave the hold times (a drug schedule: "
                                   "what answered)")
    doses: list[float] = Field(description="the doses, fractions of the stored fluid (a drug "
                                           "schedule: of the loaded drug)")
    rests: list[float] = Field(description="rests at T_start between doses, dimensionless "
                                           "(units of tau)")
    hold: list[dict[str, Any]] = Field(
        description="per dose under the hold assumption (one continuous heating, doses read "
                    "off cumulatively): start, end and actuation_time (dimensionless), "
                    "actuation_seconds, error_estimate (a drug schedule: null, and dose_ug)")
    protocol_check: dict[str, Any] | None = Field(
        None, description="the hold times simulated as heat/rest steps: delivered_fractions, "
                          "relative_errors, rest_uptake_fractions (a drug schedule: the drug "
                          "per dose and how it came out, the leak per rest)")
    corrected: dict[str, Any] | None = Field(
        None, description="actuation times meeting every dose within the tolerance")


class BatchScheduleResponse(EnvelopeFields):
    """A batch's schedule (dosing.population.cycles.BatchScheduleAnswer): actuation times in
    the reference (number-weighted mean) bead's tau and seconds whose summed release meets
    each dose of the batch's stored fluid; the size nodes run and the quadrature."""

    batch: Literal[True] = Field(True, description="always true: a batch's schedule")
    events: list[EventOut] = Field(default_factory=list, description=EVENTS_DESCRIPTION)
    model: str = Field(description="which model ran each size ('full-solver-per-size')")
    description: str = Field(description="the batch in words")
    distribution: dict[str, Any] = Field(description="the size distribution as resolved")
    doses: list[float] = Field(description="the doses, fractions of the batch's stored fluid")
    rests: list[float] = Field(description="the rests, in the reference bead's tau")
    reference_dry_radius_um: float = Field(description="the number-weighted mean dry radius")
    timescale_seconds: float = Field(description="the reference bead's tau in s")
    nodes: list[dict[str, Any]] = Field(
        description="per size node: dry_radius_um, volume_weight, rho = (R / R_ref)^2, "
                    "tau_seconds, interfacial_length")
    hold: list[dict[str, Any]] = Field(description="the hold reading the shooting started from")
    hold_model: str = Field(description="how the hold reading was found")
    protocol_check: dict[str, Any] | None = Field(
        None, description="the hold times run on every node: the batch's delivered fractions")
    corrected: dict[str, Any] | None = Field(
        None, description="actuation_times, actuation_seconds, delivered_fractions (on the "
                          "check rule), relative_errors, node_delivered_fractions, runs, met")
    quadrature: QuadratureOut = Field(description="the rule over sizes, its nodes and error "
                                                  "(table: nodes, the last dose delivered)")
    uncertainty: dict[str, UncertaintyPart] = Field(
        description="numerical, quadrature, interfacial_length_range, model_form")
    truth: str = Field(description="the runs' model, in words")
    note: str = Field(description="the answer in words")


class ScheduleResponse(ScheduleOut):
    """HTTP 200: a schedule's actuation times under each reading, with the delivered
    volumes.  A schedule needing the full solver is a :class:`PendingResponse` (a job)."""

    start_radius: float = Field(description="radius at T_start, dry radii")
    stored_volume: float = Field(description="stored fluid, dry-radius^3 units")
    stored_volume_ul: float | None = Field(None, description="stored fluid in uL")
    timescale_formula: str = Field(description="how tau was computed")
    scenario_key: str = Field(description="key of the dimensionless scenario")
    method: Literal["direct", "ladder", "paper"] = Field(
        "direct", description="how the truth is computed: 'direct', 'ladder' or 'paper'")


# the drug answers: the fluid answers' fields (DoseOut, ScheduleOut) and what a drug adds
class DrugOut(_Out):
    """What every drug answer adds (dosing.payload.release.DrugCase): the load, the wait before
    the first heating, and how fast the bead leaks at T_start."""

    drug: Literal[True] = Field(True, description="always true: a drug answer")
    load_ug: float | None = Field(None, description="drug loaded per bead in ug")
    wait: float = Field(description="time at t_start before the first heating, units of tau")
    leak_time_10pct: float = Field(
        description="time at t_start in which 10 % of the load leaks, units of tau")
    effective_diffusivity_cm2_s: float = Field(
        description="hindered diffusivity D0 f(phi) in the start state, cm^2/s")


class DrugDoseResponse(DrugOut, DoseOut):
    """HTTP 200 for a dose with a ``drug``: the actuation time for the drug dose, the leak
    before heating and how the drug came out."""

    model: str = Field(description="what answered: the fluid answer's model (D0 = 0), "
                                   "'front-solute' (the reduced drug model, the solute on "
                                   "the front model's bead: docs/drug_reduced.md) or "
                                   "'full+solute' (the full solver with the drug)")
    dose_ug: float | None = Field(None, description="the dose in ug (with a load)")
    leaked_before_heating: float = Field(
        description="fraction of the load leaked by diffusion during the wait")
    leaked_before_heating_ug: float | None = Field(None, description="the same in ug")
    leak_time_10pct_seconds: float | None = Field(None, description="the same in s")
    squeezed_fraction: float = Field(
        description="fraction of the load that left with the expelled fluid")
    diffused_fraction: float = Field(
        description="fraction of the load that left by diffusion through the edge")
    mechanism: str = Field(description="'squeezed out' or 'diffused', with the split")
    fluid_fraction: float = Field(description="fraction of the stored fluid expelled by then")
    medium_concentration_ug_per_ul: float | None = Field(
        None, description="drug concentration in a finite release volume, ug/uL")
    drug_diffusivity_cm2_s: float = Field(description="the drug's diffusivity in water D0")
    mass_balance_error: float = Field(
        description="|loaded - in gel - released| / loaded of the drug run")
    fluid_answer: dict[str, Any] | None = Field(
        None, description="the fluid answer for the same time (model, interfacial length, "
                          "error estimate)")
    scenario_key: str | None = Field(None, description="key of the drug run")
    peclet: float | None = Field(None, description="the heating's Peclet number: mean "
                                 "shrinking speed x swollen radius / D0 f(phi0)")
    split: str = Field("", description="how squeezed and diffused are defined (squeezed: the "
                                       "release of the same mechanics with D0 = 0)")
    mesh: str = Field("", description="the mesh, solute radius, sieving and partition assumed")
    permeability_law: str = Field("none", description="the permeability's temperature law "
                                                      "(none: k0 as given)")


class DrugScheduleResponse(DrugOut, ScheduleOut, StatedOut):
    """HTTP 200 for a schedule with a ``drug``: each reading in drug, leakage, warnings."""

    doses_ug: list[float] | None = Field(None, description="the doses in ug (with a load)")
    warnings: list[str] = Field(description="leaky rests, doses no actuation time can meet")


# ----------------------------------------------------------------------------- service

class HealthResponse(_Out):
    """Liveness and readiness of the service."""

    status: Literal["ok", "starting", "degraded"] = Field(
        description="'ok' once the kernels are warm; 'degraded' after a server fault (e.g. "
                    "a full disk): planner.degraded_because says why")
    version: str = Field(description="thermogel version")
    kernels_warm: int = Field(description="numba kernels compiled or loaded from the cache")
    kernels_cold: list[str] = Field(
        description="kernels never compiled in this process: unused ones, and helpers called "
                    "only from other kernels (compiled into their callers)")
    warmup_seconds: float | None = Field(None, description="time the warm-up took, s")
    planner: dict[str, Any] = Field(description="planner state: cache path, queue")


class ErrorItem(_Out):
    """One problem with a request; ``loc`` names the field."""

    loc: list[str | int] = Field(description="where: ['body', field, ...] or ['path', name]")
    msg: str = Field(description="what is wrong, with the valid range")
    type: str = Field(description="kind of error")
    input: str | float | int | bool | None = Field(
        None, description="an excerpt of the offending value (strings cut to "
                          "80 characters, containers summarised, NaN/Infinity as text)")


class ErrorResponse(_Out):
    """An error answer (404, 413, 422, 429, 503)."""

    detail: list[ErrorItem] | str = Field(
        description="the problems (422: each names its field in loc), or a message")
