"""Results in the forms the field uses: xarray Datasets, netCDF files and tidy CSV.

Every variable carries CF-style ``units`` (UDUNITS spellings: "1" for a dimensionless
number, "s", "K", "um", "uL") and a ``long_name``; time is given dimensionless (units of
tau, eq. timescale) and, where a bead size is known, in seconds; lengths in dry radii and,
with a bead size, in micrometres.  Every file carries its provenance as global attributes:
the code version (package version and ``git describe`` when run from a checkout), the
request that made the result (JSON), the truth used (in words) and the creation time.

netCDF is written with xarray's ``scipy`` engine (netCDF3 64-bit offset: no compiled
library beyond scipy); xarray and pandas are imported inside the functions only, so
importing :mod:`dosing` stays light.  A CSV header cell is ``name [unit]``.
"""

from __future__ import annotations

import datetime as _dt
import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from solver.json_safe import json_safe

from ..provenance import code_version, resolved, version_info

if TYPE_CHECKING:  # pragma: no cover
    import xarray as xr

    from solver.fit import FitResult
    from solver.full import FullResult
    from solver.solute.result import ReleaseResult

    from ..question.schedule import ScheduleAnswer
    from ..studies.sweep import SweepResult

NETCDF_ENGINE = "scipy"  # netCDF3; needs scipy only
CONVENTIONS = "CF-1.8"


# ---------------------------------------------------------------------------- provenance
def _jsonable(obj: Any) -> Any:
    if hasattr(obj, "to_dict"):
        obj = obj.to_dict()
    elif hasattr(obj, "__dataclass_fields__"):
        from dataclasses import asdict

        obj = asdict(obj)
    return json_safe(obj)


def _request(request: Any) -> Any:
    """The request as exported: resolved, with the unit of every physical field."""
    value = _jsonable(request)
    return resolved(value) if isinstance(value, dict) else value


def provenance(kind: str, request: Any = None, truth: str | None = None,
               **extra: Any) -> dict[str, Any]:
    """Global attributes of an export: what it is, the code version, the request (JSON),
    the truth used, the creation time (UTC), and ``extra`` (JSON for non-scalars)."""
    attrs: dict[str, Any] = {
        "Conventions": CONVENTIONS,
        "title": f"thermogel {kind}",
        "source": "thermogel (Butler & Montenegro-Johnson thermo-responsive gel model)",
        "thermogel_kind": kind,
        "thermogel_version": code_version(),
        "history": f"{_dt.datetime.now(_dt.timezone.utc).isoformat(timespec='seconds')} "
                   f"created by thermogel {code_version()}",
        "version": json.dumps(version_info()),
        "request": json.dumps(_request(request)) if request is not None else "",
        "truth": truth or "",
    }
    for k, v in extra.items():
        attrs[k] = _attr(v)
    return attrs


def _attr(v: Any) -> Any:
    """A netCDF3-safe attribute value (str, float, int32; anything else as JSON)."""
    if isinstance(v, bool):
        return int(v)
    if isinstance(v, (int, np.integer)) and abs(int(v)) < 2**31:
        return np.int32(v)
    if isinstance(v, (float, np.floating)):
        return float(v) if math.isfinite(v) else str(v)
    if isinstance(v, str):
        return v
    return json.dumps(_jsonable(v))


def _var(dims: tuple[str, ...] | str, data: Any, units: str, long_name: str,
         **more: str) -> tuple[Any, ...]:
    arr = np.asarray(data)
    if arr.dtype.kind in "iu":
        arr = arr.astype(np.int32)
    elif arr.dtype.kind == "b":
        arr = arr.astype(np.int8)
    return (dims, arr, {"units": units, "long_name": long_name, **more})


def _floats(values: Sequence[Any]) -> np.ndarray:
    return np.array([np.nan if v is None else float(v) for v in values], dtype=float)


