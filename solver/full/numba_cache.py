"""Keep numba's on-disk cache of this package consistent with its sources.

numba's ``cache=True`` invalidates a cached function only when its own file changes, not
when a kernel it calls in another file does (e.g. the integrator in rosenbrock.py inlines
the grids' kernels and solver/thermo.py).  Before the kernels are imported, this module
hashes every source they depend on and, when the hash changed, deletes this package's
cache files so everything recompiles together.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

_HERE = Path(__file__).resolve().parent
_STAMP = "thermogel_sources.sha256"


def _digest() -> str:
    h = hashlib.sha256()
    for path in sorted(_HERE.glob("*.py")) + [_HERE.parent / "thermo.py",
                                              _HERE.parent / "heating.py"]:
        h.update(path.name.encode())
        h.update(path.read_bytes())
    return h.hexdigest()


def refresh() -> None:
    """Drop stale cache files of solver/full (default cache location only)."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return
    cache = _HERE / "__pycache__"
    stamp = cache / _STAMP
    digest = _digest()
    try:
        if stamp.read_text() == digest:
            return
    except OSError:
        pass
    try:
        cache.mkdir(exist_ok=True)
        for f in list(cache.glob("*.nbi")) + list(cache.glob("*.nbc")):
            f.unlink(missing_ok=True)
        stamp.write_text(digest)
    except OSError:
        pass
