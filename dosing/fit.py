"""Fitting a user's gel: CSV files, the kinetics models in seconds, and the JSON reports.

    from dosing.fit import read_swelling_csv, fit_swelling
    report = fit_swelling(read_swelling_csv("curve.csv"))      # FitResult + .to_dict()

The dimensionless fits are ``solver.fit``; here are the file formats (a header row; the
columns below, in any order), the choice between the front model and the full solver for
a shrinking curve, and tau <-> k0 through eq. timescale.

Swelling CSV: ``temperature_K`` and one of ``radius``, ``diameter``, ``volume_ratio`` (any
unit), optional ``weight``.  Kinetics CSV: ``time_s`` and one size column, optional
``weight``; time 0 is the jump.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Mapping
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from solver.errors import NotApplicableError, ParameterError, SolverError
from solver.fit import FitResult, SwellingData, fit_equilibrium, fit_gel
from solver.fit.equilibrium import SIZE_POWER
from solver.fit.kinetics import KineticsData, RadiusModel, fit_kinetics
from solver.gel import Gel

from .model_choice import choose_model, front_model_name, front_run
from .planner import Planner
from .request import resolve_dry_radius, resolve_gel, resolve_jump
from .scenario import Scenario, SolverSettings
from .units import BOLTZMANN, PhysicalConstants

SIZE_COLUMNS = tuple(SIZE_POWER)
KINETICS_MODELS = ("auto", "front", "front-sharp", "full")


# ---------------------------------------------------------------- CSV
MAX_CSV_BYTES = 8 << 20  # a measured curve is kB; a file this big is not one


def _read_table(source: str | Path, what: str, first: str) -> tuple[dict[str, np.ndarray], str]:
    """Columns of a CSV (file path or the text itself) as float arrays, and the size column."""
    text = source if isinstance(source, str) and "\n" in source else None
    if text is None:
        p = Path(source)
        if not p.is_file():
            raise ParameterError("file", str(source), "a readable CSV file")
        size = p.stat().st_size
        if size > MAX_CSV_BYTES:  # refused before it is read whole (issue 22, N15)
            raise ParameterError("file", str(source), f"a CSV of at most {MAX_CSV_BYTES} bytes",
                                 f"it has {size} bytes")
        try:
            text = p.read_text(encoding="utf-8-sig")
        except (OSError, UnicodeDecodeError) as exc:
            raise ParameterError("file", str(source), "a readable UTF-8 CSV file",
                                 str(exc)) from None
    try:
        rows = [r for r in csv.reader(io.StringIO(text)) if r and any(c.strip() for c in r)
                and not r[0].lstrip().startswith("#")]
    except csv.Error as exc:
        raise ParameterError("file", str(source)[:80], "a CSV file", str(exc)) from None
    if not rows:
        raise ParameterError("file", "empty", f"a CSV with a header row ({first}, one of "
                             f"{', '.join(SIZE_COLUMNS)})")
    header = [h.strip() for h in rows[0]]
    allowed = {first, "weight", *SIZE_COLUMNS}
    unknown = [h for h in header if h not in allowed]
    if unknown:
        raise ParameterError("columns", unknown, f"{what} columns {first}, one of "
                             f"{', '.join(SIZE_COLUMNS)}, optional weight",
                             f"unknown column name(s) {', '.join(map(repr, unknown))}")
    if len(set(header)) != len(header):
        raise ParameterError("columns", header, "each column once")
    if first not in header:
        raise ParameterError("columns", header, f"a {first} column")
    sizes = [h for h in header if h in SIZE_COLUMNS]
    if len(sizes) != 1:
        raise ParameterError("columns", header, f"exactly one size column among "
                             f"{', '.join(SIZE_COLUMNS)}")
    cols: dict[str, list[float]] = {h: [] for h in header}
    for i, row in enumerate(rows[1:], start=2):
        if len(row) != len(header):
            raise ParameterError(f"line {i}", row, f"{len(header)} values ({', '.join(header)})")
        for h, cell in zip(header, row, strict=False):
            c = cell.strip()
            try:
                v = float(c) if c else math.nan
            except ValueError:
                raise ParameterError(f"line {i}, {h}", c, "a number") from None
            cols[h].append(v)
    return {h: np.array(v, dtype=float) for h, v in cols.items()}, sizes[0]


def read_swelling_csv(source: str | Path) -> SwellingData:
    """Equilibrium swelling data from a CSV (module doc); ParameterError names the problem."""
    cols, kind = _read_table(source, "swelling", "temperature_K")
    return SwellingData(cols["temperature_K"], cols[kind], kind, cols.get("weight"))


def read_kinetics_csv(source: str | Path) -> KineticsData:
    """A shrinking curve from a CSV (module doc); ParameterError names the problem."""
    cols, kind = _read_table(source, "kinetics", "time_s")
    return KineticsData(cols["time_s"], cols[kind], kind, cols.get("weight"))


def swelling_data(temperature_K: Any, size: Any, kind: str = "radius",
                  weight: Any = None) -> SwellingData:
    """SwellingData from lists (the HTTP and Python way in)."""
    return SwellingData(np.asarray(temperature_K, float), np.asarray(size, float), kind,
                        None if weight is None else np.asarray(weight, float))


def kinetics_data(time_s: Any, size: Any, kind: str = "radius",
                  weight: Any = None) -> KineticsData:
    """KineticsData from lists."""
    return KineticsData(np.asarray(time_s, float), np.asarray(size, float), kind,
                        None if weight is None else np.asarray(weight, float))


# ---------------------------------------------------------------- equilibrium
def fit_swelling(data: SwellingData, *, sigma_t: float = 0.05, size_rel_sigma: float = 0.01,
                 fixed: Mapping[str, float] | None = None, n_starts: int = 6) -> FitResult:
    """Fit Omega, A0, B0, A1, B1 and the size scale (``solver.fit.fit_equilibrium``); the
    result's ``extra`` carries the fitted gel."""
    try:
        res = fit_equilibrium(data, sigma_t=sigma_t, size_rel_sigma=size_rel_sigma,
                              fixed=fixed, n_starts=n_starts)
    except (np.linalg.LinAlgError, ArithmeticError) as exc:
        raise SolverError(f"the swelling fit failed numerically: {exc}") from exc
    try:
        res.extra["gel"] = fit_gel(res).to_dict()
    except ParameterError as exc:  # a fit at a bound can leave an invalid gel
        res.warnings.append(f"the fitted parameters do not make a valid gel: {exc}")
    return res