# ---------------------------------------------------------------------------- runs
def run_dataset(res: FullResult, dry_radius_um: float | None = None,
                timescale_seconds: float | None = None, request: Any = None,
                truth: str | None = None) -> xr.Dataset:
    """A full run (:class:`solver.full.FullResult`) as an xarray Dataset.

    Dimensions ``time`` (outputs), ``cell`` (profiles), ``step`` (accepted steps) and, on
    the moving grid, ``node``.  With ``dry_radius_um`` the radii are also in um; with
    ``timescale_seconds`` (tau, eq. timescale) the times also in s.
    """
    import xarray as xr

    t = np.asarray(res.t, dtype=float)
    coords: dict[str, Any] = {"time": _var("time", t, "1", "dimensionless time t / tau "
                                           "(eq. timescale)", axis="T")}
    data: dict[str, Any] = {
        "radius": _var("time", res.radius, "1", "bead radius a / dry radius"),
        "front": _var("time", res.front, "1", "front radius R_f / dry radius (NaN: no front)"),
    }
    optional = {
        "jump": ("1", "porosity jump at the front, core minus shell"),
        "temperature": ("K", "temperature"),
        "expelled_volume": ("1", "expelled fluid volume / (dry radius^3) "
                                 "(eq. FluidVolExpelled)"),
        "solid_error": ("1", "relative solid-volume error"),
    }
    for name, (unit, long) in optional.items():
        arr = np.asarray(getattr(res, name))
        if arr.size == t.size:
            data[name] = _var("time", arr, unit, long)
    if res.phi.size:
        data["phi"] = _var(("time", "cell"), res.phi, "1", "porosity phi (eq. FloryParam)")
        coord_name = ("R = r / a" if res.grid == "eulerian"
                      else "dry coordinate rho / dry radius")
        coords["cell"] = _var("cell", res.coords, "1", f"cell centre, {coord_name}")
        if res.nodes.size:
            nodes = np.asarray(res.nodes, dtype=float)
            data["nodes"] = _var(("time", "node"), nodes, "1",
                                 "dry node radii / dry radius (moving grid)", csv="omit")
            if nodes.shape[1] == res.phi.shape[1] + 1:
                data["cell_radius"] = _var(("time", "cell"), 0.5 * (nodes[:, 1:] + nodes[:, :-1]),
                                           "1", "dry radius of the cell centre / dry radius "
                                           "(moving grid: the cells follow the interface)")
    if res.step_t.size:
        data["step_time"] = _var("step", res.step_t, "1", "time of each accepted step / tau")
        for name, long in (("step_radius", "bead radius a / dry radius at each step"),
                           ("step_rate", "da/dt at each step (dry radii per tau)"),
                           ("step_edge", "edge cell porosity at each step")):
            arr = np.asarray(getattr(res, name))
            if arr.size == res.step_t.size:
                data[name] = _var("step", arr, "1", long)
    if timescale_seconds is not None:
        coords["seconds"] = _var("time", t * timescale_seconds, "s", "time")
    if dry_radius_um is not None:
        data["radius_um"] = _var("time", np.asarray(res.radius) * dry_radius_um, "um",
                                 "bead radius")
        data["front_um"] = _var("time", np.asarray(res.front) * dry_radius_um, "um",
                                "front radius")
    diag = dict(res.diagnostics)
    attrs = provenance("full run", request, truth, grid=res.grid,
                       spinodal=bool(res.spinodal), diagnostics=diag,
                       dry_radius_um=dry_radius_um if dry_radius_um is not None else "",
                       timescale_seconds=(timescale_seconds if timescale_seconds is not None
                                          else ""))
    if res.meta:  # without the boundary states older runs kept in meta (now the run's own)
        attrs["meta"] = _attr({k: v for k, v in res.meta.items() if k != "boundary_states"})
    return xr.Dataset(data, coords=coords, attrs=attrs)


def run_from_dataset(ds: xr.Dataset) -> FullResult:
    """The :class:`FullResult` a :func:`run_dataset` holds (profiles, steps, diagnostics)."""
    from solver.full import FullResult

    def get(name: str) -> np.ndarray:
        return np.asarray(ds[name].values, dtype=float) if name in ds else np.zeros(0)

    phi = get("phi") if "phi" in ds else np.zeros((0, 0))
    nodes = get("nodes") if "nodes" in ds else np.zeros((0, 0))
    return FullResult(
        t=np.asarray(ds["time"].values, dtype=float), radius=get("radius"), front=get("front"),
        jump=get("jump"), phi=phi, coords=get("cell") if "cell" in ds.coords else np.zeros(0),
        temperature=get("temperature"), expelled_volume=get("expelled_volume"),
        solid_error=get("solid_error"), spinodal=bool(ds.attrs.get("spinodal", 0)),
        diagnostics=json.loads(ds.attrs.get("diagnostics", "{}")), step_t=get("step_time"),
        step_radius=get("step_radius"), step_rate=get("step_rate"), step_edge=get("step_edge"),
        nodes=nodes)


