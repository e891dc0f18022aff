"""Temperature programs: typed steps in dimensionless time (tau), validated, compiled to
flat float rows a numba kernel evaluates (T(t) and dT/dt), and the mobility factor m(T).

A :class:`Program` is a list of steps run from the bead's start temperature:
:class:`Hold` (a temperature, jumped to, for a duration or until a condition),
:class:`Ramp` (linear to a target at a rate in K per tau), :class:`Bath` (a first-order lag
from the current temperature towards a target with a time constant, for a duration or
until a condition) and :class:`Trace` (measured times and temperatures, linear in between,
times from the step's start).  Until-conditions: :class:`Radius` (the bead radius reaches a
value) and :class:`Released` (a fraction of the fluid the bead held at t = 0 has left, a
radius by eq. FluidVolExpelled: a^3 = a0^3 - f (a0^3 - 1)).  After the last step the bead
holds at the last temperature.  Every error is a ParameterError naming ``steps[k].field``.

The mobility (docs/heating.md).  Stresses are scaled by k_B T_ref / Omega_p and time by
tau(T_ref) (eq. timescale); the free energy (eqs. FreeEnergy-MixingEnergy) is k_B T times a
function of the stretches and chi(T, phi) (eq. FloryParam), and Darcy's flux (eq. Darcy) is
k/eta times the pressure gradient, so at temperature T every rate is multiplied by

    m(T) = (T / T_ref) * eta(T_ref) / eta(T)

('kT': eta constant; 'water': Vogel's law for water, eta = 2.414e-5 Pa s 10^(247.8 K/(T -
140 K)); 'constant': m = 1, the paper's choice).  302 -> 308 K with T_ref = 308 K: m(302) =
0.9805 ('kT') and 0.866 ('water').
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numba import njit

from .errors import ParameterError
from .gel import T_MAX, T_MIN, check_temperature
from .limits import PROGRAM_RATE_MAX, PROGRAM_STEP_MAX, TRACE_ROWS_MAX, UNTIL_LIMIT

MOBILITIES = ("constant", "kT", "water")
Mobility = Literal["constant", "kT", "water"]
MOBILITY_CODES = {name: k for k, name in enumerate(MOBILITIES)}
DURATION_MAX = PROGRAM_STEP_MAX  # tau (solver.limits)
RATE_MAX = PROGRAM_RATE_MAX  # K per tau
# a piece row: [t0, t1, kind, T0, p, q]; kind LINEAR: T = T0 + p (t - t0);
# kind LAG: T = q + (T0 - q) exp(-(t - t0) / p)
LINEAR, LAG = 0, 1
HEAD = 6  # columns of every row; the header row: [A0, B0, A1, B1, mobility code, T_ref]


@njit(cache=True)
def mobility_factor(code, temp, t_ref):
    """m(T) relative to T_ref: 1 (code 0), T/T_ref (1), T/T_ref eta_w(T_ref)/eta_w(T) (2)."""
    if code == 0:
        return 1.0
    m = temp / t_ref
    if code == 2:
        m *= 10.0 ** (247.8 / (t_ref - 140.0) - 247.8 / (temp - 140.0))
    return m


@njit(cache=True)
def temperature_rate(heat, t):
    """(T, dT/dt) at time t of the pieces heat[1:] (rows [t0, t1, kind, T0, p, q], in time
    order); before the first piece its start, after the last its end (held: dT/dt = 0)."""
    k = heat.shape[0] - 1
    lo = 1
    hi = k
    if t < heat[1, 0]:
        return heat[1, 3], 0.0
    while lo < hi:  # the last piece with t0 <= t
        mid = (lo + hi + 1) // 2
        if heat[mid, 0] <= t:
            lo = mid
        else:
            hi = mid - 1
    row = heat[lo]
    hold = t > row[1]
    s = min(t, row[1]) - row[0]
    if row[2] == LINEAR:
        return row[3] + row[4] * s, 0.0 if hold else row[4]
    e = math.exp(-s / row[4])
    return row[5] + (row[3] - row[5]) * e, 0.0 if hold else -(row[3] - row[5]) * e / row[4]


def _number(where: str, value: Any, lo: float, hi: float, valid: str,
            open_lo: bool = True) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ParameterError(where, value, valid) from None
    if isinstance(value, bool) or not math.isfinite(x) or x > hi or x < lo or (
            open_lo and x == lo):
        raise ParameterError(where, value, valid)
    return x


@dataclass(frozen=True)
class Radius:
    """Until the bead radius (dry radii) reaches ``value`` (from the side it is on)."""

    value: float

    def radius(self, a0: float) -> float:
        """The target radius."""
        return float(self.value)

    def check(self, where: str) -> Radius:
        """Validated copy (ParameterError naming ``where``)."""
        return Radius(_number(f"{where}.radius", self.value, 1.0, 1e3,
                              "a radius > 1 (dry radii)"))


@dataclass(frozen=True)
class Released:
    """Until a fraction of the fluid held at t = 0 has left: a^3 = a0^3 - f (a0^3 - 1)
    (eq. FluidVolExpelled)."""

    fraction: float

    def radius(self, a0: float) -> float:
        """The radius at which the fraction has left a bead of start radius a0."""
        return float(np.cbrt(a0**3 - self.fraction * (a0**3 - 1.0)))

    def check(self, where: str) -> Released:
        """Validated copy (ParameterError naming ``where``)."""
        f = _number(f"{where}.fraction", self.fraction, 0.0, 1.0, "0 < fraction < 1")
        if f >= 1.0:
            raise ParameterError(f"{where}.fraction", self.fraction, "0 < fraction < 1")
        return Released(f)


Until = Radius | Released


@dataclass(frozen=True)
class Piece:
    """One stretch of the compiled program: [t0, t1], LINEAR (T0 + p (t - t0)) or LAG
    (q + (T0 - q) exp(-(t - t0)/p)); ``until`` a target radius that ends its step early
    (None: none), ``step`` its step's index."""

    t0: float
    t1: float
    kind: int
    t_start: float
    p: float
    q: float = 0.0
    until: float | None = None
    step: int = 0

    def row(self) -> list[float]:
        """[t0, t1, kind, T0, p, q]."""
        return [self.t0, self.t1, float(self.kind), self.t_start, self.p, self.q]

    @property
    def constant(self) -> bool:
        """True if T does not change on this piece."""
        return self.kind == LINEAR and self.p == 0.0

    def temperature(self, t: float) -> float:
        """T at time t in [t0, t1] (clamped)."""
        s = min(max(t, self.t0), self.t1) - self.t0
        if self.kind == LINEAR:
            return self.t_start + self.p * s
        return self.q + (self.t_start - self.q) * math.exp(-s / self.p)