def data_dict(data: SwellingData | KineticsData) -> dict[str, Any]:
    """The data as plain lists, as a CSV would hold them."""
    first = ("temperature_K", data.temperature) if isinstance(data, SwellingData) \
        else ("time_s", data.time)
    out = {first[0]: first[1].tolist(), data.kind: data.size.tolist()}
    if data.weight is not None:
        out["weight"] = data.weight.tolist()
    return out


# ---------------------------------------------------------------- kinetics
def front_radius_model(gel: Gel, t_start: float, t_end: float, branch: str,
                       sharp: bool = True) -> RadiusModel:
    """beta -> a(t) from the step-function front model (sharp-interface, or the paper's),
    constant after the front reaches the centre."""
    def for_beta(beta: float | None):
        g = gel if beta is None else gel.with_permeability("power", float(beta))
        fr = front_run(g, t_start, t_end, branch, sharp)
        c = fr.curve

        def radius(t: np.ndarray) -> np.ndarray:
            tt = np.clip(np.asarray(t, dtype=float), c.t_start, fr.t_stop)
            return np.asarray(c.radius(c.front_at(tt)), dtype=float)
        return radius
    return for_beta


def full_radius_model(gel: Gel, t_start: float, t_end: float, branch: str,
                      settings: SolverSettings, planner: Any) -> RadiusModel:
    """beta -> a(t) from one full-solver run at ``settings`` (cached by the planner), run
    until 99.8% of the change to the final equilibrium; constant after it."""
    jump = resolve_jump(gel, t_start, t_end, branch)
    need = jump.final_radius + 0.002 * (jump.start_radius - jump.final_radius)
    memo: dict[float | None, Any] = {}

    def for_beta(beta: float | None):
        key = None if beta is None else round(float(beta), 8)
        if key not in memo:
            g = gel if beta is None else gel.with_permeability("power", float(beta))
            traj = planner.trajectory(Scenario(g, t_start, t_end, branch=branch,
                                               settings=settings), need_radius=need)
            tt, aa = (traj.step_t, traj.step_radius) if traj.step_t.size >= 2 \
                else (traj.t, traj.radius)
            memo[key] = (np.asarray(tt), np.asarray(aa))
        tt, aa = memo[key]
        return lambda t: np.interp(np.asarray(t, dtype=float), tt, aa)
    return for_beta


def choose_kinetics_model(gel: Gel, t_start: float, t_end: float, branch: str,
                          settings: SolverSettings, model: str = "auto") -> tuple[str, str]:
    """(model, why): 'auto' takes the front model where the planner would."""
    if model not in KINETICS_MODELS:
        raise ParameterError("model", model, ", ".join(KINETICS_MODELS))
    if model != "auto":
        return model, "asked for"
    choice, why = choose_model(gel, t_start, t_end, branch)
    return (front_model_name(settings) if choice == "front" else "full"), why