def release_dataset(rel: ReleaseResult, dry_radius_um: float | None = None,
                    timescale_seconds: float | None = None, request: Any = None,
                    truth: str | None = None) -> xr.Dataset:
    """A drug release run (:class:`solver.solute.ReleaseResult`) as an xarray Dataset."""
    import xarray as xr

    t = np.asarray(rel.t, dtype=float)
    coords: dict[str, Any] = {"time": _var("time", t, "1", "dimensionless time t / tau",
                                           axis="T")}
    data = {
        "radius": _var("time", rel.radius, "1", "bead radius a / dry radius"),
        "released_fraction": _var("time", rel.released_fraction, "1",
                                  "released drug / loaded drug"),
        "squeezed_fraction": _var("time", rel.advected_fraction, "1",
                                  "drug squeezed out with the fluid / loaded drug"),
        "expelled_fraction": _var("time", rel.expelled_fraction, "1",
                                  "expelled fluid / stored fluid"),
        "in_gel_fraction": _var("time", rel.in_gel_fraction, "1", "drug in the gel / loaded"),
        "temperature": _var("time", rel.temperature, "K", "temperature"),
    }
    if np.asarray(rel.medium_concentration).size == t.size:
        data["medium_concentration"] = _var("time", rel.medium_concentration, "1",
                                            "medium concentration per loaded mass and volume "
                                            "4 pi R^3 / 3")
    if np.asarray(rel.profiles).size:
        coords["profile_time"] = _var("profile_time", rel.profile_t, "1",
                                      "profile time / tau")
        data["profiles"] = _var(("profile_time", "cell"), rel.profiles, "1",
                                "pore concentration c / c0")
        radii = np.asarray(rel.profile_radii)
        dims = ("profile_time", "cell") if radii.ndim == 2 else ("cell",)
        data["profile_radii"] = _var(dims, radii, "1", "cell-centre radius / dry radius")
    if timescale_seconds is not None:
        coords["seconds"] = _var("time", t * timescale_seconds, "s", "time")
    if dry_radius_um is not None:
        data["radius_um"] = _var("time", np.asarray(rel.radius) * dry_radius_um, "um",
                                 "bead radius")
    attrs = provenance("drug release run", request, truth,
                       mass_balance_error=float(rel.mass_balance_error),
                       effective_diffusivity=float(rel.effective_diffusivity),
                       diagnostics=rel.diagnostics)
    return xr.Dataset(data, coords=coords, attrs=attrs)


# ---------------------------------------------------------------------------- schedules
EVENT_COLUMNS: dict[str, tuple[str, str]] = {
    "dose": ("1", "dose number (1 = first)"),
    "time": ("1", "start of the heating on the protocol's clock / tau (hold reading)"),
    "seconds": ("s", "start of the heating on the protocol's clock"),
    "duration": ("1", "actuation (heating) time / tau"),
    "duration_seconds": ("s", "actuation (heating) time"),
    "temperature": ("K", "actuation temperature (T_end)"),
    "rest_after_seconds": ("s", "rest at T_start after this dose"),
    "rest_after": ("1", "rest after this dose / tau"),
    "dose_fraction": ("1", "this dose as a fraction of the stored fluid"),
    "cumulative_fraction": ("1", "doses so far as a fraction of the stored fluid"),
    "amount_ul": ("uL", "fluid volume released by this dose"),
    "error_estimate": ("1", "estimated relative error of the actuation time"),
    "corrected_duration": ("1", "actuation time found by shooting on the full solver / tau"),
    "corrected_duration_seconds": ("s", "actuation time found by shooting"),
}


