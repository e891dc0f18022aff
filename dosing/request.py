"""Dose and schedule requests, validated on construction (ParameterError names the field).

A dose is a fraction of the stored fluid (the swollen bead's pore volume (4 pi/3)(a0^3 - 1) in
dry-radius units), a volume in microlitres, or a drug mass with the loaded concentration; it
must be below what the gel can expel at T_end, (4 pi/3)(a0^3 - a_inf^3), reached as t -> inf."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar

from solver.equilibrium import equilibrium, nearest_stable
from solver.errors import ParameterError, require_finite_positive
from solver.gel import Gel, Permeability, check_temperature
from solver.limits import DRY_RADIUS_UM_RANGE, REST_RANGE

from .fits.gel_store import calibrated_constants, lookup
from .quantity import number
from .runs.scenario import DIRECT_ELL_RANGE, TRUTH, SolverSettings
from .units import (
    PhysicalConstants,
    released_fraction,
    stored_volume,
    timescale,
    ul_to_volume,
    volume_to_ul,
)

BRANCHES = ("swollen", "shrunken")


GEL_FIELDS = ("omega", "a0", "b0", "a1", "b1")


def gel_with(base: str, overrides: dict[str, Any] | None = None,
             permeability: str | None = None, beta: float | None = None) -> Gel:
    """A preset or stored gel (``base``, by name) with any of its parameters (eq. FloryParam) or
    its permeability law (eq. Permeability) replaced: the one rule of HTTP, the CLI and Python.
    It keeps its base's name when nothing changes, else is called 'custom'; a bad parameter is a
    ParameterError naming ``gel.<parameter>``."""
    gel = lookup(base)
    custom = {k: float(v) for k, v in (overrides or {}).items() if v is not None}
    unknown = sorted(set(custom) - set(GEL_FIELDS))
    if unknown:
        raise ParameterError(f"gel.{unknown[0]}", custom[unknown[0]],
                             "one of " + ", ".join(GEL_FIELDS))
    try:
        if permeability is None and beta is None:
            perm = gel.permeability
        else:
            perm = Permeability(permeability or "power", 0.0 if beta is None else beta)
        if not custom and perm == gel.permeability:
            return gel
        params = {n: custom.get(n, getattr(gel, n)) for n in GEL_FIELDS}
        return Gel(**params, permeability=perm, name="custom")
    except ParameterError as exc:
        field = exc.field.removeprefix("permeability.").replace("law", "permeability")
        raise ParameterError(f"gel.{field}", exc.value, exc.valid) from None


def resolve_gel(value: Gel | str | dict[str, Any]) -> Gel:
    """A Gel from a Gel, a preset name, a stored fitted gel's name (``dosing.fits.gel_store``),
    a full parameter dict (``Gel.to_dict``) or a partial one on a named base
    (``{"base": "ANB", "omega": 300}``, see :func:`gel_with`); field ``gel``."""
    if isinstance(value, Gel):
        return value
    if isinstance(value, str):
        return gel_with(value)
    if isinstance(value, dict):
        if "base" in value:
            d = dict(value)
            base = d.pop("base", "ANB")
            perm, beta = d.pop("permeability", None), d.pop("beta", None)
            if isinstance(perm, dict):  # Gel.to_dict's form
                perm, beta = perm.get("law"), perm.get("beta", beta)
            return gel_with(base, d, perm, beta)
        try:
            return Gel.from_dict(value)
        except TypeError as exc:
            raise ParameterError("gel", value, "a preset name (ANB, HHT) or gel parameters "
                                 "omega, a0, b0, a1, b1, permeability") from exc
    raise ParameterError("gel", value, "a preset name (ANB, HHT), a Gel or a parameter dict")


@dataclass(frozen=True)
class Jump:
    """The heating jump of a request: start and final equilibrium radii (dry-radius units)."""

    t_start: float
    t_end: float
    branch: str
    start_radius: float
    final_radius: float

    @property
    def stored_volume(self) -> float:
        """Dimensionless pore volume at the start, (4 pi/3)(a0^3 - 1)."""
        return stored_volume(self.start_radius)

    @property
    def max_fraction(self) -> float:
        """Largest fraction of the stored fluid the gel gives up at T_end (as t -> inf)."""
        return released_fraction(self.start_radius, self.final_radius)


def resolve_jump(gel: Gel, t_start: float, t_end: float, branch: str | None) -> Jump:
    """Validate temperatures and branch; refuse a jump on which the gel does not shrink."""
    t0 = check_temperature(t_start, "t_start")
    t1 = check_temperature(t_end, "t_end")
    if branch is None:
        branch = "swollen" if t1 >= t0 else "shrunken"
    if branch not in BRANCHES:
        raise ParameterError("branch", branch, "'swollen' or 'shrunken'")
    try:
        a0 = equilibrium(gel, t0, branch).stretch
    except ParameterError as exc:
        raise ParameterError("t_start", t_start, "a temperature with a stable equilibrium "
                             "for this gel") from exc
    af = nearest_stable(gel, t1, a0).stretch
    if not af < a0 * (1.0 - 1e-9):
        raise ParameterError(
            "t_end", t_end, f"a temperature at which the gel shrinks from its {branch} state "
            f"at t_start = {t0:g} K (usually above the volume-phase transition)",
            f"on this jump the gel goes from radius {a0:.4g} to {af:.4g}: it "
            f"{'swells, taking up fluid' if af > a0 else 'does not change'} and releases none")
    return Jump(t0, t1, branch, a0, af)


def resolve_dry_radius(dry_radius_um: float | None, swollen_radius_um: float | None,
                       start_radius: float) -> float | None:
    """The dry radius in um from either size (the swollen one at T_start), or None."""
    if dry_radius_um is not None and swollen_radius_um is not None:
        raise ParameterError("swollen_radius_um", swollen_radius_um,
                             "None when dry_radius_um is given (give one bead size)")
    if dry_radius_um is not None:  # bounded where a user gives it (HTTP, CLI; a batch's
        return require_finite_positive("dry_radius_um", dry_radius_um)  # nodes: beyond)
    if swollen_radius_um is not None:
        lo, hi = DRY_RADIUS_UM_RANGE  # after the conversion: a subnormal tau otherwise
        dry = require_finite_positive("swollen_radius_um", swollen_radius_um) / start_radius
        if not lo <= dry <= hi:
            raise ParameterError("swollen_radius_um", swollen_radius_um,
                                 f"a swollen size whose dry radius (/ a0 = {start_radius:.4g}) "
                                 f"is {lo:g}-{hi:g} um")
        return dry
    return None



def resolve_case(req: Case) -> tuple[Jump, float | None]:
    """Validate and normalise the fields every request shares (:class:`Case`, in place)."""
    from dataclasses import fields as _fields

    from .quantity import from_edge  # "50 um", "29 degC", pint Quantities -> documented unit

    for f in _fields(req):
        if f.init:
            object.__setattr__(req, f.name, from_edge(f.name, getattr(req, f.name)))
    gel = resolve_gel(req.gel)
    object.__setattr__(req, "gel", gel)
    object.__setattr__(req, "constants", calibrated_constants(
        gel, _constants(req.constants)).for_gel(gel.omega))  # Omega_p = Omega Omega_f default
    object.__setattr__(req, "settings", _settings(req.settings))
    jump = resolve_jump(gel, req.t_start, req.t_end, req.branch)
    object.__setattr__(req, "jump", jump)
    object.__setattr__(req, "t_start", jump.t_start)
    object.__setattr__(req, "t_end", jump.t_end)
    object.__setattr__(req, "branch", jump.branch)
    dry = resolve_dry_radius(req.dry_radius_um, req.swollen_radius_um, jump.start_radius)
    object.__setattr__(req, "bead_dry_radius_um", dry)
    settings, ell_range = bead_settings(req.settings, req.constants, dry)
    object.__setattr__(req, "settings", settings)
    object.__setattr__(req, "interfacial_range", ell_range)
    heating = getattr(req, "heating", None)
    if heating is not None:  # what the grammar accepts, the solver must (issue 40, R1)
        from .heating.program import check_program

        check_program(heating, None if dry is None else
                      timescale(dry, jump.t_end, req.constants).seconds)
    return jump, dry


@dataclass(frozen=True)
class Case:
    """What every request shares, resolved once on construction (:func:`resolve_case`): the
    gel, the jump t_start -> t_end on its branch, the bead size (``dry_radius_um`` or
    ``swollen_radius_um`` at T_start), the constants and the truth's settings.  Dose and
    schedule requests, fluid or drug, compose it; their own fields follow ``t_end``."""

    gel: Gel | str | dict[str, Any]
    t_start: float
    t_end: float | None = None
    dry_radius_um: float | None = field(default=None, kw_only=True)
    swollen_radius_um: float | None = field(default=None, kw_only=True)
    constants: PhysicalConstants | dict[str, Any] | None = field(default=None, kw_only=True)
    branch: str | None = field(default=None, kw_only=True)
    settings: SolverSettings | dict[str, Any] | None = field(default=None, kw_only=True)
    jump: Jump = field(init=False, repr=False, compare=False)
    bead_dry_radius_um: float | None = field(init=False, repr=False, compare=False)
    interfacial_range: tuple[float, float] | None = field(init=False, repr=False,
                                                          compare=False)

    @property
    def start_radius(self) -> float:
        """a(0): the equilibrium stretch at T_start."""
        return self.jump.start_radius

    def case_fields(self) -> dict[str, Any]:
        """The resolved case as keyword arguments of another request on the same bead."""
        return {"gel": self.gel, "t_start": self.t_start, "t_end": self.t_end,
                "dry_radius_um": self.bead_dry_radius_um, "constants": self.constants,
                "branch": self.branch, "settings": self.settings}

    def dose_request(self, fraction: float) -> DoseRequest:
        """The fluid dose of ``fraction`` of the stored fluid on the same case."""
        return DoseRequest(**self.case_fields(), dose_fraction=fraction)


def _clamp_length(ell: float) -> float:
    lo, hi = DIRECT_ELL_RANGE
    return min(max(ell, lo), hi)


def bead_settings(settings: SolverSettings, constants: PhysicalConstants,
                  dry_radius_um: float | None) -> tuple[SolverSettings,
                                                        tuple[float, float] | None]:
    """The settings at the bead's own interfacial length ell = xi_dry / a_d (direct truth,
    ell not given, a bead size known), and (ell_lo, ell_hi) over the mesh length's range
    (None without a bead size, or when the truth is not direct).  ell is kept within the
    direct runs' range (DIRECT_ELL_RANGE: 2e-5 is xi_lo = 2 nm on a 100 um dry bead)."""
    if not settings.direct or dry_radius_um is None:
        return settings, None
    ell, lo, hi = (_clamp_length(x) for x in constants.interfacial_lengths(dry_radius_um))
    if settings.auto_length:
        settings = settings.with_length(ell)
    else:  # an ell given by hand: its range scales with it
        ell0 = ell
        ell = settings.interfacial_length
        lo, hi = _clamp_length(ell * lo / ell0), _clamp_length(ell * hi / ell0)
    return settings, (lo, hi)

