"""A drug's runs: what one is (``DrugScenario``: a protocol's mechanics from the start
state and the passive solute on them, eqs. PDE_Dimless to Boundary_Dimless and
``solver.solute.release``; ``run_drug_scenario``, the plain function any executor runs),
and where it is kept (``DrugRuns``: memory, then the cache file's ``drug_runs`` table, then
the store's executor; a run whose protocol starts with a kept run's steps continues from
that run's state: its mechanics, and its solute when it is the same drug)."""

from __future__ import annotations

import functools
import hashlib
import io
import json
import math
import threading
import time
from collections import OrderedDict
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from solver.errors import ParameterError, SolverError
from solver.gel import Gel
from solver.solute import ReleaseResult, Solute
from solver.solute.result import RELEASE_ARRAYS

from .cache import ValidationCache
from .lru import ByteLRU
from .scenario import NPZ_LOCK, RUN_BUDGET_S, Scenario, SolverSettings, Step, code_version

# mechanics samples per unit time (at least MIN_SAMPLES per step): benchmarks/drug.py measures
# the released fraction within 3e-3 of the load (1e-3 with sieving) at a cost <= 1.5 x
SAMPLES_PER_TAU = 2000
MIN_SAMPLES = 200
# and geometric outputs from EARLY_OUTPUT tau after each step's start up to its first uniform
# output, EARLY_PER_DECADE a decade: between outputs the solute code takes the bead to
# shrink linearly in time, which the first 5e-4 tau of a jump are not (issue 23's reduced
# drug model measured a fast drug's 10 % dose 17 % late without them, ANB, 1e-7 cm^2/s)
EARLY_OUTPUT = 1e-6
EARLY_PER_DECADE = 40


def drug_settings(settings: SolverSettings) -> SolverSettings:
    """The mechanics of a drug run: the fluid answers' own settings (issue 12: one truth).
    The direct truth runs on the moving grid at the bead's ell (the solute is resampled onto
    uniform dry cells, :func:`solver.solute.node_volumes`); a ladder runs its coarsest rung
    on the Lagrangian grid; the paper's model (ell = 0) moves to the Lagrangian grid with
    its N (the solute lives on the dry coordinate's cells)."""
    if settings.grid in ("lagrangian", "moving"):
        return settings
    return replace(settings, grid="lagrangian")


@dataclass(frozen=True)
class DrugScenario:
    """A dimensionless drug run: a protocol from the start state, and the solute."""

    gel: Gel
    t_start: float
    protocol: tuple[Step, ...]
    solute: Solute
    branch: str = "swollen"
    settings: SolverSettings = field(default_factory=SolverSettings)

    def mechanics(self) -> Scenario:
        """The mechanical scenario (on the Lagrangian grid)."""
        return Scenario(self.gel, self.t_start, protocol=self.protocol, branch=self.branch,
                        settings=drug_settings(self.settings))

    def key(self) -> str:
        """Cache key: the mechanics' key dict plus the solute and the drug code's version."""
        return self._key

    @functools.cached_property
    def _key(self) -> str:
        d = {"kind": "drug", "mechanics": self.mechanics().key_dict(),
             "solute": self.solute.to_dict(), "samples": SAMPLES_PER_TAU,
             "min_samples": MIN_SAMPLES, "drug_code": drug_code_version()}
        text = json.dumps(d, sort_keys=True, separators=(",", ":"))
        return "drug-" + hashlib.sha256(text.encode()).hexdigest()[:32]

    def to_dict(self) -> dict[str, Any]:
        """Plain data for a worker process."""
        return {"mechanics": self.mechanics().to_dict(), "solute": self.solute.to_dict()}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> DrugScenario:
        """Inverse of :meth:`to_dict`."""
        m = Scenario.from_dict(d["mechanics"])
        return cls(m.gel, m.t_start, m.protocol, Solute.from_dict(d["solute"]), m.branch,
                   m.settings)