def _until(until: Any, where: str) -> Until | None:
    if until is None:
        return None
    if not isinstance(until, (Radius, Released)):
        raise ParameterError(f"{where}.until", until, "None, a Radius or a Released")
    return until.check(f"{where}.until")


def _bounded(duration: Any, until: Any, where: str) -> tuple[float, Until | None]:
    """(duration or the until-limit, validated until); one of them is needed."""
    u = _until(until, where)
    if duration is None:
        if u is None:
            raise ParameterError(f"{where}.duration", None, "a duration or an until-condition")
        return UNTIL_LIMIT, u
    return _number(f"{where}.duration", duration, 0.0, DURATION_MAX,
                   f"0 < duration <= {DURATION_MAX:g} (tau)"), u


@dataclass(frozen=True)
class Hold:
    """Hold at ``temperature`` (jumped to) for ``duration`` tau, or ``until`` a condition
    (``duration`` then bounds the wait; default UNTIL_LIMIT)."""

    temperature: float
    duration: float | None = None
    until: Until | None = None

    def checked(self, where: str) -> Hold:
        d, u = _bounded(self.duration, self.until, where)
        return Hold(check_temperature(self.temperature, f"{where}.temperature"), d, u)

    def pieces(self, t0: float, temp: float, k: int, a0: float) -> list[Piece]:
        target = None if self.until is None else self.until.radius(a0)
        return [Piece(t0, t0 + float(self.duration), LINEAR, self.temperature, 0.0,
                      until=target, step=k)]

    def final(self, temp: float) -> float:
        return self.temperature


@dataclass(frozen=True)
class Ramp:
    """Heat or cool linearly from the current temperature to ``target`` at ``rate`` K per
    tau (> 0; the sign follows the target)."""

    target: float
    rate: float

    def checked(self, where: str) -> Ramp:
        return Ramp(check_temperature(self.target, f"{where}.target"),
                    _number(f"{where}.rate", self.rate, 0.0, RATE_MAX,
                            f"0 < rate <= {RATE_MAX:g} (K per tau)"))

    def pieces(self, t0: float, temp: float, k: int, a0: float) -> list[Piece]:
        span = self.target - temp
        if span == 0.0:
            return []
        d = abs(span) / self.rate
        return [Piece(t0, t0 + d, LINEAR, temp, math.copysign(self.rate, span), step=k)]

    def final(self, temp: float) -> float:
        return self.target