def _constants(value: PhysicalConstants | dict[str, Any] | None) -> PhysicalConstants:
    if value is None:
        return PhysicalConstants()
    if isinstance(value, dict):
        return PhysicalConstants.from_dict(value)
    if not isinstance(value, PhysicalConstants):
        raise ParameterError("constants", value, "PhysicalConstants or a dict of its fields")
    return value


def _settings(value: SolverSettings | dict[str, Any] | None) -> SolverSettings:
    if value is None:
        return TRUTH
    if isinstance(value, dict):
        try:
            value = SolverSettings(**value)
        except TypeError as exc:
            raise ParameterError("settings", value, "a dict of grid, n, integrator, rtol, "
                                 "interfacial_length") from exc
    if not isinstance(value, SolverSettings):
        raise ParameterError("settings", value, "SolverSettings or a dict of its fields")
    value.rungs()  # the validation runs must be possible (ParameterError names the field)
    return value


def _fraction_range(jump: Jump) -> str:
    return (f"0 < fraction < {jump.max_fraction:.4f} of the stored fluid (the gel keeps "
            f"radius {jump.final_radius:.4g} at T_end, so it never gives up all of it)")


def check_fraction(name: str, value: float, jump: Jump, limit: float | None = None) -> float:
    """A dose fraction of the stored fluid, 0 < f < what the gel can expel at T_end."""
    f = require_finite_positive(name, value)
    top = jump.max_fraction if limit is None else limit
    if f >= top:
        why = ("a dose larger than the stored fluid" if f > 1.0 else
               "more than the gel can expel at T_end")
        raise ParameterError(name, value, _fraction_range(jump), why)
    return f


