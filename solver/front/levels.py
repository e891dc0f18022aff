"""The two porosity levels of the step-function front and where the front model applies.

Sec. FrontSoln: the swollen core keeps the initial equilibrium porosity phi_- (eq. EqlEqn at
T_start) and the shrunken shell sits at phi_+, the shrunken root of P(phi) = 0 at T_end.  The
model describes a front that forms when a swollen bead is heated into the coexistence region
(classifier behaviour ``front``); after a delayed front it is only approximate.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from functools import lru_cache

from ..equilibrium import Branch, equilibrium
from ..errors import NotApplicableError, ParameterError
from ..gel import Gel, Permeability
from ..phase import classify_jump, shrunken_level
from ..thermo import osmotic_dp, osmotic_p


@dataclass(frozen=True)
class FrontLevels:
    """Everything the front model needs about one jump, all at T_end unless named otherwise.

    ``a0`` is the initial radius (the initial isotropic stretch), ``omega_p_minus`` the core's
    osmotic pressure Omega P(phi_-) at T_end (the last term of eq. BVP_Front_BCFront, see the
    slips in DESIGN.md), ``dp_plus`` P'(phi_+), ``k_plus`` k(phi_+) (eq. FrontEvolve) and
    ``permeability`` the gel's law k(phi).
    """

    t_start: float
    t_end: float
    branch: str
    a0: float
    phi_minus: float
    phi_plus: float
    omega: float
    omega_p_minus: float
    dp_plus: float
    k_plus: float
    behaviour: str
    permeability: Permeability = Permeability()

    @property
    def s_minus(self) -> float:
        """Solid fraction of the swollen core, 1 - phi_-."""
        return 1.0 - self.phi_minus

    @property
    def s_plus(self) -> float:
        """Solid fraction of the shrunken shell, 1 - phi_+."""
        return 1.0 - self.phi_plus

    @property
    def jump(self) -> float:
        """phi_- - phi_+ > 0: the porosity lost as the front passes (eq. FrontEvolve)."""
        return self.phi_minus - self.phi_plus

    def to_dict(self) -> dict[str, float | str]:
        """Plain-data form."""
        return asdict(self)


@lru_cache(maxsize=256)
def _assess_cached(gel: Gel, t_start: float, t_end: float,
            branch: Branch | None) -> tuple[FrontLevels | None, str]:
    """(levels, reason) when the model applies, (None, reason) when it does not (cached)."""
    c = classify_jump(gel, t_start, t_end, branch)
    if c.direction != "shrink":
        return None, (f"the jump {c.t_start:g} K -> {c.t_end:g} K does not shrink the gel "
                      f"({c.direction}); the front model describes a shrinking core-shell front")
    if c.behaviour not in ("front", "delayed_front"):
        return None, (f"no core-shell front: the classifier says '{c.behaviour}' ({c.reason}); "
                      "use the full solver")
    try:
        phi_plus = shrunken_level(gel, c.t_end)
    except ParameterError as exc:
        return None, f"no shrunken level phi_+ at T_end: {exc}"
    phi_minus = equilibrium(gel, c.t_start, c.branch).porosity
    if not phi_plus < phi_minus:
        return None, (f"the shrunken level phi_+={phi_plus:.4g} is not below the core porosity "
                      f"phi_-={phi_minus:.4g}: no shrinking front")
    chi0, chi1 = gel.chi0(c.t_end), gel.chi1(c.t_end)
    levels = FrontLevels(
        t_start=c.t_start, t_end=c.t_end, branch=c.branch, a0=c.start_stretch,
        phi_minus=phi_minus, phi_plus=phi_plus, omega=gel.omega,
        omega_p_minus=gel.omega * float(osmotic_p(phi_minus, chi0, chi1)),
        dp_plus=float(osmotic_dp(phi_plus, chi0, chi1)),
        k_plus=float(gel.permeability(phi_plus)), behaviour=c.behaviour,
        permeability=gel.permeability)
    if c.behaviour == "delayed_front":
        return levels, ("approximate only: the start lies outside the coexistence region and a "
                        "front forms after a delay the step-function model ignores")
    return levels, c.reason


def front_applicability(gel: Gel, t_start: float, t_end: float,
                        branch: Branch | None = None) -> tuple[bool, str]:
    """(applies, reason): True for the classifier's ``front`` (and, approximately,
    ``delayed_front``) shrinking jumps with phi_+ < phi_-; otherwise False and why."""
    levels, reason = _assess_cached(gel, float(t_start), float(t_end), branch)
    return levels is not None, reason


def front_levels(gel: Gel, t_start: float, t_end: float,
                 branch: Branch | None = None) -> FrontLevels:
    """The levels phi_-, phi_+ (sec. FrontSoln); NotApplicableError where no front applies."""
    levels, reason = _assess_cached(gel, float(t_start), float(t_end), branch)
    if levels is None:
        raise NotApplicableError(f"front model not applicable: {reason}")
    return levels