@functools.cache
def drug_code_version() -> str:
    """Digest of what a drug run computes: the mechanics' code version, the solute sources,
    and the source of the functions here that set up, run and store it (not this module's
    other text: moving code around it keeps the stored runs)."""
    import inspect

    import solver.solute

    h = hashlib.sha256(code_version().encode())
    for p in sorted(Path(solver.solute.__file__).parent.glob("*.py")):
        h.update(p.name.encode())
        h.update(p.read_bytes())
    for obj in (DrugScenario, drug_settings, step_outputs, simulate_protocol,
                mechanics_prefix, run_drug_scenario, to_npz, from_npz):
        h.update(inspect.getsource(obj).encode())
    return h.hexdigest()[:16]


def step_outputs(duration: float, k: int) -> np.ndarray:
    """A protocol step's output times: k uniform intervals, and geometric ones
    (EARLY_PER_DECADE a decade from EARLY_OUTPUT) until their spacing reaches the uniform
    one, so that no interval is longer than either (the step's jump is fast at first)."""
    uniform = np.linspace(0.0, duration, k + 1)
    ratio = 10.0 ** (1.0 / EARLY_PER_DECADE)
    end = min(duration, uniform[1] / (ratio - 1.0))  # where t (ratio - 1) = the uniform dt
    if end <= EARLY_OUTPUT:
        return uniform
    m = int(math.ceil(EARLY_PER_DECADE * math.log10(end / EARLY_OUTPUT)))
    return np.union1d(uniform, np.geomspace(EARLY_OUTPUT, end, m + 1))


def simulate_protocol(gel: Gel, t_start: float, steps: list[Step], branch: str,
                      settings: SolverSettings, budget: float | None = None,
                      start: Any = None) -> Any:
    """The mechanics of a protocol: one ``simulate`` of its steps of positive duration,
    sampled densely after every step's start (:func:`step_outputs`; on the moving grid
    between steps, ``MeshOptions.land`` False: docs/moving_mesh.md sec. 8), within
    ``budget`` wall seconds; one FullResult with its state after every step.  ``start``:
    the mechanics of a protocol's first steps (a :func:`mechanics_prefix`), continued from
    its last state (``simulate(..., initial=state)``, joined by ``FullResult.after``)."""
    from .full import full_solver

    simulate = full_solver()
    from solver.full.moving import MeshOptions

    s = drug_settings(settings)
    if budget is None:
        from ..runs.scenario import run_budget

        budget = run_budget(RUN_BUDGET_S)
    run = [(float(d), temp) for d, temp in steps if d > 0.0]
    if not run:
        raise ParameterError("protocol", steps, "at least one step of positive duration")
    times, t0 = [], 0.0
    for duration, _ in run:
        k = max(MIN_SAMPLES, int(math.ceil(duration * SAMPLES_PER_TAU)))
        times.append(t0 + step_outputs(duration, k))
        t0 += duration
    state = None
    if start is not None and start.boundary_states:
        state = start.boundary_states[-1]
        if state.stopped or state.steps >= len(run):
            state = None
    kw: dict[str, Any] = {"branch": branch} if state is None else {"initial": state}
    if s.grid == "moving":  # dense outputs between steps (docs/moving_mesh.md sec. 8)
        kw["mesh"] = MeshOptions(land=False)
    res = simulate(gel, t_start, protocol=run, grid=s.grid, n=s.n, integrator=s.integrator,
                   rtol=s.rtol, saveat=np.concatenate(times), max_seconds=budget,
                   interfacial_length=s.interfacial_length, **kw)
    if state is not None:
        res = res.after(start)
    res.diagnostics["mechanics_from_step"] = 0 if state is None else int(
        start.diagnostics.get("prefix_steps", state.steps))
    return res


def mechanics_prefix(res: Any, steps: tuple[Step, ...]) -> Any:
    """The mechanics of a :func:`simulate_protocol` run up to the end of the protocol's
    first steps ``steps`` (its state after those of positive duration), as a FullResult of
    the same kind; None if it kept no state there."""
    state = res.boundary_state(sum(1 for d, _ in steps if d > 0.0))
    if state is None:
        return None
    cut = res.truncated(state.t)
    cut.diagnostics = {**res.diagnostics, "prefix_steps": len(steps)}
    return cut