@dataclass(frozen=True)
class DoseRequest(Case):
    """One dose: how long to heat a bead from T_start to T_end to release it.  Exactly one of
    ``dose_fraction`` (of the stored fluid), ``dose_volume_ul``, or ``drug_mass_ug`` with
    ``concentration_ug_per_ul``; volumes and seconds need a bead size (``dry_radius_um`` or
    ``swollen_radius_um`` at T_start; the :class:`Case` fields)."""

    dose_fraction: float | None = None
    dose_volume_ul: float | None = None
    drug_mass_ug: float | None = None
    concentration_ug_per_ul: float | None = None
    size_distribution: Any = field(default=None, kw_only=True)  # a batch (dosing.population.sizes)
    fraction: float = field(init=False, repr=False, compare=False)
    # a heating protocol in place of t_end (dosing.heating.grammar; the dose:
    # dosing.heating.response)
    protocol: Any = field(default=None, kw_only=True)
    heating: Any = field(init=False, repr=False, compare=False, default=None)

    def __post_init__(self) -> None:
        _resolve_protocol(self)
        from .population.sizes import request_sizes

        request_sizes(self)  # a batch: its number-weighted mean is the bead size
        jump, dry = resolve_case(self)
        object.__setattr__(self, "fraction", self._resolve_fraction(jump, dry))

    def _resolve_fraction(self, jump: Jump, dry: float | None) -> float:
        given = [n for n in ("dose_fraction", "dose_volume_ul", "drug_mass_ug")
                 if getattr(self, n) is not None]
        if len(given) != 1:
            raise ParameterError(given[1] if len(given) > 1 else "dose_fraction", None,
                                 "exactly one of dose_fraction, dose_volume_ul, drug_mass_ug")
        if (self.concentration_ug_per_ul is not None and given[0] != "drug_mass_ug"
                and self.heating is None):  # a protocol's "until 20 ug released" uses it
            raise ParameterError("concentration_ug_per_ul", self.concentration_ug_per_ul,
                                 "None unless drug_mass_ug is given")
        if given[0] == "dose_fraction":
            return check_fraction("dose_fraction", self.dose_fraction, jump)
        name = given[0]
        if name == "drug_mass_ug":
            mass = require_finite_positive("drug_mass_ug", self.drug_mass_ug)
            if self.concentration_ug_per_ul is None:
                raise ParameterError("concentration_ug_per_ul", None,
                                     "a finite number > 0 (ug/uL) to turn drug_mass_ug "
                                     "into a volume")
            conc = require_finite_positive("concentration_ug_per_ul",
                                           self.concentration_ug_per_ul)
            vol_ul = mass / conc
        else:
            vol_ul = require_finite_positive("dose_volume_ul", self.dose_volume_ul)
        if dry is None:
            raise ParameterError("dry_radius_um", None,
                                 f"a finite number > 0 (um; or swollen_radius_um) to turn "
                                 f"{name} into a fraction of the stored fluid")
        stored_ul = volume_to_ul(jump.stored_volume, dry)
        f = ul_to_volume(vol_ul, dry) / jump.stored_volume
        if not f < jump.max_fraction:
            unit = "ug" if name == "drug_mass_ug" else "uL"
            scale = 1.0 if name == "dose_volume_ul" else self.concentration_ug_per_ul
            top = jump.max_fraction * stored_ul * scale
            raise ParameterError(
                name, getattr(self, name), f"0 < {name} < {top:.4g} {unit}",
                f"the bead stores {stored_ul:.4g} uL of fluid and can expel "
                f"{jump.max_fraction:.1%} of it at T_end"
                + ("; this dose is larger than the stored fluid" if f > 1.0 else ""))
        return f

    @property
    def heating_kind(self) -> str:
        """The key of the request's heating in the planner's dose paths: ``"jump"`` (T_end
        held, the paper's) or ``"protocol"`` (steps of ``dosing.heating.grammar``)."""
        return "jump" if self.heating is None else "protocol"

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form of the request as resolved (gel parameters, fraction, sizes)."""
        return {"gel": self.gel.to_dict(), "t_start": self.t_start, "t_end": self.t_end,
                "branch": self.branch, "dose_fraction": self.fraction,
                "dry_radius_um": self.bead_dry_radius_um,
                "constants": self.constants.to_dict(), "settings": self.settings.to_dict(),
                **({} if self.size_distribution is None
                   else {"size_distribution": self.size_distribution.to_dict()}),
                **({} if self.heating is None else {"protocol": self.heating.to_dict()})}


def _resolve_protocol(req: Any) -> None:
    """A request's heating protocol (``dosing.heating.grammar.Protocol``) in place of t_end: its
    hottest temperature is the jump's T_end (the dose's limit, tau's reference)."""
    if req.protocol is None:
        if req.t_end is None:
            raise ParameterError("t_end", None, "a temperature in K (or give a protocol)")
        return
    from .heating.grammar import Protocol

    if req.t_end is not None:
        raise ParameterError("t_end", req.t_end, "None when a protocol is given (the "
                             "protocol's steps set the heating)")
    prot = Protocol.parse(req.t_start, req.protocol)
    object.__setattr__(req, "heating", prot)
    object.__setattr__(req, "t_start", prot.t_start)
    object.__setattr__(req, "t_end", prot.hottest)


