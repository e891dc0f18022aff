"""numba kernels that load numba only on their first compiled use.

``@kernel`` stands for ``@njit(cache=True)`` on the scalar kernels a Python caller also
calls (the thermodynamics of ``solver.thermo``, the front model's Chebyshev inversion and
lower hull).  Called from Python, a :class:`Kernel` runs the compiled function once this
process has one loaded (the full solver's, the service's after its warm-up) and its own
Python body otherwise: the same arithmetic, bit for bit (tests/test_speed_imports.py).  A
one-off answer (a front-model CLI dose) then imports none of numba, 0.3-0.4 s of CPU, more
than its few calls cost in Python (docs/speed.md sec. 7).

A numba kernel that calls one binds :attr:`Kernel.compiled`, the numba dispatcher, at its
own import (numba cannot call a Python object); the dispatcher is built with every
:class:`Kernel` its body names replaced by theirs, and is cached on disk as ``@njit``'s.
"""

from __future__ import annotations

from collections.abc import Callable
from types import FunctionType
from typing import Any


class Kernel:
    """A function compiled by ``numba.njit(cache=True)`` on first compiled use."""

    def __init__(self, func: Callable[..., Any]) -> None:
        self.py_func = func
        self._dispatcher: Any = None
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

    def __call__(self, *args: Any) -> Any:
        d = self._dispatcher
        if d is not None and d.signatures:
            return d(*args)
        return self.py_func(*args)

    def __repr__(self) -> str:
        return f"<Kernel {self.__module__}.{self.__qualname__}>"


def kernel(func: Callable[..., Any]) -> Kernel:
    """``@kernel``: ``@njit(cache=True)``, numba loaded on the first compiled use."""
    return Kernel(func)
