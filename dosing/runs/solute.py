"""The store's drug runs: a drug's mechanics and its solute (``dosing.payload.drug``), in memory
and in the cache file's ``drug_runs`` table, run on the store's executor; a run whose
protocol starts with a kept run's steps continues from that run's state (its mechanics,
and its solute when it is the same drug)."""

from __future__ import annotations

import functools
import json
import threading
import time
from collections import OrderedDict
from pathlib import Path
from typing import Any

from solver.errors import SolverError
from solver.solute import ReleaseResult

from ..payload.drug import (
    DrugScenario,
    Step,
    drug_settings,
    from_npz,
    mechanics_prefix,
    run_drug_scenario,
)
from .cache import ValidationCache
from .lru import ByteLRU

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
            self._mem[key] = rel
            self._mem.move_to_end(key)
            while len(self._mem) > 32:
                self._mem.popitem(last=False)

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