@dataclass(frozen=True)
class Bath:
    """A first-order lag from the current temperature towards ``target`` with
    ``time_constant`` tau: T = target + (T_now - target) exp(-t / time_constant), for
    ``duration`` or ``until`` a condition."""

    target: float
    time_constant: float
    duration: float | None = None
    until: Until | None = None

    def checked(self, where: str) -> Bath:
        d, u = _bounded(self.duration, self.until, where)
        return Bath(check_temperature(self.target, f"{where}.target"),
                    _number(f"{where}.time_constant", self.time_constant, 0.0, DURATION_MAX,
                            f"0 < time_constant <= {DURATION_MAX:g} (tau)"), d, u)

    def pieces(self, t0: float, temp: float, k: int, a0: float) -> list[Piece]:
        target = None if self.until is None else self.until.radius(a0)
        if temp == self.target:
            return [Piece(t0, t0 + float(self.duration), LINEAR, temp, 0.0, until=target,
                          step=k)]
        return [Piece(t0, t0 + float(self.duration), LAG, temp, self.time_constant,
                      self.target, until=target, step=k)]

    def final(self, temp: float) -> float:
        return self.target  # the limit (the held temperature is the reached one)


@dataclass(frozen=True)
class Trace:
    """Measured temperatures at ``times`` (tau from the step's start, the first 0,
    increasing), linear in between; the bead jumps to the first temperature."""

    times: tuple[float, ...]
    temperatures: tuple[float, ...]

    def checked(self, where: str) -> Trace:
        try:
            t = np.asarray(self.times, dtype=float).ravel()
            temp = np.asarray(self.temperatures, dtype=float).ravel()
        except (TypeError, ValueError):
            raise ParameterError(f"{where}.times", self.times, "numbers") from None
        if not (2 <= t.size <= TRACE_ROWS_MAX) or temp.size != t.size:
            raise ParameterError(f"{where}.times", f"{t.size} times, {temp.size} temperatures",
                                 f"2-{TRACE_ROWS_MAX} (time, temperature) rows")
        bad = np.nonzero(~np.isfinite(t))[0]
        if bad.size:
            raise ParameterError(f"{where}.times[{bad[0]}]", t[bad[0]], "a finite time")
        if t[0] != 0.0:
            raise ParameterError(f"{where}.times[0]", t[0], "0 (times from the step's start)")
        bad = np.nonzero(np.diff(t) <= 0.0)[0]
        if bad.size:
            raise ParameterError(f"{where}.times[{bad[0] + 1}]", t[bad[0] + 1],
                                 f"> {t[bad[0]]:g} (increasing)")
        if t[-1] > DURATION_MAX:
            raise ParameterError(f"{where}.times[{t.size - 1}]", t[-1],
                                 f"<= {DURATION_MAX:g} (tau)")
        bad = np.nonzero(~(np.isfinite(temp) & (temp >= T_MIN) & (temp <= T_MAX)))[0]
        if bad.size:
            raise ParameterError(f"{where}.temperatures[{bad[0]}]", temp[bad[0]],
                                 f"{T_MIN}-{T_MAX} K (liquid water)")
        return Trace(tuple(t.tolist()), tuple(temp.tolist()))

    def pieces(self, t0: float, temp: float, k: int, a0: float) -> list[Piece]:
        t, v = self.times, self.temperatures
        return [Piece(t0 + t[i], t0 + t[i + 1], LINEAR, v[i],
                      (v[i + 1] - v[i]) / (t[i + 1] - t[i]), step=k)
                for i in range(len(t) - 1)]

    def final(self, temp: float) -> float:
        return self.temperatures[-1]


Step = Hold | Ramp | Bath | Trace


