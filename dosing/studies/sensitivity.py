"""Global sensitivity of the dose time in seconds: Sobol indices and Morris screening (SALib).

Which input matters most for a dose time?  Each varied input (a request field name:
``dry_radius_um``, ``permeability_m2``, ``viscosity_pa_s``, ``polymer_volume_m3``,
``t_start``, ``t_end``, ``dose_fraction`` or a gel parameter of eq. FloryParam ``omega``,
``a0``, ``b0``, ``a1``, ``b1``) is drawn uniformly between its bounds, or log-uniformly
(uniform in log10) with ``log``.  Every sample is one dose request answered with the front
model (the planner's millisecond answer, :func:`dosing.model_choice.front_answer`): the
dimensionless time of eq. timescale's scaling depends only on the gel, the jump and the
dose, so it is computed once per distinct (gel, jump, dose) and multiplied by
tau = eta Omega_p R^2 / (k0 k_B T_end) of each sample.  Inputs that change the gel or the
jump cost a front trajectory each (~50 ms); the physical constants and the bead size cost
microseconds.

Sobol (Saltelli's sampling, ``SALib.sample.sobol``; first-order ``S1`` and total ``ST``
indices with 95% bootstrap intervals) for a few inputs, Morris elementary effects
(``mu_star``, ``sigma``) to screen many.  SALib is imported on use only.
"""

from __future__ import annotations

import math
import time as _time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from solver.errors import NotApplicableError, ParameterError, SolverError
from solver.gel import Gel
from solver.limits import DRY_RADIUS_UM_RANGE, T_MAX, T_MIN

from ..request import DoseRequest, resolve_gel
from ..units import PhysicalConstants, timescale

GEL_FIELDS = ("omega", "a0", "b0", "a1", "b1")
CONSTANT_FIELDS = ("viscosity_pa_s", "polymer_volume_m3", "permeability_m2")
REQUEST_FIELDS = ("dry_radius_um", "t_start", "t_end", "dose_fraction")
NAMES = REQUEST_FIELDS + CONSTANT_FIELDS + GEL_FIELDS
UNITS = {"dry_radius_um": "um", "t_start": "K", "t_end": "K", "dose_fraction": "1",
         "viscosity_pa_s": "Pa s", "polymer_volume_m3": "m^3", "permeability_m2": "m^2",
         "omega": "1", "a0": "1", "b0": "1/K", "a1": "1", "b1": "1/K"}
# each input's physical range (its unit's), the bounds a request's own fields have: a
# range beyond them is refused before sampling (issue 40, R6; gel parameters: finite, sane)
RANGES: dict[str, tuple[float, float]] = {
    "dry_radius_um": DRY_RADIUS_UM_RANGE, "t_start": (T_MIN, T_MAX), "t_end": (T_MIN, T_MAX),
    "dose_fraction": (0.0, 1.0), "viscosity_pa_s": (0.0, 10.0),
    "polymer_volume_m3": (0.0, 1e-20), "permeability_m2": (0.0, 1e-10),
    "omega": (0.0, 1e6), "a0": (-1e3, 1e3), "b0": (-1e3, 1e3), "a1": (-1e3, 1e3),
    "b1": (-1e3, 1e3)}
OPEN_BELOW = {"dose_fraction", "viscosity_pa_s", "polymer_volume_m3", "permeability_m2",
              "omega"}  # a bound the input may not reach (0 < x)
METHODS = ("sobol", "morris")
MAX_EVALUATIONS = 200_000  # model evaluations of one analysis
CONFIDENCE = 0.95
MORRIS_LEVELS = 4  # grid levels of Morris's trajectories


