"""Design maps: the planner's answer over a grid of gels x T_end x bead size x dose.

Every point is answered with the front model at once (milliseconds; sec. Application with
the reduced model); points where only the full solver answers are reported as such, and
full-solver validations are queued for a chosen subset.  The grid is cut into chunks that
share a jump (gel, T_start, T_end), so each chunk computes its front trajectory once, and
the chunks run on any ``concurrent.futures`` executor: inline by default, a process pool,
or a Dask cluster through ``Client(...).get_executor()``.  A point that fails (a dose above
the stored fluid, a temperature out of range) is a row with its message; the rest of the
sweep completes.
"""

from __future__ import annotations

import csv
import io
import math
import time
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import Executor, Future, as_completed
from dataclasses import dataclass, field, replace
from itertools import product
from typing import TYPE_CHECKING, Any, ClassVar

from solver.errors import NotApplicableError, ParameterError, SolverError
from solver.gel import Gel
from solver.json_safe import json_safe
from solver.presenters import presenter

from ..model_choice import front_answer, jump_class
from ..request import DoseRequest, resolve_gel
from ..runs.jobs import QueueFullError
from ..runs.scenario import SolverSettings
from ..units import PhysicalConstants, timescale
from ..validation import error_estimate

if TYPE_CHECKING:
    from ..planner import Planner

MAX_POINTS = 100_000  # a larger map is several sweeps
CHUNK_SIZE = 256  # points per executor task at most (one jump per task)

# name -> (unit, description); the row order of every table
COLUMNS: dict[str, tuple[str, str]] = {
    "index": ("1", "point number, C order over gel, t_end, dry_radius_um, dose_fraction"),
    "gel_index": ("1", "which gel of the grid's gels"),
    "gel": ("", "gel name (a preset, a preset with a parameter varied, or 'custom')"),
    "t_start": ("K", "start (loading) temperature"),
    "t_end": ("K", "end (actuation) temperature"),
    "dry_radius_um": ("um", "dry bead radius"),
    "dose_fraction": ("1", "dose as a fraction of the stored fluid"),
    "status": ("", "'answered' (front model), 'needs-full' (only the full solver answers: "
                   "validate it) or 'error' (see message)"),
    "model": ("", "'front-sharp' or 'front' (the paper's), 'full' where needed"),
    "behaviour": ("", "the jump's class: front, delayed_front, smooth, spinodal"),
    "time": ("tau", "actuation time, dimensionless (units of tau, eq. timescale)"),
    "seconds": ("s", "actuation time"),
    "timescale_seconds": ("s", "tau for this bead size and T_end"),
    "final_radius_um": ("um", "bead radius after the dose"),
    "expelled_volume_ul": ("uL", "fluid released"),
    "stored_volume_ul": ("uL", "fluid stored at T_start"),
    "error_estimate": ("1", "estimated relative error of the time (the front model's prior "
                            "until a validation is cached)"),
    "message": ("", "why a point failed or needs the full solver"),
    "field": ("", "the input a failed point names"),
    "validation_id": ("", "full-solver validation queued for this point (poll "
                          "/v1/validations/{id})"),
    "validation_status": ("", "pending, running, done or failed"),
    "truth_time": ("tau", "the full solver's time for this dose, once validated"),
    "front_time_error": ("1", "the front model's relative time error against it"),
    "size_cv": ("1", "with a CV axis: the batch's CV of size (a number-weighted lognormal "
                     "whose mean is dry_radius_um; time and seconds are the batch's)"),
    "batch_delay": ("1", "the batch's dose time over its mean bead's, minus 1"),
    "fraction_delivered": ("1", "the fraction of the batch's beads that have delivered "
                                "their own dose by the batch's time"),
}


def _floats(name: str, values: Iterable[float]) -> tuple[float, ...]:
    out = tuple(float(v) for v in values)
    if not out:
        raise ParameterError(name, list(out), "a non-empty list of numbers")
    for i, v in enumerate(out):
        if not math.isfinite(v):
            raise ParameterError(f"{name}[{i}]", v, "a finite number")
    return out


