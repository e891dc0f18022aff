"""Errors raised by the solver layer: bad parameters name the field and its valid range."""

from __future__ import annotations

from typing import Any


class ParameterError(ValueError):
    """An input outside its valid range; ``field`` names it, ``valid`` states the range."""

    def __init__(self, field: str, value: Any, valid: str, reason: str = "") -> None:
        self.field = field
        self.value = value
        self.valid = valid
        msg = f"{field}={value!r} is invalid: valid range is {valid}"
        if reason:
            msg += f" ({reason})"
        super().__init__(msg)


class NotApplicableError(ValueError):
    """A model asked about a scenario outside its domain (e.g. the front model on a smooth jump)."""


class SolverError(RuntimeError):
    """Numerical failure (step budget, non-finite state, collapse); carries the diagnostics."""

    def __init__(self, message: str, diagnostics: dict[str, Any] | None = None) -> None:
        self.diagnostics = dict(diagnostics or {})
        super().__init__(message)


class BudgetExceeded(SolverError):
    """A run stopped by its wall-clock budget (``simulate(max_seconds=...)``)."""


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