@dataclass(frozen=True)
class Vary:
    """One varied input: its request field name, bounds and whether log-uniform."""

    name: str
    low: float
    high: float
    log: bool = False

    def __post_init__(self) -> None:
        if self.name not in NAMES:
            raise ParameterError("vary", self.name, f"one of {', '.join(NAMES)}")
        lo, hi = float(self.low), float(self.high)
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise ParameterError(f"vary.{self.name}", [self.low, self.high],
                                 "two finite bounds with low < high")
        if self.log and lo <= 0.0:
            raise ParameterError(f"vary.{self.name}", [self.low, self.high],
                                 "positive bounds for a log-uniform input")
        a, b = RANGES[self.name]
        low_ok = lo > a if self.name in OPEN_BELOW else lo >= a
        if not (low_ok and hi <= b and (self.name != "dose_fraction" or hi < b)):
            op = "<" if self.name in OPEN_BELOW else "<="
            top = "<" if self.name == "dose_fraction" else "<="
            raise ParameterError(f"vary.{self.name}", [self.low, self.high],
                                 f"{a:g} {op} low < high {top} {b:g} {UNITS[self.name]}")
        object.__setattr__(self, "low", lo)
        object.__setattr__(self, "high", hi)

    @classmethod
    def parse(cls, text: str) -> Vary:
        """'NAME=LO:HI' or 'NAME=LO:HI:log' (the CLI's ``--vary``)."""
        try:
            name, rng = text.split("=", 1)
            parts = rng.split(":")
            if len(parts) not in (2, 3) or (len(parts) == 3 and parts[2] not in ("log", "lin")):
                raise ValueError
            lo, hi = float(parts[0]), float(parts[1])
        except ValueError:
            raise ParameterError("vary", text, "NAME=LO:HI or NAME=LO:HI:log") from None
        return cls(name.strip(), lo, hi, len(parts) == 3 and parts[2] == "log")

    def bounds(self) -> list[float]:
        """The sampling bounds (log10 of the bounds for a log-uniform input)."""
        return [math.log10(self.low), math.log10(self.high)] if self.log else [self.low,
                                                                             self.high]

    def values(self, u: np.ndarray) -> np.ndarray:
        """Samples in the sampling space -> the input's values."""
        return 10.0 ** u if self.log else u

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form."""
        return {"name": self.name, "low": self.low, "high": self.high, "log": self.log,
                "unit": UNITS[self.name]}


@dataclass
class SensitivityResult:
    """Sensitivity indices of the dose time in seconds, keyed by the varied names.

    Sobol: ``S1``, ``S1_conf``, ``ST``, ``ST_conf`` (95% half-widths); Morris: ``mu_star``,
    ``mu_star_conf``, ``sigma``, ``mu``.  ``output`` summarises the seconds over the samples.
    """

    method: str
    names: list[str]
    indices: dict[str, dict[str, float]]
    vary: list[dict[str, Any]]
    base: dict[str, Any]
    samples: int
    evaluations: int
    output: dict[str, float]
    seconds: float
    model: str = "front model (the planner's front-regime answer, eq. timescale for seconds)"
    notes: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form (JSON-ready)."""
        return {"method": self.method, "output": "dose time [s]", "names": self.names,
                "indices": self.indices, "vary": self.vary, "base": self.base,
                "samples": self.samples, "evaluations": self.evaluations,
                "output_summary": self.output, "seconds": self.seconds, "model": self.model,
                "confidence": CONFIDENCE, "notes": self.notes}

    def to_dataframe(self) -> Any:
        """One row per varied input, one column per index (pandas)."""
        import pandas as pd

        return pd.DataFrame([{"name": n, **self.indices[n]} for n in self.names])