def run_drug_scenario(scenario: dict[str, Any], budget: float | None = None,
                      start: Any = None, keep: bool = False,
                      solute_from: ReleaseResult | None = None) -> tuple[Any, ...]:
    """A drug run: plain data in, (metadata, npz blob) out (for any executor); ``start``
    the mechanics of its protocol's first steps (:func:`mechanics_prefix`) to continue, and
    ``solute_from`` the stored drug run those mechanics came from, whose solute continues
    from the same boundary where it kept its state (``solver.solute.SoluteStart``; else the
    solute runs from t = 0); ``keep``: (metadata, blob, the mechanics) out, for the next
    run to start from."""
    from solver.solute import SoluteStart, release

    sc = DrugScenario.from_dict(scenario)
    wall = time.perf_counter()
    res = simulate_protocol(sc.gel, sc.t_start, list(sc.protocol), sc.branch, sc.settings, budget,
                            start)
    mech = time.perf_counter() - wall
    from_solute = None  # else from t = 0
    if start is not None and solute_from is not None and sc.solute.squeezed_is_expelled \
            and start.boundary_states:
        from_solute = SoluteStart.at(solute_from, start.boundary_states[-1].t, res.t)
    rel = release(res, sc.solute, start=from_solute)
    meta = {"key": sc.key(), "scenario": sc.to_dict(), "mechanics_seconds": mech,
            "solute_seconds": time.perf_counter() - wall - mech,
            "mass_balance_error": rel.mass_balance_error,
            "effective_diffusivity": rel.effective_diffusivity,
            "solute_steps": rel.diagnostics.get("steps"), "created": time.time(),
            "mechanics_from_step": res.diagnostics["mechanics_from_step"],
            "solute_from_sample": rel.diagnostics.get("from_sample", 0)}
    return (meta, to_npz(rel), res) if keep else (meta, to_npz(rel))


def to_npz(rel: ReleaseResult) -> bytes:
    """A release result's arrays as an .npz blob."""
    buf = io.BytesIO()
    np.savez_compressed(buf, **{k: np.asarray(getattr(rel, k), dtype=float)
                                for k in RELEASE_ARRAYS})
    return buf.getvalue()


def from_npz(blob: bytes, meta: dict[str, Any]) -> ReleaseResult:
    """Inverse of :func:`to_npz` (scalars from the metadata)."""
    with NPZ_LOCK, np.load(io.BytesIO(blob)) as z:
        arrays = {k: np.array(z[k]) for k in RELEASE_ARRAYS if k in z}
    return ReleaseResult(**arrays, mass_balance_error=float(meta.get("mass_balance_error", 0.0)),
                         effective_diffusivity=float(meta.get("effective_diffusivity", 0.0)),
                         diagnostics=dict(meta))


_SCHEMA = """
CREATE TABLE IF NOT EXISTS drug_runs (
    key TEXT PRIMARY KEY,
    meta TEXT NOT NULL,
    data BLOB NOT NULL,
    created REAL NOT NULL
);
"""


class DrugCache(ValidationCache):
    """Drug runs in the validation cache's SQLite file, in a table of their own."""

    def __init__(self, path: str | Path | None = None) -> None:
        super().__init__(path)
        self._con().executescript(_SCHEMA)

    def put_run(self, key: str, meta: dict[str, Any], blob: bytes) -> None:
        """Store a drug run (one atomic transaction)."""
        import sqlite3

        self._write("INSERT OR REPLACE INTO drug_runs (key, meta, data, created) "
                    "VALUES (?, ?, ?, ?)", (key, json.dumps(meta), sqlite3.Binary(blob),
                                            time.time()))

    def get_run(self, key: str) -> ReleaseResult | None:
        """The stored drug run, or None."""
        row = self._con().execute("SELECT meta, data FROM drug_runs WHERE key = ?",
                                  (key,)).fetchone()
        return None if row is None else from_npz(bytes(row[1]), json.loads(row[0]))


MECHANICS_MEMORY = 64e6  # bytes of drug-run mechanics (profiles) a store keeps


