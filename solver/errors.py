"""Errors raised by the solver layer: bad parameters name the field and its valid range.

Every one pickles (``__reduce__``: its constructor's arguments, the value and diagnostics
made plain data when they are not), so an error raised in a process-pool worker comes back
to the parent as itself instead of breaking the pool (issue 40, R1).
"""

from __future__ import annotations

from typing import Any


class ParameterError(ValueError):
    """An input outside its valid range; ``field`` names it, ``valid`` states the range."""

    def __init__(self, field: str, value: Any, valid: str, reason: str = "") -> None:
        self.field = field
        self.value = value
        self.valid = valid
        self.reason = reason
        msg = f"{field}={value!r} is invalid: valid range is {valid}"
        if reason:
            msg += f" ({reason})"
        super().__init__(msg)

    def __reduce__(self) -> tuple[Any, ...]:
        return (_rebuild, (type(self), (self.field, _plain(self.value), self.valid, self.reason),
                           _plain(self.__dict__)))


class NotApplicableError(ValueError):
    """A model asked about a scenario outside its domain (e.g. the front model on a smooth jump)."""


class SolverError(RuntimeError):
    """Numerical failure (step budget, non-finite state, collapse); carries the diagnostics."""

    def __init__(self, message: str, diagnostics: dict[str, Any] | None = None) -> None:
        self.diagnostics = dict(diagnostics or {})
        super().__init__(message)

    def __reduce__(self) -> tuple[Any, ...]:
        return (_rebuild, (type(self), (str(self), _plain(self.diagnostics)),
                           _plain(self.__dict__)))


class BudgetExceeded(SolverError):
    """A run stopped by its wall-clock budget (``simulate(max_seconds=...)``)."""


def _plain(value: Any) -> Any:
    """``value`` if it pickles, else its repr, item by item in a dict or list (an error's
    payload crosses processes)."""
    import pickle

    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return type(value)(_plain(v) for v in value) if type(value) in (list, tuple) \
            else repr(value)
    try:
        pickle.dumps(value)
    except Exception:
        return repr(value)
    return value


def _rebuild(cls: type, args: tuple[Any, ...], state: dict[str, Any]) -> BaseException:
    """An error unpickled: constructed from ``args``, then its attributes (plain) restored."""
    exc = cls(*args)
    exc.__dict__.update(state)
    return exc


def require_finite_positive(field: str, value: float) -> float:
    """Return ``value`` as float if finite and > 0, else raise :class:`ParameterError`."""
    import math

    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ParameterError(field, value, "a finite number > 0") from None
    if not math.isfinite(x) or x <= 0.0:
        raise ParameterError(field, value, "a finite number > 0")
    return x


def require_finite(field: str, value: float) -> float:
    """Return ``value`` as float if finite, else raise :class:`ParameterError`."""
    import math

    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ParameterError(field, value, "a finite number") from None
    if not math.isfinite(x):
        raise ParameterError(field, value, "a finite number")
    return x