@dataclass(frozen=True)
class Base:
    """The fixed part of the requests: gel, jump, dose, bead and constants."""

    gel: Gel
    t_start: float
    t_end: float
    dose_fraction: float
    dry_radius_um: float
    constants: PhysicalConstants
    branch: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form."""
        return {"gel": self.gel.to_dict(), "t_start": self.t_start, "t_end": self.t_end,
                "dose_fraction": self.dose_fraction, "dry_radius_um": self.dry_radius_um,
                "constants": self.constants.to_dict(), "branch": self.branch}


class DoseTimeModel:
    """Seconds of the front model's dose time for rows of input values (one column per
    varied name).  The first sample of each (gel, jump) is a full front-model answer
    (:func:`dosing.model_choice.front_answer`: the classifier's model choice and checks);
    its trajectory then serves every dose of that jump (eq. FluidVolExpelled's target
    radius, ``time_to_radius``), exactly as the answer reads it."""

    def __init__(self, base: Base, names: Sequence[str]) -> None:
        self.base, self.names = base, list(names)
        self._jumps: dict[tuple[Any, ...], tuple[Any, float]] = {}
        self.failures: list[tuple[dict[str, float], str]] = []

    def _time(self, gel: Gel, t_start: float, t_end: float, dose: float) -> float:
        from ..model_choice import front_answer, front_run
        from ..units import radius_after_dose

        if not 0.0 < dose < 1.0:
            raise ParameterError("dose_fraction", dose, "0 < dose_fraction < 1")
        key = (gel, t_start, t_end)
        if key not in self._jumps:
            req = DoseRequest(gel, t_start, t_end, dose_fraction=dose,
                              dry_radius_um=self.base.dry_radius_um,
                              constants=self.base.constants, branch=self.base.branch)
            ans = front_answer(req)
            fr = front_run(req.gel, req.t_start, req.t_end, req.branch,
                           req.settings.regularized)
            self._jumps[key] = (fr, req.start_radius)
            return ans.time
        fr, a0 = self._jumps[key]
        return float(fr.time_to_radius(radius_after_dose(a0, dose)))

    def one(self, values: Mapping[str, float]) -> float:
        """The dose time in seconds at one sample (raises as a dose request does)."""
        b = self.base
        gel_kw = {k: v for k, v in values.items() if k in GEL_FIELDS}
        gel = replace(b.gel, **gel_kw) if gel_kw else b.gel
        c_kw = {k: v for k, v in values.items() if k in CONSTANT_FIELDS}
        constants = replace(b.constants, **c_kw) if c_kw else b.constants
        t_start = values.get("t_start", b.t_start)
        t_end = values.get("t_end", b.t_end)
        t = self._time(gel, t_start, t_end, values.get("dose_fraction", b.dose_fraction))
        return t * timescale(values.get("dry_radius_um", b.dry_radius_um), t_end,
                             constants, omega=gel.omega).seconds

    def __call__(self, x: np.ndarray) -> np.ndarray:
        out = np.empty(x.shape[0])
        for i, row in enumerate(x):
            values = dict(zip(self.names, map(float, row), strict=True))
            try:
                out[i] = self.one(values)
            except (ParameterError, NotApplicableError, SolverError, ValueError,
                    ArithmeticError) as exc:
                out[i] = math.nan
                if len(self.failures) < 5:
                    self.failures.append((values, str(exc)))
        return out


def _base(gel: Gel | str | dict[str, Any], t_start: Any, t_end: Any, dose_fraction: float,
          dry_radius_um: Any, constants: PhysicalConstants | dict[str, Any] | None,
          branch: str | None) -> Base:
    from ..quantity import kelvin, micrometres

    c = (constants if isinstance(constants, PhysicalConstants)
         else PhysicalConstants.from_dict(constants))
    radius = micrometres(dry_radius_um, "dry_radius_um")
    lo, hi = RANGES["dry_radius_um"]
    if not lo <= radius <= hi:  # after the unit's conversion
        raise ParameterError("dry_radius_um", dry_radius_um, f"{lo:g}-{hi:g} um")
    base = Base(resolve_gel(gel), kelvin(t_start, "t_start"), kelvin(t_end, "t_end"),
                float(dose_fraction), radius, c, branch)
    # the base request itself must be answerable by the front model
    DoseTimeModel(base, []).one({})
    return base


def sensitivity(gel: Gel | str | dict[str, Any], t_start: Any, t_end: Any,
                dose_fraction: float, vary: Sequence[Vary | str | Mapping[str, Any]], *,
                dry_radius_um: Any = 50.0,
                constants: PhysicalConstants | dict[str, Any] | None = None,
                branch: str | None = None, method: str = "sobol", samples: int = 1000,
                seed: int = 0,
                max_trajectories: int | None = None) -> SensitivityResult:
    """Sobol (``S1``, ``ST``) or Morris (``mu_star``, ``sigma``) indices of the dose time in
    seconds over the ``vary`` ranges (``Vary``, 'NAME=LO:HI[:log]' or dicts), the other
    inputs at the base request's values.

    ``samples`` is the Sobol base sample N (N (D + 2) evaluations; a power of 2 is best)
    or the number of Morris trajectories (r (D + 1) evaluations).  A sample the front model
    cannot answer (a dose above the stored fluid, a jump without a front) is a
    ParameterError naming ``vary``: narrow the ranges.  ``max_trajectories`` bounds the
    front trajectories the inputs that change the gel or the jump can need (the HTTP
    service answers at once: about 50 ms each).
    """
    t0 = _time.perf_counter()
    if method not in METHODS:
        raise ParameterError("method", method, "'sobol' or 'morris'")
    vs = [v if isinstance(v, Vary) else Vary.parse(v) if isinstance(v, str) else Vary(**v)
          for v in vary]
    names = [v.name for v in vs]
    if not vs or len(set(names)) != len(names):
        raise ParameterError("vary", names, "one or more distinct input names")
    if not (isinstance(samples, int) and samples >= 4):
        raise ParameterError("samples", samples, "an integer >= 4")
    d = len(vs)
    evals = samples * (d + 2) if method == "sobol" else samples * (d + 1)
    if evals > MAX_EVALUATIONS:
        raise ParameterError("samples", samples, f"at most {MAX_EVALUATIONS} evaluations "
                             f"({evals} asked: samples x (inputs + 2) for Sobol)")
    costly = sum(n in GEL_FIELDS or n in ("t_start", "t_end") for n in names)
    trajectories = 0 if not costly else (min(evals, 2 * samples * costly)
                                         if method == "sobol" else evals)
    if max_trajectories is not None and trajectories > max_trajectories:
        raise ParameterError("samples", samples, f"at most {max_trajectories} front "
                             f"trajectories ({trajectories} asked: the gel parameters, t_start "
                             "and t_end need one per distinct value); fewer samples")
    base = _base(gel, t_start, t_end, dose_fraction, dry_radius_um, constants, branch)
    problem = {"num_vars": d, "names": names, "bounds": [v.bounds() for v in vs]}
    model = DoseTimeModel(base, names)
    if method == "sobol":
        from SALib.analyze import sobol as analyze
        from SALib.sample import sobol as sample

        u = sample.sample(problem, samples, calc_second_order=False, seed=seed)
    else:
        from SALib.analyze import morris as analyze
        from SALib.sample import morris as sample

        u = sample.sample(problem, samples, num_levels=MORRIS_LEVELS, seed=seed)
    x = np.column_stack([v.values(u[:, j]) for j, v in enumerate(vs)])
    y = model(x)
    bad = int(np.count_nonzero(~np.isfinite(y)))
    if bad:
        values, msg = model.failures[0]
        raise ParameterError("vary", [v.to_dict() for v in vs],
                             f"ranges the front model answers everywhere ({bad} of {y.size} "
                             f"samples failed, e.g. at {values}: {msg})")
    if method == "sobol":
        si = analyze.analyze(problem, y, calc_second_order=False, conf_level=CONFIDENCE,
                             seed=seed)
        keys = ("S1", "S1_conf", "ST", "ST_conf")
    else:
        si = analyze.analyze(problem, u, y, num_levels=MORRIS_LEVELS, conf_level=CONFIDENCE,
                             seed=seed)
        keys = ("mu", "mu_star", "mu_star_conf", "sigma")
    indices = {n: {k: float(si[k][j]) for k in keys} for j, n in enumerate(names)}
    q = np.quantile(y, [0.05, 0.5, 0.95])
    notes = []
    if method == "sobol":
        worst = max(max(i["S1_conf"], i["ST_conf"]) for i in indices.values())
        if worst > 0.1:
            notes.append(f"intervals up to +-{worst:.2f}: more samples narrow them")
    return SensitivityResult(
        method=method, names=names, indices=indices, vary=[v.to_dict() for v in vs],
        base=base.to_dict(), samples=samples, evaluations=int(y.size),
        output={"mean": float(y.mean()), "std": float(y.std()), "p05": float(q[0]),
                "median": float(q[1]), "p95": float(q[2])},
        seconds=_time.perf_counter() - t0, notes=notes)


def analytic_power_law_indices(bounds: Mapping[str, tuple[float, float]],
                               powers: Mapping[str, float]) -> dict[str, dict[str, float]]:
    """Exact Sobol indices of Y = prod_i X_i^{p_i} with independent log-uniform X_i on
    ``bounds`` (e.g. the dose time ~ R^2 / k0: powers {R: 2, k0: -1}).

    With m_i = E[X_i^p_i], s_i = E[X_i^(2 p_i)] (for log-uniform X on [a, b]:
    E[X^q] = (b^q - a^q) / (q ln(b / a))), Var Y = prod s - prod m^2,
    V_i = (s_i - m_i^2) prod_{j != i} m_j^2, and the total effect
    VT_i = (s_i - m_i^2) prod_{j != i} s_j.
    """
    def moment(a: float, b: float, q: float) -> float:
        return (b**q - a**q) / (q * math.log(b / a))

    names = list(bounds)
    m = {n: moment(*bounds[n], powers[n]) for n in names}
    s = {n: moment(*bounds[n], 2.0 * powers[n]) for n in names}
    var = math.prod(s.values()) - math.prod(v * v for v in m.values())
    out = {}
    for n in names:
        vi = s[n] - m[n] ** 2
        out[n] = {"S1": vi * math.prod(m[k] ** 2 for k in names if k != n) / var,
                  "ST": vi * math.prod(s[k] for k in names if k != n) / var}
    return out