@dataclass(frozen=True)
class KineticsOptions:
    """How a shrinking curve is fitted: the curve's ``model`` ('front-sharp' / 'front', the
    step-function front models, milliseconds per curve; 'full', one full-solver run per
    beta, cached, with ``settings``; 'auto', the planner's choice), whether to fit the
    permeability exponent (``fit_beta``; ``beta`` fixed, or its start) and the relative
    size noise ``size_rel_sigma``."""

    model: str = "auto"
    fit_beta: bool = False
    beta: float | None = None
    settings: SolverSettings | None = None
    size_rel_sigma: float = 0.01


def fit_shrinking(data: KineticsData, gel: Gel | str | dict[str, Any], t_start: float,
                  t_end: float, *, branch: str | None = None, dry_radius_um: float | None = None,
                  swollen_radius_um: float | None = None,
                  constants: PhysicalConstants | None = None, planner: Any = None,
                  options: KineticsOptions | None = None,
                  **option_fields: Any) -> FitResult:
    """Fit tau (s) and, with a bead size, k0 (m^2) of eq. timescale to a shrinking curve.

    ``options`` (or its fields as keywords): a :class:`KineticsOptions`.  With a front
    model only k0 k(phi_+) enters the curve, so beta cannot be fitted there
    (ParameterError); with 'full' each beta costs a solver run.
    """
    try:
        opts = replace(options or KineticsOptions(), **option_fields)
    except TypeError as exc:
        raise ParameterError("options", sorted(option_fields), "fields of KineticsOptions: "
                             "model, fit_beta, beta, settings, size_rel_sigma") from exc
    model, fit_beta, beta = opts.model, opts.fit_beta, opts.beta
    settings, size_rel_sigma = opts.settings, opts.size_rel_sigma
    g = resolve_gel(gel)
    jump = resolve_jump(g, t_start, t_end, branch)
    settings = settings or SolverSettings()
    name, why = choose_kinetics_model(g, jump.t_start, jump.t_end, jump.branch, settings, model)
    if fit_beta and name != "full":
        raise ParameterError("fit_beta", True, "False with the front model, or model='full'",
                             "in the step-function front model the permeability enters only "
                             "as k0 k(phi_+), so beta and k0 are not separately identifiable")
    if beta is not None and not fit_beta:
        g = g.with_permeability("power", beta)
    owned = None
    if name == "full" and planner is None:
        planner = owned = Planner(executor=ThreadPoolExecutor(1))
    try:
        if name == "full":
            curve = full_radius_model(g, jump.t_start, jump.t_end, jump.branch, settings,
                                      planner)
        else:
            curve = front_radius_model(g, jump.t_start, jump.t_end, jump.branch,
                                       sharp=name == "front-sharp")
        try:
            res = fit_kinetics(data, curve, fit_beta=fit_beta,
                               beta=beta if fit_beta else None, size_rel_sigma=size_rel_sigma)
        except NotApplicableError as exc:
            raise ParameterError("model", name, "'full' for this jump", str(exc)) from exc
        except (np.linalg.LinAlgError, ArithmeticError) as exc:
            raise SolverError(f"the kinetics fit failed numerically: {exc}") from exc
    finally:
        if owned is not None:
            owned.close()
            owned.jobs.executor.shutdown(wait=True)
    dry = resolve_dry_radius(dry_radius_um, swollen_radius_um, jump.start_radius)
    res.extra.update({"model": name, "model_reason": why, "t_start": jump.t_start,
                      "t_end": jump.t_end, "branch": jump.branch, "gel": g.to_dict(),
                      "tau_s": res.parameters["tau"], "tau_interval_s": res.intervals["tau"],
                      "dry_radius_um": dry})
    if dry is not None:
        c = constants or PhysicalConstants()
        res.extra["k0_m2"] = k0_from_tau(res.parameters["tau"], dry, jump.t_end, c)
        iv = res.intervals["tau"]
        res.extra["k0_interval_m2"] = None if iv is None else sorted(
            k0_from_tau(v, dry, jump.t_end, c) for v in iv)
        res.extra["constants"] = c.to_dict()
    return res


def k0_from_tau(tau_s: float, dry_radius_um: float, t_end: float,
                constants: PhysicalConstants) -> float:
    """k0 = eta Omega_p R^2 / (tau k_B T_end) (eq. timescale solved for k0), in m^2."""
    r = dry_radius_um * 1.0e-6
    return (constants.viscosity(t_end) * constants.polymer_volume_m3 * r * r
            / (tau_s * BOLTZMANN * t_end))