def at_start(name: str, value: Any, seconds: Any, dry: float | None, t_end: float,
             constants: PhysicalConstants, top: float = REST_RANGE[1]) -> Any:
    """The one parser of a time at T_start before or between heatings (a schedule's
    ``rests``, a drug's ``wait``), in tau: ``value`` (a number or a list) in tau, or
    ``seconds`` (``name``_seconds) over the bead's tau (eq. timescale; needs the dry radius
    ``dry``); each finite and within REST_RANGE (solver.limits), up to ``top`` tau.  None
    when neither is given."""
    if value is not None and seconds is not None:
        raise ParameterError(f"{name}_seconds", seconds,
                             f"None when {name} is given (give one of them)")
    field_name, given = (name, value) if seconds is None else (f"{name}_seconds", seconds)
    if given is None:
        return None
    tau = None
    if seconds is not None:
        if dry is None:
            raise ParameterError("dry_radius_um", None, "a finite number > 0 (um; or "
                                 f"swollen_radius_um) to turn {field_name} into tau units")
        tau = timescale(dry, t_end, constants).seconds
    lo = REST_RANGE[0]
    span = f"{lo:g}-{top:g} tau" + ("" if tau is None else
                                    f" = {lo:g}-{top * tau:.4g} s (tau = {tau:.4g} s)")

    def one(where: str, v: Any) -> float:
        x = number(v) if tau is None else number(v) / tau
        if not (math.isfinite(x) and lo <= x <= top):
            raise ParameterError(where, v, f"a finite number {span}")
        return x

    try:  # a list (or any iterable: a numpy array), else one number
        items = None if isinstance(given, str) else list(given)
    except TypeError:
        items = None
    if items is None:
        return one(field_name, given)
    return tuple(one(f"{field_name}[{i}]", v) for i, v in enumerate(items))