@dataclass(frozen=True)
class SweepGrid:
    """The axes of a design map; every combination is one point.

    Points are not checked here beyond being finite numbers: each is checked (and may
    fail on its own, with its message) when it is answered.
    """

    t_ends: Sequence[float]
    dry_radii_um: Sequence[float]
    doses: Sequence[float]
    gels: Sequence[Gel | str | dict[str, Any]] = ("ANB",)
    t_start: float = 302.0
    branch: str | None = None
    constants: PhysicalConstants | dict[str, Any] | None = None
    settings: SolverSettings | dict[str, Any] | None = None
    size_cvs: Sequence[float] | None = None  # a fifth axis: batches (dosing.population.front)
    _gels: tuple[Gel, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "t_ends", _floats("t_ends", self.t_ends))
        object.__setattr__(self, "dry_radii_um", _floats("dry_radii_um", self.dry_radii_um))
        object.__setattr__(self, "doses", _floats("doses", self.doses))
        gels = tuple(self.gels)
        if not gels:
            raise ParameterError("gels", [], "a non-empty list of gels")
        resolved = []
        for i, g in enumerate(gels):
            try:
                resolved.append(resolve_gel(g))
            except (ParameterError, ValueError) as exc:
                raise ParameterError(f"gels[{i}]", g, "a preset name (ANB, HHT) or gel "
                                     "parameters") from exc
        object.__setattr__(self, "_gels", tuple(resolved))
        object.__setattr__(self, "t_start", float(self.t_start))
        if self.size_cvs is not None:
            from .batch_design import check_cvs

            object.__setattr__(self, "size_cvs", check_cvs(self.size_cvs))
        if self.size > MAX_POINTS:
            raise ParameterError("grid", self.shape, f"at most {MAX_POINTS} points (this grid "
                                 f"has {self.size}): split it into several sweeps")
        if isinstance(self.constants, PhysicalConstants):
            object.__setattr__(self, "constants", self.constants.to_dict())
        if isinstance(self.settings, SolverSettings):  # unresolved: each point's bead's ell
            object.__setattr__(self, "settings", self.settings.request_dict())

    @property
    def shape(self) -> tuple[int, ...]:
        """(gels, t_ends, dry radii, doses), and CVs when the grid has that axis."""
        four = (len(self._gels), len(self.t_ends), len(self.dry_radii_um), len(self.doses))
        return four if self.size_cvs is None else (*four, len(self.size_cvs))

    @property
    def size(self) -> int:
        """Number of points."""
        return math.prod(self.shape)

    def points(self) -> list[dict[str, Any]]:
        """Every point as plain data (picklable, JSON-ready), in C order of :attr:`shape`."""
        out = []
        cvs = (None,) if self.size_cvs is None else self.size_cvs
        axes = product(enumerate(self._gels), self.t_ends, self.dry_radii_um, self.doses, cvs)
        for i, ((g, gel), t_end, r, f, cv) in enumerate(axes):
            out.append({"index": i, "gel_index": g, "gel": gel.to_dict(), "t_start": self.t_start,
                        "t_end": t_end, "dry_radius_um": r, "dose_fraction": f,
                        "branch": self.branch, "constants": self.constants,
                        "settings": self.settings, "size_cv": cv})
        return out

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form (the axes)."""
        return {"gels": [g.to_dict() for g in self._gels], "t_start": self.t_start,
                "t_ends": list(self.t_ends), "dry_radii_um": list(self.dry_radii_um),
                "doses": list(self.doses), "branch": self.branch,
                "constants": self.constants, "settings": self.settings,
                "shape": list(self.shape),
                **({} if self.size_cvs is None else {"size_cvs": list(self.size_cvs)})}


GEL_PARAMETERS = ("omega", "a0", "b0", "a1", "b1")


def vary_gel(base: Gel | str, **axes: Sequence[float]) -> list[Gel]:
    """Gels along parameter axes (eq. FloryParam), e.g. ``vary_gel("ANB", omega=[50, 100])``:
    the product of the axes, each gel named after its base and values ('ANB omega=50')."""
    gel = resolve_gel(base)
    for name in axes:
        if name not in GEL_PARAMETERS:
            raise ParameterError("vary", name, f"one of {', '.join(GEL_PARAMETERS)}")
    names = list(axes)
    out = []
    for values in product(*(_floats(n, axes[n]) for n in names)):
        label = " ".join(f"{n}={v:g}" for n, v in zip(names, values, strict=True))
        try:
            out.append(replace(gel, **dict(zip(names, values, strict=True)),
                               name=f"{gel.name} {label}".strip()))
        except ParameterError as exc:
            raise ParameterError(f"vary.{exc.field}", exc.value, exc.valid) from None
    return out


def point_request(point: dict[str, Any]) -> DoseRequest:
    """The dose request of one point (ParameterError names what is wrong with it)."""
    return DoseRequest(point["gel"], point["t_start"], point["t_end"],
                       dose_fraction=point["dose_fraction"],
                       dry_radius_um=point["dry_radius_um"], constants=point["constants"],
                       branch=point["branch"], settings=point["settings"])


def _row(point: dict[str, Any]) -> dict[str, Any]:
    row = dict.fromkeys(COLUMNS)
    row.update(index=point["index"], gel_index=point["gel_index"], size_cv=point.get("size_cv"),
               gel=point["gel"].get("name", "custom"),
               t_start=point["t_start"], t_end=point["t_end"],
               dry_radius_um=point["dry_radius_um"], dose_fraction=point["dose_fraction"])
    return row


def answer_point(point: dict[str, Any]) -> dict[str, Any]:
    """One row of the table: the front model's answer, or why there is none (never raises
    for a bad point: its status is 'error' with the message and the field)."""
    row = _row(point)
    try:
        req = point_request(point)
        row["behaviour"] = jump_class(req.gel, req.t_start, req.t_end, req.branch).behaviour
        ans = front_answer(req)
    except ParameterError as exc:
        row.update(status="error", message=str(exc), field=exc.field)
        return row
    except NotApplicableError as exc:
        tau = timescale(req.bead_dry_radius_um, req.t_end, req.constants).seconds
        row.update(status="needs-full", model="full", message=str(exc), timescale_seconds=tau)
        return row
    except SolverError as exc:
        row.update(status="error", message=f"the front model could not answer: {exc}")
        return row
    except (ArithmeticError, ValueError) as exc:
        row.update(status="error", message=f"the computation failed at this point: {exc}")
        return row
    row.update(status="answered", model=ans.model, time=ans.time, seconds=ans.seconds,
               timescale_seconds=ans.timescale_seconds, final_radius_um=ans.final_radius_um,
               expelled_volume_ul=ans.expelled_volume_ul, stored_volume_ul=ans.stored_volume_ul,
               error_estimate=ans.error_estimate)
    if point.get("size_cv") is not None:  # a batch of that CV (issue 26)
        from .batch_design import batch_row

        row.update(batch_row(req, point["size_cv"]))
    return row


def answer_chunk(points: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The rows of a chunk of points (the task an executor runs; top-level, so it pickles)."""
    return [answer_point(p) for p in points]