class DrugRuns:
    """Drug runs for a run store (or a planner: its ``cache`` and ``jobs``): memory, then
    the cache file, then its executor.  The
    mechanics of the latest runs (profiles, up to MECHANICS_MEMORY bytes) are kept, and a
    run whose protocol starts with one of theirs continues from there (``restarts``
    counts them): a schedule's shooting runs only the heating it varies."""

    def __init__(self, store: Any) -> None:
        self.store = store
        self.cache = DrugCache(store.cache.path)
        self._mem: ByteLRU = ByteLRU(MECHANICS_MEMORY, max_items=32)  # bytes, not entries
        self._lock = threading.Lock()
        # key -> (case, protocol, mechanics, the run's solute as a dict)
        self._mech: OrderedDict[str, tuple[tuple, tuple[Step, ...], Any, dict[str, Any]]] = \
            OrderedDict()
        self.restarts = 0

    def cached(self, sc: DrugScenario) -> ReleaseResult | None:
        """The stored run, or None (no computation)."""
        key = sc.key()
        with self._lock:
            hit = self._mem.get(key)
        if hit is None:
            hit = self.cache.get_run(key)
            if hit is not None:
                self._remember(key, hit)
        return hit

    def _remember(self, key: str, rel: ReleaseResult) -> None:
        with self._lock:
            self._mem[key] = rel  # last in the ByteLRU's order; it evicts past its bounds

    def run(self, sc: DrugScenario) -> ReleaseResult:
        """The drug run for ``sc`` (blocking; cached)."""
        hit = self.cached(sc)
        if hit is not None:
            return hit

        def store(fut: Any) -> None:
            meta, blob = fut.result()[:2]
            self.cache.put_run(meta["key"], meta, blob)

        start, solute_from = self._start(sc)
        fn = functools.partial(run_drug_scenario, start=start, keep=True,
                               solute_from=solute_from)
        meta, blob, mech = self.store.jobs.submit(sc.key(), fn, sc.to_dict(),
                                                    on_done=store).result()
        self._keep(sc, mech)
        rel = from_npz(blob, meta)
        if rel.mass_balance_error > 1e-10:
            raise SolverError(f"drug run lost mass: {rel.mass_balance_error:.3g}", meta)
        self._remember(sc.key(), rel)
        return rel

    @staticmethod
    def _case(sc: DrugScenario) -> tuple:
        return (sc.gel.key(), sc.t_start, sc.branch, drug_settings(sc.settings))

    def _start(self, sc: DrugScenario) -> tuple[Any, ReleaseResult | None]:
        """The kept mechanics of the longest prefix of ``sc``'s protocol (or None), and the
        drug run they came from if its solute was ``sc``'s (its states continue it)."""
        case, steps = self._case(sc), tuple(sc.protocol)
        best, best_j = None, 0
        with self._lock:
            for key, (c, kept, _m, _s) in self._mech.items():
                if c != case:
                    continue
                j = 0
                while j < min(len(kept), len(steps)) and kept[j] == steps[j]:
                    j += 1
                if j > best_j:
                    best, best_j = key, j
            if best is None:
                return None, None
            self._mech.move_to_end(best)
            _, _, mech, solute = self._mech[best]
        start = mechanics_prefix(mech, steps[:best_j])
        if start is None:
            return None, None
        self.restarts += 1
        if solute != sc.solute.to_dict():
            return start, None
        with self._lock:
            rel = self._mem.get(best)
        return start, rel if rel is not None else self.cache.get_run(best)

    def _keep(self, sc: DrugScenario, mech: Any) -> None:
        """Keep a run's mechanics (the latest first out past MECHANICS_MEMORY bytes)."""
        if mech is None or not mech.boundary_states:
            return
        with self._lock:
            self._mech[sc.key()] = (self._case(sc), tuple(sc.protocol), mech,
                                    sc.solute.to_dict())
            self._mech.move_to_end(sc.key())
            while len(self._mech) > 1 and sum(
                    m.phi.nbytes + m.nodes.nbytes for _, _, m, _ in self._mech.values()
            ) > MECHANICS_MEMORY:
                self._mech.popitem(last=False)

    def close(self) -> None:
        """Close this object's connections to the cache file."""
        self.cache.close()


def runs_for(planner: Any) -> DrugRuns:
    """The planner's drug runs (its run store's, :attr:`dosing.runs.store.RunStore.solute`)."""
    return planner.runs.solute