@dataclass(frozen=True)
class ScheduleCase(Case):
    """What every schedule shares (fluid or drug): ``rests`` between consecutive doses
    (dimensionless, time / tau), or ``rests_seconds`` with a bead size (none given: back to
    back); ``check_protocol`` simulates the real heat/cool protocol with the full solver;
    ``correct`` then shoots for actuation times meeting every dose within ``tolerance``."""

    rests: Sequence[float] | None = field(default=None, kw_only=True)
    rests_seconds: Sequence[float] | None = field(default=None, kw_only=True)
    check_protocol: bool = field(default=True, kw_only=True)
    correct: bool = field(default=True, kw_only=True)
    tolerance: float = field(default=0.01, kw_only=True)
    # every heating follows this protocol in place of a jump to t_end (dosing.heating.cycles)
    protocol: Any = field(default=None, kw_only=True)
    heating: Any = field(init=False, repr=False, compare=False, default=None)
    rest_max: ClassVar[float] = REST_RANGE[1]  # tau: the longest rest (a drug case: shorter)

    def resolve_heating(self) -> None:
        """The heating protocol in place of t_end (:func:`_resolve_protocol`), without
        until-steps: the schedule's doses end each heating."""
        _resolve_protocol(self)
        for i in () if self.heating is None else self.heating.until_steps:
            raise ParameterError(f"protocol[{i}].until", self.heating.steps[i].text,
                                 "a step with a duration or none (a schedule's doses end "
                                 "each heating)")

    def case_fields(self) -> dict[str, Any]:
        """The resolved case, with the protocol in place of t_end when there is one."""
        out = super().case_fields()
        if self.heating is not None:
            out.update(t_end=None, protocol=self.heating)
        return out

    def resolve_schedule(self, n_doses: int, dry: float | None) -> None:
        """Rests in tau (:func:`at_start`; zeros when none are given), one fewer than the
        doses, and the tolerance (0 < tol <= 0.2)."""
        rests, given = self.rests, self.rests_seconds
        if rests is None and given is None:
            rests = (0.0,) * max(n_doses - 1, 0)
        out = at_start("rests", rests, given, dry, self.t_end, self.constants, self.rest_max)
        if not isinstance(out, tuple) or len(out) != n_doses - 1:
            raise ParameterError(*(("rests", rests) if given is None else ("rests_seconds",
                                   given)), f"{n_doses - 1} values (one rest between "
                                 "consecutive doses)")
        object.__setattr__(self, "rests", out)
        tol = require_finite_positive("tolerance", self.tolerance)
        if tol > 0.2:
            raise ParameterError("tolerance", self.tolerance, "0 < tolerance <= 0.2")
        object.__setattr__(self, "tolerance", tol)


@dataclass(frozen=True)
class ScheduleRequest(ScheduleCase):
    """Several doses (fractions of the stored fluid) with rests at T_start between them
    (the :class:`ScheduleCase` fields)."""

    doses: Sequence[float] = ()

    def __post_init__(self) -> None:
        self.resolve_heating()
        jump, dry = resolve_case(self)
        doses = tuple(self.doses or ())
        if not doses:
            raise ParameterError("doses", self.doses, "a non-empty list of fractions")
        doses = tuple(check_fraction(f"doses[{i}]", d, jump) for i, d in enumerate(doses))
        if sum(doses) >= jump.max_fraction:
            raise ParameterError("doses", list(doses), f"fractions summing to less than "
                                 f"{jump.max_fraction:.4f}", f"they sum to {sum(doses):.4g}: "
                                 "more than the gel can expel at T_end")
        object.__setattr__(self, "doses", doses)
        self.resolve_schedule(len(doses), dry)