def chunks(points: list[dict[str, Any]], size: int = CHUNK_SIZE) -> list[list[dict[str, Any]]]:
    """Points grouped by jump (gel, T_end), each group cut into pieces of at most ``size``."""
    if size < 1:
        raise ParameterError("chunk_size", size, "an integer >= 1")
    groups: dict[tuple[int, float], list[dict[str, Any]]] = {}
    for p in points:
        groups.setdefault((p["gel_index"], p["t_end"]), []).append(p)
    return [g[i:i + size] for g in groups.values() for i in range(0, len(g), size)]


def select(rows: list[dict[str, Any]], which: str | Iterable[int]) -> list[int]:
    """Indices of the points to validate: a list of indices, 'all' (every point with no
    error) or 'needs-full' (the points only the full solver answers)."""
    if isinstance(which, str):
        if which == "all":
            return [r["index"] for r in rows if r["status"] != "error"]
        if which == "needs-full":
            return [r["index"] for r in rows if r["status"] == "needs-full"]
        raise ParameterError("validate", which, "'all', 'needs-full' or a list of indices")
    out = sorted({int(i) for i in which})
    for i in out:
        if not 0 <= i < len(rows):
            raise ParameterError("validate", i, f"point indices 0-{len(rows) - 1}")
    return out


@dataclass
class SweepResult:
    """The table of a sweep: one row per point (:data:`COLUMNS`), with the grid and timing."""

    COLUMNS: ClassVar[dict[str, tuple[str, str]]] = COLUMNS  # for the export layer
    grid: dict[str, Any]
    rows: list[dict[str, Any]]
    seconds: float = 0.0

    @property
    def counts(self) -> dict[str, int]:
        """Points per status."""
        out: dict[str, int] = {}
        for r in self.rows:
            out[r["status"]] = out.get(r["status"], 0) + 1
        return out

    def column(self, name: str) -> list[Any]:
        """One column, in point order."""
        return [r[name] for r in self.rows]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the grid, the columns with their units, the rows, counts, timing."""
        return {"grid": self.grid,
                "columns": [{"name": n, "unit": u, "description": d}
                            for n, (u, d) in COLUMNS.items()],
                "rows": self.rows, "counts": self.counts, "seconds": self.seconds}

    def to_json(self) -> str:
        """:meth:`to_dict` as strict JSON (non-finite numbers as null)."""
        import json

        return json.dumps(json_safe(self.to_dict()))

    def to_csv(self) -> str:
        """The rows as CSV; each header is ``name [unit]`` (units of '1' are fractions)."""
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow([f"{n} [{u}]" if u else n for n, (u, _) in COLUMNS.items()])
        for r in self.rows:
            w.writerow(["" if r[n] is None else (repr(r[n]) if isinstance(r[n], float)
                                                 else r[n]) for n in COLUMNS])
        return buf.getvalue()

    def to_dataframe(self) -> Any:
        """One row per point, columns ``name [unit]`` (pandas)."""
        return presenter("sweep_frame")(self)

    def to_xarray(self, request: Any = None) -> Any:
        """The map over (gel, t_end, dry_radius_um, dose_fraction) as an xarray Dataset."""
        return presenter("sweep_dataset")(self, request)



def _chunk_failed(chunk: list[dict[str, Any]], exc: BaseException) -> list[dict[str, Any]]:
    rows = []
    for p in chunk:
        row = _row(p)
        why = str(exc) or "no reason given"
        row.update(status="error", message=f"the executor failed on this chunk ({why})")
        rows.append(row)
    return rows


def _queue_validations(planner: Planner, rows: list[dict[str, Any]],
                       points: list[dict[str, Any]], indices: list[int]) -> None:
    for i in indices:
        row = rows[i]
        if row["status"] == "error":
            continue
        if row.get("size_cv") is not None:  # a batch: dosing.population.bands validates it
            note = "validation not queued: a batch's (validate_full on its dose request)"
            row["message"] = f"{row['message']}; {note}" if row["message"] else note
            continue
        try:
            row["validation_id"] = planner.submit_validation(point_request(points[i]))
        except (QueueFullError, ParameterError, SolverError) as exc:
            note = f"validation not queued: {exc}"
            row["message"] = f"{row['message']}; {note}" if row["message"] else note


def fill_validations(result: SweepResult, planner: Planner) -> int:
    """Poll the rows' validations on ``planner``; fill the truth's time and the front
    model's error of those done (a 'needs-full' row takes the truth's time and seconds).
    Returns how many are unfinished."""
    unfinished = 0
    for row in result.rows:
        vid = row.get("validation_id")
        if not vid or row.get("validation_status") in ("done", "failed"):
            continue
        try:
            st = planner.validation(vid)
        except Exception as exc:  # one bad point never poisons the table (issue 22, N4)
            row.update(validation_status="failed", message=f"validation failed: {exc}")
            continue
        row["validation_status"] = st.status
        if st.status in ("pending", "running"):
            unfinished += 1
        elif st.status == "failed":
            row["message"] = f"validation failed: {st.error}"
        else:
            rep = st.result
            row["truth_time"] = None if rep is None else rep.time
            row["front_time_error"] = None if rep is None else rep.front_time_error
            if row["status"] == "needs-full" and rep is not None and rep.time is not None:
                tau = row["timescale_seconds"]
                est, _ = error_estimate("full", rep.time, rep, row["dose_fraction"])
                row.update(time=rep.time, error_estimate=est,
                           seconds=None if tau is None else rep.time * tau)
    return unfinished


def run_sweep(grid: SweepGrid, executor: Executor | None = None, planner: Planner | None = None,
              validate: str | Iterable[int] = (),
              progress: Callable[[int], None] | None = None,
              chunk_size: int = CHUNK_SIZE) -> SweepResult:
    """Answer every point of ``grid`` with the front model.

    ``executor``: where the chunks run (None: in this thread); the rows do not depend on
    it.  ``validate``: points whose full-solver validation to queue on ``planner``
    (:func:`select`); their ids are in the ``validation_id`` column.  ``progress(n)`` is
    called as each chunk of n points finishes.
    """
    start = time.perf_counter()
    points = grid.points()
    rows: list[dict[str, Any] | None] = [None] * len(points)
    parts = chunks(points, chunk_size)

    def put(chunk_rows: list[dict[str, Any]]) -> None:
        for r in chunk_rows:
            rows[r["index"]] = r
        if progress is not None:
            progress(len(chunk_rows))

    if executor is None:
        for part in parts:
            put(answer_chunk(part))
    else:
        futs: dict[Future, list[dict[str, Any]]] = {
            executor.submit(answer_chunk, part): part for part in parts}
        for fut in as_completed(futs):
            exc = (RuntimeError("the chunk was cancelled (executor shut down)")
                   if fut.cancelled() else fut.exception())
            put(_chunk_failed(futs[fut], exc) if exc is not None else fut.result())
    table: list[dict[str, Any]] = [r for r in rows if r is not None]
    chosen = select(table, validate)
    if chosen:
        if planner is None:
            raise ParameterError("validate", validate, "no validations without a planner")
        _queue_validations(planner, table, points, chosen)
    return SweepResult(grid.to_dict(), table, time.perf_counter() - start)