def schedule_events(ans: ScheduleAnswer) -> dict[str, np.ndarray]:
    """One entry per dose of a schedule (:data:`EVENT_COLUMNS`): when its heating starts on
    the protocol's clock (previous heatings plus rests), how long, at what temperature,
    the dose and the fluid it releases."""
    n = len(ans.hold)
    tau = ans.timescale_seconds
    dur = _floats([r.actuation_time for r in ans.hold])
    rests = _floats(list(ans.rests) + [0.0])[:n]
    start = np.concatenate([[0.0], np.cumsum(dur + rests)[:-1]]) if n else np.zeros(0)
    tau_f = np.nan if tau is None else float(tau)
    rest_s = rests  # ScheduleRequest rests are in units of tau
    stored_ul = np.nan if ans.stored_volume_ul is None else ans.stored_volume_ul
    doses = _floats([r.dose_fraction for r in ans.hold])
    corr = (ans.corrected or {}).get("actuation_times")
    corr_d = _floats(corr) if corr and len(corr) == n else np.full(n, np.nan)
    t_end = getattr(ans, "t_end", None)
    return {
        "dose": np.arange(1, n + 1), "time": start, "seconds": start * tau_f,
        "duration": dur, "duration_seconds": dur * tau_f,
        "temperature": np.full(n, np.nan if t_end is None else float(t_end)),
        "rest_after_seconds": rest_s * tau_f, "rest_after": rest_s,
        "dose_fraction": doses,
        "cumulative_fraction": _floats([r.cumulative_fraction for r in ans.hold]),
        "amount_ul": doses * stored_ul,
        "error_estimate": _floats([r.error_estimate for r in ans.hold]),
        "corrected_duration": corr_d, "corrected_duration_seconds": corr_d * tau_f,
    }


def schedule_dataset(ans: ScheduleAnswer, request: Any = None) -> xr.Dataset:
    """A schedule as an event table Dataset (dimension ``dose``)."""
    import xarray as xr

    ev = schedule_events(ans)
    data = {k: _var("dose", v, *EVENT_COLUMNS[k]) for k, v in ev.items() if k != "dose"}
    coords = {"dose": _var("dose", ev["dose"], "1", EVENT_COLUMNS["dose"][1])}
    attrs = provenance("schedule", request, ans.truth, model=ans.model, note=ans.note,
                       timescale_formula=ans.timescale_formula,
                       scenario_key=ans.scenario_key,
                       stored_volume_ul=(ans.stored_volume_ul if ans.stored_volume_ul
                                         is not None else ""))
    return xr.Dataset(data, coords=coords, attrs=attrs)


# ---------------------------------------------------------------------------- sweeps
def sweep_dataset(sw: SweepResult, request: Any = None) -> xr.Dataset:
    """A design map as a Dataset over (gel, t_end, dry_radius_um, dose_fraction): every
    numeric column of :data:`dosing.studies.sweep.COLUMNS` (NaN where a point has none) and the
    text columns (status, model, behaviour, message) as strings."""
    import xarray as xr

    COLUMNS = sw.COLUMNS
    g = sw.grid
    gels = [x.get("name", "custom") for x in g["gels"]]
    shape = (len(gels), len(g["t_ends"]), len(g["dry_radii_um"]), len(g["doses"]))
    rows = sorted(sw.rows, key=lambda r: r["index"])
    dims = ("gel", "t_end", "dry_radius_um", "dose_fraction")
    coords = {
        "gel": ("gel", np.array(gels, dtype=str), {"long_name": "gel name", "units": ""}),
        "t_end": _var("t_end", _floats(g["t_ends"]), "K", COLUMNS["t_end"][1]),
        "dry_radius_um": _var("dry_radius_um", _floats(g["dry_radii_um"]), "um",
                              COLUMNS["dry_radius_um"][1]),
        "dose_fraction": _var("dose_fraction", _floats(g["doses"]), "1",
                              COLUMNS["dose_fraction"][1]),
    }
    skip = {"index", "gel_index", "gel", "t_end", "dry_radius_um", "dose_fraction", "t_start"}
    data: dict[str, Any] = {}
    for name, (unit, desc) in COLUMNS.items():
        if name in skip:
            continue
        col = [r.get(name) for r in rows]
        if unit in ("", None) or any(isinstance(v, str) for v in col):
            arr = np.array(["" if v is None else str(v) for v in col], dtype=str)
            data[name] = (dims, arr.reshape(shape), {"long_name": desc, "units": ""})
        else:
            un = "1" if unit == "tau" else unit.replace("uL", "uL")
            long = desc + (" (units of tau)" if unit == "tau" else "")
            data[name] = _var(dims, _floats(col).reshape(shape), un, long)
    attrs = provenance("design map (sweep)", request if request is not None else g,
                       "front model answers; error_estimate is the front model's prior "
                       "until a validation is cached", t_start=float(g["t_start"]),
                       seconds=float(sw.seconds))
    return xr.Dataset(data, coords=coords, attrs=attrs)


