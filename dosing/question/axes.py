"""The axes of a request: payload x population x heating x question, one class per value.

Payload :class:`Fluid` (the stored pore fluid, eq. FluidVolExpelled) or :class:`Drug`;
population :class:`OneBead` or :class:`Batch`; heating :class:`Jump` or :class:`Heating` (the
step grammar); question :class:`Dose` or :class:`Schedule`.  Each gives ``key`` and ``fields()``
and branches on no other axis (docs/architecture.md, "Where to add ...")."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, fields
from typing import Any, ClassVar

from ..request import ScheduleCase

# the planner's schedule defaults, written once (dosing.request.ScheduleCase)
_SCHEDULE = {f.name: f.default for f in fields(ScheduleCase) if f.kw_only}


@dataclass(frozen=True)
class Fluid:
    """The payload is the stored pore fluid: a dose is a fraction of it (or a volume, or a
    drug mass carried in it at a concentration)."""

    key: ClassVar[str] = "fluid"
    tags: ClassVar[dict[str, Any]] = {}  # what its answers add to their JSON
    # its dimensionless answer is free of tau (the seconds scale with it: eq. timescale)
    tau_free: ClassVar[bool] = True

    def fields(self) -> dict[str, Any]:
        """Nothing to add: the fluid is the bead's own."""
        return {}

    @staticmethod
    def mesh_variants(planned: Any) -> list[tuple[str, Any]]:
        """No sieving: no mesh part."""
        return []

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form."""
        return {"kind": self.key}


@dataclass(frozen=True)
class Drug:
    """The payload is a drug dissolved in the pore fluid (``model``: a
    ``dosing.payload.drug.DrugModel`` or a dict of its fields), ``wait`` (tau) or
    ``wait_seconds`` at T_start before the first heating; a batch shares a well-mixed
    ``medium_volume_ml`` with ``bead_count`` beads (neither: a perfect sink)."""

    model: Any
    wait: float | None = None
    wait_seconds: float | None = None
    medium_volume_ml: Any = None
    bead_count: float | None = None

    key: ClassVar[str] = "drug"
    tags: ClassVar[dict[str, Any]] = {"drug": True}  # its answers say so (api DrugOut)
    tau_free: ClassVar[bool] = False  # D0 / D_gel moves with the constants

    def fields(self) -> dict[str, Any]:
        """The drug request's fields (the medium is the population's to use)."""
        return {"drug": self.model, "wait": self.wait, "wait_seconds": self.wait_seconds}

    def mesh_variants(self, planned: Any) -> list[tuple[str, Any]]:
        """The payloads of the mesh part (issue 36): a sieved drug at xi_dry / 2 and 2 xi_dry (its
        own mesh_size_nm: the bead's mechanics and runs stay), with the other stretch bound and,
        with a fibre radius, in the other microstructure (docs/drug.md, "One microstructure ...");
        none when nothing sieves it (no solute radius, no hindrance)."""
        from dataclasses import replace

        drug = planned.drug
        if drug.hindrance == "none" or drug.solute_radius() is None:
            return []
        xi = drug.dry_mesh_nm(planned.start_radius, planned.constants)
        swollen = xi * planned.start_radius
        other = "volume" if drug.mesh_stretch == "smallest" else "smallest"
        out = [(f"xi_dry {f * xi:.3g} nm", replace(self, model=replace(
                   drug, mesh_size_nm=f * swollen))) for f in (0.5, 2.0)] + [
               (f"mesh stretch '{other}'", replace(self, model=replace(
                   drug, mesh_stretch=other)))]
        if drug.fiber_radius_nm is not None:
            fibre = drug.hindrance == "ogston" and drug.partition_law_used() == "ogston"
            out.append(("pore microstructure (free-volume diffusion, constant partition)",
                        replace(self, model=replace(drug, hindrance="free-volume",
                                                    partition_law="constant")))
                       if fibre else
                       ("fibre-matrix microstructure (Ogston's diffusion and partition)",
                        replace(self, model=replace(drug, hindrance="ogston",
                                                    partition_law="ogston"))))
        return out

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form."""
        model = self.model.to_dict() if hasattr(self.model, "to_dict") else self.model
        return {"kind": self.key, "drug": model, "wait": self.wait,
                "wait_seconds": self.wait_seconds, "medium_volume_ml": self.medium_volume_ml,
                "bead_count": self.bead_count}


@dataclass(frozen=True)
class OneBead:
    """One bead of the case's size."""

    key: ClassVar[str] = "one"

    def fields(self) -> dict[str, Any]:
        """Nothing to add: the case's bead."""
        return {}

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form."""
        return {"kind": self.key}


@dataclass(frozen=True)
class Batch:
    """A batch of beads: ``sizes`` is a ``dosing.population.sizes.SizeDistribution``, a
    measured table (``DrySizes``) or a dict of the distribution's fields."""

    sizes: Any

    key: ClassVar[str] = "batch"

    def fields(self) -> dict[str, Any]:
        """A dose request's batch (its number-weighted mean is the case's bead)."""
        return {"size_distribution": self.sizes}

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form."""
        sizes = self.sizes.to_dict() if hasattr(self.sizes, "to_dict") else self.sizes
        return {"kind": self.key, "sizes": sizes}


@dataclass(frozen=True)
class Jump:
    """Heating by a jump to ``t_end`` (K), held there: the paper's experiment."""

    t_end: Any

    key: ClassVar[str] = "jump"
    tau_free: ClassVar[bool] = True

    def fields(self) -> dict[str, Any]:
        """The request's T_end."""
        return {"t_end": self.t_end}

    @staticmethod
    def lattice(planned: Any, settings: Any, target: float) -> Any:
        """The jump's run under ``settings`` (the envelope's delayed-law lattice)."""
        from ..runs.scenario import Scenario

        return Scenario(planned.gel, planned.t_start, planned.t_end, branch=planned.branch,
                        settings=settings)

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form."""
        return {"kind": self.key, "t_end": self.t_end}


@dataclass(frozen=True)
class Heating:
    """Heating by a protocol of steps (texts, dicts or a ``dosing.heating.grammar.Protocol``; the
    grammar of ``dosing.heating.grammar``) from T_start; after the last step the bead holds at the
    last temperature."""

    steps: Any

    key: ClassVar[str] = "protocol"
    tau_free: ClassVar[bool] = False  # its rates and times are in seconds: tau moves them

    def fields(self) -> dict[str, Any]:
        """The request's protocol (its hottest temperature is T_end)."""
        return {"t_end": None, "protocol": self.steps}

    @staticmethod
    def lattice(planned: Any, settings: Any, target: float) -> Any:
        """The protocol's run under ``settings`` (the envelope's delayed-law lattice)."""
        from ..heating.response import lattice_scenario

        return lattice_scenario(planned, settings, target)

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form."""
        steps = self.steps.texts if hasattr(self.steps, "texts") else list(self.steps)
        return {"kind": self.key, "steps": steps}


@dataclass(frozen=True)
class Dose:
    """One dose: ``fraction`` of the payload (of the stored fluid, of a drug's load, of a
    batch's), or ``volume_ul`` of fluid, or ``drug_mass_ug`` (of a drug's load; of fluid
    with ``concentration_ug_per_ul``)."""

    fraction: float | None = None
    volume_ul: float | None = None
    drug_mass_ug: float | None = None
    concentration_ug_per_ul: float | None = None

    key: ClassVar[str] = "dose"

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form."""
        return {"kind": self.key, "fraction": self.fraction, "volume_ul": self.volume_ul,
                "drug_mass_ug": self.drug_mass_ug,
                "concentration_ug_per_ul": self.concentration_ug_per_ul}


@dataclass(frozen=True)
class Schedule:
    """Several doses (``doses`` fractions, or ``doses_ug`` of a drug's load) with ``rests``
    (tau) or ``rests_seconds`` at T_start between them; ``check_protocol`` simulates the
    hold reading's times, ``correct`` shoots for times meeting every dose within
    ``tolerance`` (the planner's defaults: ``dosing.request.ScheduleCase``)."""

    doses: Sequence[float] | None = None
    doses_ug: Sequence[float] | None = None
    rests: Sequence[float] | None = None
    rests_seconds: Sequence[float] | None = None
    check_protocol: bool = _SCHEDULE["check_protocol"]
    correct: bool = _SCHEDULE["correct"]
    tolerance: float = _SCHEDULE["tolerance"]

    key: ClassVar[str] = "schedule"

    def fields(self) -> dict[str, Any]:
        """The schedule fields every schedule request shares."""
        return {"rests": self.rests, "rests_seconds": self.rests_seconds,
                "check_protocol": self.check_protocol, "correct": self.correct,
                "tolerance": self.tolerance}

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form."""
        return {"kind": self.key, "doses": None if self.doses is None else list(self.doses),
                "doses_ug": None if self.doses_ug is None else list(self.doses_ug),
                **{k: (list(v) if isinstance(v, (list, tuple)) else v)
                   for k, v in self.fields().items()}}


PAYLOADS = (Fluid, Drug)
POPULATIONS = (OneBead, Batch)
HEATINGS = (Jump, Heating)
QUESTIONS = (Dose, Schedule)
