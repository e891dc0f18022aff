"""numba kernels that load numba only on their first compiled use.

``@kernel`` stands for ``@njit(cache=True)`` on the scalar kernels a Python caller also
calls (the thermodynamics of ``solver.thermo``, the front model's Chebyshev inversion and
lower hull).  Called from Python, a :class:`Kernel` runs the compiled function once this
process has one loaded (the full solver's, the service's after its warm-up) and its own
Python body otherwise: the same arithmetic, bit for bit (tests/test_speed_imports.py).  The
body runs with the C library's log, log1p, exp and expm1 in place of numpy's (:data:`LIBM`),
as the compiled kernel calls them: numpy's own (its SIMD code on AVX-512 machines) differ
in the last bit, and a front-model answer then moved by ~4e-14 with the way in.  A
one-off answer (a front-model CLI dose) then imports none of numba, 0.3-0.4 s of CPU, more
than its few calls cost in Python (docs/speed.md sec. 7).

A numba kernel that calls one binds :attr:`Kernel.compiled`, the numba dispatcher, at its
own import (numba cannot call a Python object); the dispatcher is built with every
:class:`Kernel` its body names replaced by theirs, and is cached on disk as ``@njit``'s.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from types import FunctionType
from typing import Any

import numpy as np


def _c_log(v: float) -> float:
    return math.log(v) if v > 0.0 else (-math.inf if v == 0.0 else math.nan)


def _c_log1p(v: float) -> float:
    return math.log1p(v) if v > -1.0 else (-math.inf if v == -1.0 else math.nan)


def _c_exp(v: float) -> float:
    try:
        return math.exp(v)
    except OverflowError:
        return math.inf


def _c_expm1(v: float) -> float:
    try:
        return math.expm1(v)
    except OverflowError:
        return math.inf


def _elementwise(scalar: Callable[[float], float]) -> Callable[[Any], Any]:
    """``scalar`` (a C library function, with its results at the poles and outside the
    domain) on a float or elementwise on an array."""
    vec = np.vectorize(scalar, otypes=[float])

    def f(x: Any) -> Any:
        if isinstance(x, np.ndarray):
            return vec(x) if x.size else np.empty(x.shape)
        return scalar(float(x))

    f.__name__ = scalar.__name__[3:]
    return f


class _LibmNumpy:
    """numpy, but log, log1p, exp and expm1 those of the C library (what a compiled kernel
    calls), for a Kernel's Python body."""

    log = staticmethod(_elementwise(_c_log))
    log1p = staticmethod(_elementwise(_c_log1p))
    exp = staticmethod(_elementwise(_c_exp))
    expm1 = staticmethod(_elementwise(_c_expm1))

    def __getattr__(self, name: str) -> Any:
        return getattr(np, name)


LIBM = _LibmNumpy()


class Kernel:
    """A function compiled by ``numba.njit(cache=True)`` on first compiled use."""

    def __init__(self, func: Callable[..., Any]) -> None:
        self.py_func = func
        self._dispatcher: Any = None
        self._body: Callable[..., Any] | None = None
        self.__name__ = func.__name__
        self.__qualname__ = func.__qualname__
        self.__module__ = func.__module__
        self.__doc__ = func.__doc__
        self.__wrapped__ = func

    @property
    def compiled(self) -> Any:
        """The numba dispatcher (built, and numba imported, on the first use)."""
        if self._dispatcher is None:
            from numba import njit

            func = self.py_func
            names = func.__globals__
            calls = {n: names[n].compiled for n in func.__code__.co_names
                     if isinstance(names.get(n), Kernel)}
            if calls:  # the body as numba sees it: the kernels it calls compiled
                func = FunctionType(func.__code__, {**names, **calls}, func.__name__,
                                    func.__defaults__, func.__closure__)
                func.__qualname__ = self.__qualname__
            self._dispatcher = njit(cache=True)(func)
        return self._dispatcher

    @property
    def loaded(self) -> bool:
        """True once this process holds a compiled signature of the kernel."""
        return self._dispatcher is not None and bool(self._dispatcher.signatures)

    @property
    def python_body(self) -> Callable[..., Any]:
        """The body as Python runs it: ``np`` the C library's transcendentals (:data:`LIBM`)."""
        if self._body is None:
            func = self.py_func
            if "np" in func.__code__.co_names:
                func = FunctionType(func.__code__, {**func.__globals__, "np": LIBM},
                                    func.__name__, func.__defaults__, func.__closure__)
                func.__qualname__ = self.__qualname__
            self._body = func
        return self._body

    def __call__(self, *args: Any) -> Any:
        d = self._dispatcher
        if d is not None and d.signatures:
            return d(*args)
        return self.python_body(*args)

    def __repr__(self) -> str:
        return f"<Kernel {self.__module__}.{self.__qualname__}>"


def kernel(func: Callable[..., Any]) -> Kernel:
    """``@kernel``: ``@njit(cache=True)``, numba loaded on the first compiled use."""
    return Kernel(func)
