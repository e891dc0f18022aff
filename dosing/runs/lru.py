"""One least-recently-used map bounded in bytes (issue 40, R7): the planner's caches of runs,
programs and mechanics, and the service's rendered tables, hold a memory budget, not a count.

:class:`ByteLRU`: an ``OrderedDict`` as those caches used it that evicts its oldest entries
past ``max_bytes`` (or ``max_items``); a value larger than the budget is not kept.  Sizes:
:func:`approx_size`, an estimate per insertion (docs/architecture.md, "The run store")."""

from __future__ import annotations

import sys
import threading
from collections import OrderedDict
from collections.abc import Callable, Hashable
from typing import Any

_SCALAR = 32  # bytes of a boxed float or int and its slot in a container
_DEPTH = 8


def approx_size(obj: Any, _seen: set[int] | None = None, _depth: int = 0) -> int:
    """Bytes an object holds, approximately: numpy arrays by ``nbytes``, strings and bytes
    by length, containers, dataclasses and plain objects by walking their items (each
    object counted once; long lists of numbers counted from their length)."""
    seen = set() if _seen is None else _seen
    if id(obj) in seen or _depth > _DEPTH:
        return 0
    seen.add(id(obj))
    if obj is None or isinstance(obj, (bool, int, float, complex)):
        return _SCALAR
    if isinstance(obj, (str, bytes, bytearray, memoryview)):
        return sys.getsizeof(obj)
    nbytes = getattr(obj, "nbytes", None)
    if isinstance(nbytes, int) and hasattr(obj, "dtype"):  # a numpy array (views: theirs)
        return nbytes + 112
    if isinstance(obj, (list, tuple, set, frozenset)):
        n = len(obj)
        if n > 64 and all(isinstance(x, (int, float)) for x in list(obj)[:8]):
            return 56 + n * _SCALAR  # a column of numbers
        return 56 + 8 * n + sum(approx_size(x, seen, _depth + 1) for x in obj)
    if isinstance(obj, dict):
        return 64 + 16 * len(obj) + sum(approx_size(k, seen, _depth + 1)
                                         + approx_size(v, seen, _depth + 1)
                                         for k, v in obj.items())
    fields = getattr(obj, "__dict__", None)
    total = 56
    if fields is not None:
        total += approx_size(fields, seen, _depth + 1)
    for name in getattr(type(obj), "__slots__", ()) or ():
        if isinstance(name, str) and hasattr(obj, name):
            total += approx_size(getattr(obj, name), seen, _depth + 1)
    return total


class ByteLRU(OrderedDict):
    """An OrderedDict used as an LRU, bounded in bytes (module doc).  Thread-safe for its
    own operations; ``on_evict(key)`` is called for each entry it drops."""

    def __init__(self, max_bytes: float, max_items: int | None = None,
                 sizeof: Callable[[Any], int] = approx_size,
                 on_evict: Callable[[Hashable], None] | None = None) -> None:
        super().__init__()
        self.max_bytes = int(max_bytes)
        self.max_items = max_items
        self.sizeof = sizeof
        self.on_evict = on_evict
        self._sizes: dict[Hashable, int] = {}
        self.nbytes = 0
        self._lock = threading.RLock()

    def __setitem__(self, key: Hashable, value: Any) -> None:
        size = int(self.sizeof(value))
        with self._lock:
            if key in self:
                self._drop(key, evicted=False)
            if size > self.max_bytes:  # never kept: it would evict everything
                if self.on_evict is not None:
                    self.on_evict(key)
                return
            super().__setitem__(key, value)
            self._sizes[key] = size
            self.nbytes += size
            self._shrink()

    def _drop(self, key: Hashable, evicted: bool) -> Any:
        value = super().pop(key)
        self.nbytes -= self._sizes.pop(key, 0)
        if evicted and self.on_evict is not None:
            self.on_evict(key)
        return value

    def _shrink(self) -> None:
        while self and (self.nbytes > self.max_bytes
                        or (self.max_items is not None and len(self) > self.max_items)):
            self._drop(next(iter(self)), evicted=True)

    def __delitem__(self, key: Hashable) -> None:
        with self._lock:
            self._drop(key, evicted=False)

    def get(self, key: Hashable, default: Any = None) -> Any:
        with self._lock:
            return super().get(key, default)

    def pop(self, key: Hashable, *default: Any) -> Any:
        with self._lock:
            if key not in self:
                if default:
                    return default[0]
                raise KeyError(key)
            return self._drop(key, evicted=False)

    def popitem(self, last: bool = True) -> tuple[Hashable, Any]:
        with self._lock:
            if not self:
                raise KeyError("popitem(): the cache is empty")
            key = next(reversed(self)) if last else next(iter(self))
            return key, self._drop(key, evicted=False)

    def move_to_end(self, key: Hashable, last: bool = True) -> None:
        with self._lock:
            super().move_to_end(key, last)

    def clear(self) -> None:
        with self._lock:
            super().clear()
            self._sizes.clear()
            self.nbytes = 0

    def __reduce__(self) -> Any:  # a cache is not state: it pickles empty
        return (type(self), (self.max_bytes, self.max_items))