# ---------------------------------------------------------------------------- fits
PARAMETER_UNITS: dict[str, str] = {
    "omega": "1", "a0": "1", "b0": "1/K", "a1": "1", "b1": "1/K", "tau": "s", "scale": "1",
    "beta": "1",
}


def fit_dataset(fit: FitResult, request: Any = None, units: Mapping[str, str] | None = None
                ) -> xr.Dataset:
    """A fit as a Dataset over ``parameter``: estimate, 95% interval, standard error,
    covariance and correlation (parameter x parameter_), with the fit's statistics and
    warnings as attributes."""
    import xarray as xr

    table = {**PARAMETER_UNITS, **dict(units or {})}
    names = list(fit.names)
    iv = [fit.intervals.get(n) or [None, None] for n in names]
    unit_of = [table.get(n.removeprefix("log_"), "") for n in names]
    data = {
        "estimate": _var("parameter", _floats([fit.parameters[n] for n in names]), "",
                         "fitted value (units: the parameter's 'unit')"),
        "lower": _var("parameter", _floats([v[0] for v in iv]), "",
                      "lower end of the 95% interval"),
        "upper": _var("parameter", _floats([v[1] for v in iv]), "",
                      "upper end of the 95% interval"),
        "stderr": _var("parameter", _floats([fit.stderr.get(n) for n in names]), "",
                       "standard error"),
        "unit": ("parameter", np.array(unit_of, dtype=str),
                 {"long_name": "unit of each parameter", "units": ""}),
    }
    cov = np.asarray(fit.covariance, dtype=float)
    if cov.shape == (len(names), len(names)):
        data["covariance"] = _var(("parameter", "parameter_"), cov, "",
                                  "covariance of the reported parameters")
        data["correlation"] = _var(("parameter", "parameter_"), np.asarray(fit.correlation),
                                   "1", "correlation of the reported parameters")
    coords = {"parameter": ("parameter", np.array(names, dtype=str),
                            {"long_name": "fitted parameter", "units": ""}),
              "parameter_": ("parameter_", np.array(names, dtype=str),
                             {"long_name": "fitted parameter", "units": ""})}
    attrs = provenance("fit", request, "weighted least squares, linearised 95% intervals",
                       success=bool(fit.success), message=fit.message, nfev=int(fit.nfev),
                       n_points=int(fit.n_points), rms_residual=float(fit.rms_residual),
                       chi2_reduced=float(fit.chi2_reduced), fixed=fit.fixed,
                       warnings=fit.warnings, extra=fit.extra)
    return xr.Dataset(data, coords=coords, attrs=attrs)


# ---------------------------------------------------------------------------- files
def to_netcdf(ds: xr.Dataset, path: str | Path) -> Path:
    """Write ``ds`` to a netCDF file (the suffix .nc is added if missing)."""
    p = Path(path)
    if p.suffix != ".nc":
        p = p.with_name(p.name + ".nc")
    ds.to_netcdf(p, engine=NETCDF_ENGINE)
    return p


def open_netcdf(path: str | Path) -> xr.Dataset:
    """Read a file written by :func:`to_netcdf` (loaded into memory, the file closed)."""
    import xarray as xr

    with xr.open_dataset(Path(path), engine=NETCDF_ENGINE) as ds:
        return ds.load()


def header(name: str, unit: str | None) -> str:
    """A tidy CSV header cell: ``name [unit]`` (no brackets without a unit)."""
    return f"{name} [{unit}]" if unit else name


# A CSV export is bounded: every table is estimated before it is written (rows x columns x
# CSV_CELL_BYTES) and a table above CSV_MAX_BYTES is not written (the series: refused
# whole; the profiles: left out, with a note naming .nc, which stores them compactly).
CSV_MAX_BYTES = 50 * 2**20
CSV_CELL_BYTES = 22  # a float64 written by pandas (repr: up to 17 digits, sign, exponent, comma)
# a table's file beside the series' (run.csv -> run.profiles.csv), by the dimension it adds
TABLE_NAMES = {"cell": "profiles", "step": "steps", "node": "nodes",
               "parameter_": "covariance"}
# provenance lines written before the header of every CSV table
CSV_ATTRS = ("thermogel_kind", "thermogel_version", "version", "history", "truth", "request")