@dataclass(frozen=True)
class Program:
    """A temperature program: ``steps`` from the start temperature, the mobility law
    ('constant', 'kT', 'water'; module docstring) relative to ``reference`` (K; default the
    program's last temperature, the T_end of the paper's scales)."""

    steps: tuple[Step, ...]
    mobility: Mobility = "constant"
    reference: float | None = None

    def __post_init__(self) -> None:
        try:
            items = tuple(self.steps)
        except TypeError:
            raise ParameterError("steps", self.steps, "a list of Hold/Ramp/Bath/Trace") from None
        if not items:
            raise ParameterError("steps", [], "at least one step")
        out = []
        for k, step in enumerate(items):
            if not isinstance(step, (Hold, Ramp, Bath, Trace)):
                raise ParameterError(f"steps[{k}]", step, "a Hold, Ramp, Bath or Trace")
            out.append(step.checked(f"steps[{k}]"))
        if self.mobility not in MOBILITIES:
            raise ParameterError("mobility", self.mobility, " or ".join(map(repr, MOBILITIES)))
        ref = self.reference
        if ref is None:
            temp = 0.0
            for s in out:
                temp = s.final(temp)
            ref = temp
        object.__setattr__(self, "steps", tuple(out))
        object.__setattr__(self, "reference", check_temperature(ref, "reference"))

    @classmethod
    def from_protocol(cls, protocol: list[tuple[float, float]],
                      mobility: Mobility = "constant") -> Program:
        """The old piecewise-constant protocol [(duration, temperature), ...] as Holds."""
        return cls(tuple(Hold(float(temp), float(d)) for d, temp in protocol), mobility)

    @property
    def mobility_code(self) -> int:
        return MOBILITY_CODES[self.mobility]

    def rate_factor(self, temp: float) -> float:
        """m(T) of this program's mobility law (module docstring)."""
        return float(mobility_factor(self.mobility_code, float(temp), float(self.reference)))

    def header(self, gel: Any) -> np.ndarray:
        """The header row [A0, B0, A1, B1, mobility code, T_ref] for ``gel``."""
        return np.array([gel.a0, gel.b0, gel.a1, gel.b1, float(self.mobility_code),
                         float(self.reference)])

    @property
    def planned_duration(self) -> float:
        """The program's length with every until-step at its bound (Ramps from the
        previous step's end temperature; a first Ramp's length needs the start: see
        :meth:`pieces`)."""
        return float(sum(p.t1 - p.t0 for p in self.pieces(self.first_temperature)))

    @property
    def first_temperature(self) -> float:
        """The temperature the first step starts from if it sets one (Hold, Trace), else
        the reference."""
        s = self.steps[0]
        if isinstance(s, Hold):
            return s.temperature
        if isinstance(s, Trace):
            return s.temperatures[0]
        return float(self.reference)  # type: ignore[arg-type]

    def pieces(self, t_start: float, a0: float = 2.0,
               ends: dict[int, float] | None = None) -> list[Piece]:
        """All pieces from start temperature ``t_start`` at t = 0, until-steps lasting their
        bound or ending at ``ends[k]`` (the times their conditions were met)."""
        out: list[Piece] = []
        t, temp = 0.0, float(t_start)
        for k, step in enumerate(self.steps):
            for piece in step.pieces(t, temp, k, a0):
                if ends is not None and k in ends and piece.t0 >= ends[k]:
                    break
                if ends is not None and k in ends and piece.t1 > ends[k]:
                    piece = Piece(piece.t0, ends[k], piece.kind, piece.t_start, piece.p,
                                  piece.q, piece.until, k)
                out.append(piece)
                t, temp = piece.t1, piece.temperature(piece.t1)
        return out

    def table(self, t_start: float, ends: dict[int, float] | None = None) -> np.ndarray:
        """The compiled program as one float array for :func:`temperature_rate` (header row
        of zeros but the mobility code and T_ref, then one row per piece)."""
        pieces = self.pieces(t_start, ends=ends)
        if not pieces:
            pieces = [Piece(0.0, 0.0, LINEAR, float(t_start), 0.0)]
        head = [0.0, 0.0, 0.0, 0.0, float(self.mobility_code), float(self.reference)]
        return np.array([head] + [p.row() for p in pieces])

    def temperature(self, t_start: float, t: Any,
                    ends: dict[int, float] | None = None) -> np.ndarray:
        """T(t) (K) at times ``t`` (tau) of this program from ``t_start``."""
        heat = self.table(t_start, ends)
        tt = np.atleast_1d(np.asarray(t, dtype=float))
        return np.array([temperature_rate(heat, float(x))[0] for x in tt])

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form (the run record's diagnostics)."""
        steps = []
        for s in self.steps:
            d: dict[str, Any] = {"kind": type(s).__name__.lower()}
            for name in s.__dataclass_fields__:
                v = getattr(s, name)
                if isinstance(v, (Radius, Released)):
                    v = {type(v).__name__.lower(): float(getattr(v, next(iter(
                        v.__dataclass_fields__))))}
                elif isinstance(v, tuple):
                    v = list(v)
                d[name] = v
            steps.append(d)
        return {"steps": steps, "mobility": self.mobility, "reference": self.reference}
