"""FullResult: the plain-data outcome of a full PDE run (arrays plus diagnostics)."""

from __future__ import annotations

import json
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from ..crossing import first_fall, hermite_root
from ..json_safe import json_safe

_ARRAYS = ("t", "radius", "front", "jump", "phi", "coords", "temperature", "expelled_volume",
           "solid_error", "step_t", "step_radius", "step_rate", "step_edge", "nodes")




@dataclass
class FullResult:
    """Outputs of :func:`solver.full.simulate` (dimensionless, as in the paper).

    Per output time t: radius a(t), front R_f(t) (r units, NaN without a sharp front),
    porosity jump at the front (core minus shell, NaN without a front), porosity
    snapshots phi (len(t), n) at ``coords`` (cell centres: R = r/a on the Eulerian grid,
    the dry coordinate rho on the Lagrangian grid), temperature, expelled fluid volume
    (eq. FluidVolExpelled) and the relative solid-volume error.  ``step_*`` hold a,
    da/dt and the edge cell's porosity at every accepted step (dense a(t) for crossing
    times; the time a front nucleates at the edge).  On the moving grid ``nodes`` holds
    every output's dry node radii (len(t), n + 1), the cells ``phi`` refers to, and
    ``coords`` the last output's cell midpoints; on fixed grids it is empty.
    """

    t: np.ndarray
    radius: np.ndarray
    front: np.ndarray
    jump: np.ndarray
    phi: np.ndarray
    coords: np.ndarray
    temperature: np.ndarray
    expelled_volume: np.ndarray
    solid_error: np.ndarray
    spinodal: bool = False
    diagnostics: dict[str, Any] = field(default_factory=dict)
    step_t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    step_radius: np.ndarray = field(default_factory=lambda: np.zeros(0))
    step_rate: np.ndarray = field(default_factory=lambda: np.zeros(0))
    step_edge: np.ndarray = field(default_factory=lambda: np.zeros(0))
    nodes: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))

    @property
    def grid(self) -> str:
        """'eulerian', 'lagrangian' or 'moving'."""
        return str(self.diagnostics.get("grid", "eulerian"))

    def nucleation_time(self, level: float) -> float:
        """First time the edge cell's porosity falls to ``level`` (NaN if it never does):
        with a level between the swollen and shrunken porosities, when the front forms."""
        return first_fall(self.step_t, self.step_edge, level)

    def time_to_radius(self, a_target: float) -> float:
        """First time at which a(t) crosses ``a_target`` (cubic Hermite between steps).

        Raises ValueError if the radius never reaches it.
        """
        target = float(a_target)
        if self.step_t.size >= 2:
            t, a, d = self.step_t, self.step_radius, self.step_rate
        else:
            t, a = self.t, self.radius
            d = np.gradient(a, t) if t.size >= 2 else np.zeros_like(a)
        if a.size and a[0] == target:
            return float(t[0])
        s = np.sign(a - target)
        idx = np.nonzero(s[:-1] * s[1:] <= 0)[0]
        if idx.size == 0:
            raise ValueError(f"the radius never reaches {target:g} "
                             f"(range {a.min():.6g} to {a.max():.6g} over t <= {t[-1]:.6g})")
        k = int(idx[0])
        if t[k + 1] <= t[k]:
            return float(t[k])
        return float(hermite_root(t[k], t[k + 1], a[k], a[k + 1], d[k], d[k + 1], target))

    def state_at(self, time: float) -> tuple[float, float, np.ndarray]:
        """(a, R_f, phi profile) at ``time``, interpolated linearly between outputs."""
        x = float(time)
        if not (self.t[0] <= x <= self.t[-1]):
            raise ValueError(f"time {x:g} outside the run [{self.t[0]:g}, {self.t[-1]:g}]")
        k = int(np.searchsorted(self.t, x, side="right") - 1)
        k = min(max(k, 0), self.t.size - 1)
        if k == self.t.size - 1 or self.t[k + 1] == self.t[k]:
            return float(self.radius[k]), float(self.front[k]), self.phi[k].copy()
        w = (x - self.t[k]) / (self.t[k + 1] - self.t[k])
        a = (1 - w) * self.radius[k] + w * self.radius[k + 1]
        fr = (1 - w) * self.front[k] + w * self.front[k + 1]
        return float(a), float(fr), (1 - w) * self.phi[k] + w * self.phi[k + 1]

    def cell_radii(self) -> np.ndarray:
        """Cell-centre radii r at every output, shape (len(t), n)."""
        if self.grid == "eulerian":
            return self.radius[:, None] * self.coords[None, :]
        n = self.coords.size
        if self.nodes.size:
            w = np.diff(self.nodes**3, axis=1)
            r3 = np.cumsum(w / (1.0 - self.phi), axis=1)
        else:
            w = np.diff((np.arange(n + 1) / n) ** 3)
            r3 = np.cumsum(w[None, :] / (1.0 - self.phi), axis=1)
        lo = np.concatenate([np.zeros((r3.shape[0], 1)), r3[:, :-1]], axis=1)
        return np.cbrt(0.5 * (lo + r3))

    def to_json_dict(self, profiles: bool = True) -> dict[str, Any]:
        """JSON-ready dict (NaN -> None); ``profiles=False`` drops the phi snapshots."""
        out: dict[str, Any] = {}
        for name in _ARRAYS:
            if name in ("phi", "nodes") and not profiles:
                continue
            if name == "nodes" and not self.nodes.size:
                continue
            out[name] = getattr(self, name)
        out["spinodal"] = bool(self.spinodal)
        out["diagnostics"] = self.diagnostics
        return json_safe(out)

    def save(self, path: str | Path) -> Path:
        """Write to an .npz file (arrays plus the diagnostics as JSON)."""
        p = Path(path)
        arrays = {name: np.asarray(getattr(self, name)) for name in _ARRAYS}
        np.savez_compressed(p, spinodal=np.array(bool(self.spinodal)),
                            diagnostics=np.array(json.dumps(json_safe(self.diagnostics))),
                            **arrays)
        return p if p.suffix == ".npz" else p.with_name(p.name + ".npz")

    @classmethod
    def load(cls, path: str | Path) -> FullResult:
        """Read a file written by :meth:`save`."""
        with np.load(Path(path), allow_pickle=False) as data:
            kwargs: dict[str, Any] = {}
            for f in fields(cls):
                if f.name in _ARRAYS and f.name in data:
                    kwargs[f.name] = np.array(data[f.name])
            kwargs["spinodal"] = bool(data["spinodal"])
            kwargs["diagnostics"] = json.loads(str(data["diagnostics"]))
        return cls(**kwargs)