def _groups(ds: xr.Dataset) -> list[tuple[tuple[str, ...], list[str]]]:
    """The data variables grouped by their dimensions, the series' group (most variables,
    then fewest dimensions) first."""
    by: dict[tuple[str, ...], list[str]] = {}
    for name, var in ds.data_vars.items():
        by.setdefault(tuple(var.dims), []).append(str(name))
    order = sorted(by.items(), key=lambda kv: (-len(kv[1]), len(kv[0])))
    if not order:
        return []
    main, rest = order[0], order[1:]
    # a variable on fewer dimensions joins a wider table that holds them all (the profiles'
    # cell radii beside the profiles), never the series'
    merged: list[tuple[tuple[str, ...], list[str]]] = []
    for dims, names in sorted(rest, key=lambda kv: -len(kv[0])):
        home = next((m for m in merged if set(dims) < set(m[0])), None)
        if home is None:
            merged.append((dims, list(names)))
        else:
            home[1].extend(names)
    return [main, *merged]


def _table_name(dims: tuple[str, ...], main_dims: tuple[str, ...]) -> str:
    extra = [d for d in dims if d not in main_dims] or list(dims)
    for d in extra:
        if d in TABLE_NAMES:
            return TABLE_NAMES[d]
    return "_".join(extra)


def table_size(ds: xr.Dataset, names: Sequence[str]) -> tuple[int, int]:
    """(rows, columns) of the tidy table of the variables ``names`` (long form over their
    dimensions, with their coordinates)."""
    dims = sorted({d for n in names for d in ds[n].dims})
    rows = int(np.prod([ds.sizes[d] for d in dims])) if dims else 1
    coords = [c for c in ds.coords if set(ds[c].dims) <= set(dims)]
    return rows, len(names) + len(coords) + len(dims)


def dataset_frame(ds: xr.Dataset) -> Any:
    """A tidy pandas DataFrame of ``ds`` (one row per coordinate combination), its columns
    named ``name [unit]`` and the provenance in ``DataFrame.attrs``.  For a Dataset whose
    variables have different dimensions (a run's series, profiles and steps) it is the
    series' table (:func:`csv_tables` gives the others)."""
    groups = _groups(ds)
    if len(groups) > 1:
        ds = ds[groups[0][1]]
    df = ds.to_dataframe().reset_index()
    return _named(ds, df)


def _named(ds: xr.Dataset, df: Any) -> Any:
    names = {}
    for col in df.columns:
        var = ds[col] if col in ds.variables else None
        names[col] = header(col, None if var is None else var.attrs.get("units"))
    df = df.rename(columns=names)
    df.attrs.update({k: v for k, v in ds.attrs.items()})
    return df


class CsvTooLarge(ValueError):
    """A table too large for CSV (the message names .nc)."""


def csv_tables(ds: xr.Dataset, max_bytes: int = CSV_MAX_BYTES
               ) -> tuple[list[tuple[str, Any]], list[str]]:
    """The tidy tables of ``ds``: ``[("", series), (name, table), ...]`` (a table per
    further set of dimensions, long form: one row per time and cell for the profiles) and
    notes on the tables left out because they would exceed ``max_bytes`` of CSV.  The
    series' table above ``max_bytes`` raises :class:`CsvTooLarge`."""
    omit = [str(n) for n, v in ds.data_vars.items() if v.attrs.get("csv") == "omit"]
    ds = ds.drop_vars(omit)
    groups = _groups(ds)
    tables: list[tuple[str, Any]] = []
    notes: list[str] = [f"{', '.join(omit)} only in .nc"] if omit else []
    main_dims = groups[0][0] if groups else ()
    for i, (dims, names) in enumerate(groups):
        rows, cols = table_size(ds, names)
        size = rows * cols * CSV_CELL_BYTES
        name = "" if i == 0 else _table_name(dims, main_dims)
        if size > max_bytes:
            what = (f"{', '.join(names)} over {' x '.join(dims)}: {rows:,} rows, about "
                    f"{size / 2**20:,.0f} MB of CSV (at most {max_bytes / 2**20:,.0f} MB)")
            if i == 0:
                raise CsvTooLarge(f"the table {what}: write .nc (netCDF keeps it in binary), "
                                  "or ask for fewer outputs")
            notes.append(f"{name} not written as CSV ({what}): write .nc for them")
            continue
        sub = ds[names]
        frame = sub.to_dataframe().reset_index()
        keep = [c for c in frame.columns if c in sub.variables]
        tables.append((name, _named(sub, frame[keep])))
    return tables, notes


