"""Measured series for the fits: the checks every (x, size) data set must pass."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import ParameterError

MAX_POINTS = 5000  # the nearest-point search holds points x stretch-grid arrays
SIZE_POWER = {"radius": 1, "diameter": 1, "volume_ratio": 3}  # size = scale * stretch^m


def _rows(index: np.ndarray) -> str:
    return ", ".join(str(i + 1) for i in index[:5])


def checked_series(x: Any, size: Any, kind: str, weight: Any, x_name: str,
                   per: str) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """(x, size, weight) as float arrays after the common checks: a known size ``kind``,
    at most MAX_POINTS points, one size (and weight) per ``per``, finite numbers, sizes > 0,
    weights > 0; a ParameterError names the column (``x_name`` or ``kind``) and the rows."""
    if kind not in SIZE_POWER:
        raise ParameterError("size_kind", kind, "radius, diameter or volume_ratio")
    xs = np.asarray(x, dtype=float).ravel()
    ys = np.asarray(size, dtype=float).ravel()
    if xs.size > MAX_POINTS:
        raise ParameterError("data", f"{xs.size} points", f"at most {MAX_POINTS} points")
    if xs.size != ys.size:
        raise ParameterError("size", f"{ys.size} values", f"{xs.size} values (one per {per})")
    for name, v in ((x_name, xs), (kind, ys)):
        bad = np.nonzero(~np.isfinite(v))[0]
        if bad.size:
            raise ParameterError(name, "NaN or infinite", "finite numbers", f"row(s) {_rows(bad)}")
    neg = np.nonzero(ys <= 0.0)[0]
    if neg.size:
        raise ParameterError(kind, float(ys[neg[0]]), "sizes > 0", f"row(s) {_rows(neg)} are <= 0")
    w = None
    if weight is not None:
        w = np.asarray(weight, dtype=float).ravel()
        if w.size != xs.size or not np.all(np.isfinite(w) & (w > 0.0)):
            raise ParameterError("weight", "invalid", "one finite weight > 0 per point")
    return xs, ys, w


class SizeSeries:
    """What the measured series share: the size column's power m (size = scale x
    stretch^m) and the number of points."""

    size: np.ndarray
    kind: str

    @property
    def power(self) -> int:
        """m in size = scale stretch^m."""
        return SIZE_POWER[self.kind]

    def __len__(self) -> int:
        return int(np.size(self.size))