def csv_path(path: str | Path, name: str) -> Path:
    """The file of table ``name`` beside ``path`` (run.csv -> run.profiles.csv)."""
    p = Path(path)
    return p if not name else p.with_name(f"{p.stem}.{name}{p.suffix or '.csv'}")


def _write_csv(ds: xr.Dataset, p: Path, df: Any, notes: Sequence[str] = ()) -> None:
    lines = [f"# {k}: {v}" for k, v in ds.attrs.items() if k in CSV_ATTRS]
    lines += [f"# note: {n}" for n in notes]
    with p.open("w", encoding="utf-8", newline="") as fh:
        fh.write("\n".join(lines) + ("\n" if lines else ""))
        df.to_csv(fh, index=False, lineterminator="\n")


def write_csv(ds: xr.Dataset, path: str | Path, max_bytes: int = CSV_MAX_BYTES
              ) -> tuple[list[Path], list[str]]:
    """Write ``ds`` as tidy CSV tables: the series at ``path`` and each further table
    (profiles long form, steps) beside it (``run.csv`` -> ``run.profiles.csv``), every one
    with ``name [unit]`` headers and the provenance as '# key: value' lines before the
    header (``pandas.read_csv(path, comment="#")`` reads it back).  Returns the files and
    the notes on tables left out (too large: .nc holds them)."""
    tables, notes = csv_tables(ds, max_bytes)
    written = []
    others = [csv_path(path, name).name for name, _ in tables if name]
    for name, df in tables:
        p = csv_path(path, name)
        extra = list(notes)
        if not name and others:
            extra.insert(0, "further tables: " + ", ".join(others))
        _write_csv(ds, p, df, extra if not name else ())
        written.append(p)
    return written, notes


def to_csv(ds: xr.Dataset, path: str | Path) -> Path:
    """Write ``ds`` as tidy CSV (:func:`write_csv`); the series' file."""
    return write_csv(ds, path)[0][0]


def save(ds: xr.Dataset, path: str | Path) -> Path:
    """Write ``ds`` by its suffix: .nc (netCDF), .csv (tidy CSV) or .xlsx (Excel, needs
    openpyxl)."""
    p = Path(path)
    if p.suffix == ".csv":
        return to_csv(ds, p)
    if p.suffix == ".xlsx":
        tables, _ = csv_tables(ds)
        import pandas as pd

        with pd.ExcelWriter(p) as xl:
            for name, df in tables:
                df.to_excel(xl, sheet_name=name or "series", index=False)
        return p
    return to_netcdf(ds, p)


def events_dataset(events: Sequence[dict[str, Any]], attrs: dict[str, Any] | None = None
                   ) -> Any:
    """The events as an xarray Dataset over ``step`` (units and long names on every
    variable; text columns as strings; None as NaN), with ``attrs``."""
    import xarray as xr

    from ..question.events import EVENT_COLUMNS

    n = len(events)
    data: dict[str, Any] = {}
    for name, (unit, long_name) in EVENT_COLUMNS.items():
        if name == "step":
            continue
        values = [e.get(name) for e in events]
        if unit == "" or name in ("kind", "program", "reading"):
            arr = np.array(["" if v is None else str(v) for v in values], dtype=str)
        elif name in ("heating", "rough"):
            arr = np.array([int(v or 0) for v in values], dtype=np.int32)
        else:
            arr = np.array([np.nan if v is None else float(v) for v in values], dtype=float)
        data[name] = ("step", arr, {"units": unit, "long_name": long_name})
    coords = {"step": ("step", np.arange(1, n + 1, dtype=np.int32),
                       {"units": "1", "long_name": EVENT_COLUMNS["step"][1]})}
    return xr.Dataset(data, coords=coords, attrs=dict(attrs or {}))


def schedule_result_dataset(res: Any, request: Any = None) -> xr.Dataset:
    """Any schedule (every cell) as its events Dataset, with provenance, the reading and
    the headline: what ``thermogel schedule --out`` writes."""
    attrs = provenance("schedule events", request, res.truth, model=res.model,
                       reading=res.reading, headline=res.headline, note=res.note)
    return events_dataset(res.events, attrs)
