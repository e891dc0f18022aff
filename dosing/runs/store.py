"""The run store: the one place in dosing/ that runs the full solver.

Every full-solver run the planner needs is found or run here: memory (a byte-bounded LRU),
the SQLite cache file (:class:`dosing.runs.cache.ValidationCache`), then the executor
(:class:`dosing.runs.jobs.JobRunner`) with the planner's ``solver``; a protocol run starts from
its longest stored prefix (:mod:`dosing.runs.restart`).  docs/architecture.md, "The run store"."""

from __future__ import annotations

import functools
import hashlib
import json
import sqlite3
import threading
from collections import OrderedDict
from concurrent.futures import Executor, Future, ThreadPoolExecutor, wait
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from solver.errors import SolverError

from ..truth import is_model_form_run
from .cache import ValidationCache
from .full import full_solver
from .jobs import DEFAULT_LEASE_SECONDS, Job, JobRunner
from .lru import ByteLRU
from .restart import Start, restartable, stopped_as_run
from .scenario import (
    Scenario,
    Solver,
    Trajectory,
    decode,
    hard_limit,
    run_budget,
    run_scenario,
)

if TYPE_CHECKING:
    from .solute import DrugRuns

RUNS_MEMORY = 64e6  # bytes of runs a store keeps in memory (dosing.runs.lru.ByteLRU)
DEFAULT_HORIZON = 1.0  # first simulated time of a jump (extended x4 when a dose needs more)
# the moving grid resolves the front's interface, so its steps are short: its first horizon
# is shorter (a dose past it extends the run x4, a restart from the stored end state)
MOVING_HORIZON = 0.1
# a model-form run (the delayed law's) reaches its dose up to this many times the truth's
MODEL_FORM_REACH = 4.0
RUN_FAILURE = "run-failure-"  # the id prefix of a run whose worker died (the cache's jobs)


class RunStore:
    """Full-solver runs: memory, the cache file, then ``executor`` (module doc).  ``solver`` runs
    each scenario (default :func:`full_solver`; tests pass a fake) and must pickle on a process
    pool or Dask (a module-level function does, by name).  At most ``max_pending`` groups of runs
    are queued; a claim on a run lapses ``lease_seconds`` after its holder stops renewing it."""

    def __init__(self, cache_path: str | None = None, executor: Executor | None = None,
                 max_pending: int = 64, horizon: float = DEFAULT_HORIZON,
                 lease_seconds: float = DEFAULT_LEASE_SECONDS,
                 solver: Solver | None = None) -> None:
        self._solver = solver  # None: the full solver, imported when a run is queued
        self.cache = ValidationCache(cache_path)
        self.jobs = JobRunner(executor, max_pending, leases=self.cache,
                              lease_seconds=lease_seconds,
                              hard_seconds=hard_limit(run_budget()))
        self.jobs.on_worker_died = self._remember_death
        self.horizon = float(horizon)
        self._row_digest: dict[str, str] = {}  # the cache row each _mem entry came from
        # runs held in memory: RUNS_MEMORY bytes at most (a run of a long trace program
        # weighs hundreds of ordinary ones), and at most 64 of them
        self._mem: ByteLRU = ByteLRU(RUNS_MEMORY, max_items=64,
                                     on_evict=lambda key: self._row_digest.pop(key, None))
        self._mem_lock = threading.Lock()
        # protocol prefixes with a stored state at their end: prefix key -> (the stored
        # run's scenario, steps) (module ``restart``; kept for this store's life)
        self._starts: OrderedDict[str, tuple[Scenario, int]] = OrderedDict()
        self.restarts = 0  # protocol runs started from a stored prefix's state
        self._solute: DrugRuns | None = None
        self._solute_lock = threading.Lock()

    @property
    def solver(self) -> Solver:
        """What runs a scenario (default :func:`full_solver`, imported on first use)."""
        if self._solver is None:
            self._solver = full_solver()
        return self._solver

    @property
    def solute(self) -> DrugRuns:
        """The drug runs (mechanics and solute, :class:`dosing.runs.solute.DrugRuns`) on
        this store's cache file and executor, made on first use."""
        with self._solute_lock:
            if self._solute is None:
                from .solute import DrugRuns

                self._solute = DrugRuns(self)
            return self._solute

    def close(self) -> None:
        """Shut down an owned executor and close the cache file's connections."""
        self.jobs.shutdown(wait=False)
        if self._solute is not None:
            self._solute.close()
        self.cache.close()

    def cached(self, sc: Scenario, need_radius: float | None = None,
               need_time: float = 0.0) -> Trajectory | None:
        """The stored trajectory if it covers the need (no computation), else None."""
        key = sc.key()
        with self._mem_lock:
            traj = self._mem.get(key)
        if traj is None or not _covers(traj, sc, need_radius, need_time):
            traj = self.cache.get(key)
            if traj is None:
                return None
            with self._mem_lock:
                self._mem[key] = traj  # the ByteLRU evicts (and drops its row digest)
                self._row_digest.pop(key, None)  # its row unknown: cached_many reads it
        return traj if _covers(traj, sc, need_radius, need_time) else None

    def cached_many(self, scs: list[Scenario] | tuple[Scenario, ...],
                    need_radius: float | None = None,
                    need_time: float = 0.0) -> list[Trajectory | None]:
        """:meth:`cached` of several runs with one cache query (for the runs this planner
        does not hold in memory already; only rows found are decoded, once)."""
        with self._mem_lock:
            out: list[Trajectory | None] = [self._mem.get(sc.key()) for sc in scs]
        ask = [i for i, (sc, t) in enumerate(zip(scs, out, strict=True))
               if t is None or not _covers(t, sc, need_radius, need_time)]
        short = [scs[i].key() for i in ask if out[i] is not None]  # held, short of the need
        if short:  # read again only a row that changed since (a longer run stored)
            now = self.cache.digests(short)
            ask = [i for i in ask if out[i] is None
                   or now[scs[i].key()] != self._row_digest.get(scs[i].key())]
        if ask:
            found: dict[str, str] = {}
            rows = self.cache.get_many([scs[i].key() for i in ask], found)
            for i in ask:
                key = scs[i].key()
                raw = rows.get(key)
                if raw is None:
                    continue
                traj = decode(raw[1], raw[0])
                with self._mem_lock:
                    self._mem[key] = traj
                    if key in self._mem:  # a run over the memory budget is not kept
                        self._row_digest[key] = found[key]
                out[i] = traj
        if all(t is None for t in out):
            return out
        return [t if t is not None and _covers(t, sc, need_radius, need_time) else None
                for sc, t in zip(scs, out, strict=True)]

    def _store(self, fut: Future) -> None:
        meta, blob = fut.result()
        self.cache.put_if_longer(meta["key"], meta, blob)

    def _fetch(self, sc: Scenario, need_radius: float | None,
               need_time: float) -> tuple[dict[str, Any], bytes] | None:
        """(meta, blob) of a stored run covering the need (one another process stored)."""
        raw = self.cache.get_raw(sc.key())
        if raw is None or not _covers(decode(raw[1], raw[0]), sc, need_radius,
                                      need_time):
            return None
        return raw

    def job(self, sc: Scenario, need_radius: float | None, need_time: float) -> Job:
        """The full-solver run for ``sc`` as a job: past the stored horizon (x4)."""
        meta = self.cache.meta(sc.key())
        first = self.horizon
        if sc.settings.grid == "moving":
            first = min(first, MOVING_HORIZON)
        elif is_model_form_run(sc.settings):  # its dose comes 1.5-9x after the truth's
            first = min(first, max(MOVING_HORIZON, MODEL_FORM_REACH * need_time))
        horizon = first if meta is None else 4.0 * float(meta.get("horizon", 0.0))
        start = self._start(sc) if restartable(self.solver) else None
        if start is not None:
            self.restarts += 1
        return Job(sc.key(), functools.partial(run_scenario, solver=self.solver, start=start),
                   (sc.to_dict(compact=True), max(horizon, first), need_radius, need_time),
                   on_done=self._store,
                   fetch=functools.partial(self._fetch, sc, need_radius, need_time))

    def submit(self, sc: Scenario, need_radius: float | None = None,
               need_time: float = 0.0) -> Future:
        """Queue the full-solver run for ``sc`` (deduplicated by key); returns its future."""
        return self.jobs.submit_group(sc.key(), [self.job(sc, need_radius, need_time)])[0]

    def run_here(self, sc: Scenario, need_radius: float | None = None,
                 budget: float = 30.0) -> Trajectory:
        """The trajectory for ``sc``, stored or run in this thread (not queued behind the
        pool's validations) within ``budget`` seconds of wall time, and stored: for the
        sub-second runs an answer's envelope needs (the delayed-law lattice).  Not kept in
        this planner's memory (its caller keeps the number it needs)."""
        with self._mem_lock:
            traj = self._mem.get(sc.key())
        if traj is not None and _covers(traj, sc, need_radius, 0.0):
            return traj
        raw = self._fetch(sc, need_radius, 0.0)
        if raw is not None:
            return decode(raw[1], raw[0])
        meta, blob = run_scenario(sc.to_dict(), self.horizon, need_radius, budget=budget,
                                  solver=self.solver)
        self.cache.put_if_longer(meta["key"], meta, blob)
        return decode(blob, meta)

    def trajectory(self, sc: Scenario, need_radius: float | None = None,
                   need_time: float = 0.0) -> Trajectory:
        """The full-solver trajectory for ``sc`` covering the need (blocking, cached)."""
        for _ in range(6):
            traj = self.cached(sc, need_radius, need_time)
            if traj is not None:
                return self._keep_states(sc, traj)
            meta, blob = self.submit(sc, need_radius, need_time).result()
            traj = decode(blob, meta)
            if _covers(traj, sc, need_radius, need_time):
                return self._keep_states(sc, traj)
        raise SolverError("the full-solver run does not cover the dose", {"key": sc.key()})

    def _keep_states(self, sc: Scenario, traj: Trajectory) -> Trajectory:
        """Remember where a protocol run kept its state after each step (module
        ``restart``), so that a later protocol sharing those steps starts there."""
        states = traj.boundary_states if sc.protocol is not None else []
        alias = stopped_as_run(sc, traj) if states else None
        if alias is not None:  # a read-off heating's run is also the run to its dose
            self._keep_states(*alias)
            key = alias[0].key()
            self.cache.put_if_longer(key, alias[1].meta, alias[1].to_npz())
            with self._mem_lock:
                self._mem[key] = alias[1]  # the ByteLRU evicts past its bounds
                self._row_digest.pop(key, None)  # its row unknown: cached_many reads it
        if states:
            new = []
            with self._mem_lock:
                for st in states:
                    if st.stopped:
                        continue
                    j = st.steps
                    key = _prefix(sc, j).key()
                    if self._starts.get(key) != (sc, j):
                        new.append((key, sc.to_dict(), j))
                    self._starts[key] = (sc, j)
                    self._starts.move_to_end(key)
                while len(self._starts) > 4096:
                    self._starts.popitem(last=False)
            try:  # kept in the cache too: a restarted planner starts from the same states
                self.cache.put_starts(new)
            except sqlite3.Error:
                pass  # only where a run starts is lost (a full disk): it starts earlier
        return traj

    def _start(self, sc: Scenario) -> Start | None:
        """Where ``sc``'s protocol run starts: the state after its longest prefix that a
        run this planner, or one before it on this cache, has seen kept (the cache's
        ``starts``: a job resumed after a restart starts where it would have), or a stored
        run of that prefix itself (the run store keeps each run's states: another
        process's runs serve too); None: t = 0."""
        if sc.protocol is None or len(sc.protocol) < 2:
            return None
        for j in range(len(sc.protocol) - 1, 0, -1):
            pre = _prefix(sc, j)
            with self._mem_lock:
                hit = self._starts.get(pre.key())
            if hit is None:
                try:
                    row = self.cache.get_start(pre.key())
                except sqlite3.Error:
                    row = None
                if row is not None:
                    hit = (Scenario.from_dict(row[0]), row[1])
            stored = self.cached(pre if hit is None else hit[0])
            start = None if stored is None else Start.of(stored, j if hit is None else hit[1])
            if start is not None:
                return start
        return None

    def trajectories(self, scs: list[Scenario], need_radius: float,
                      need_time: float) -> list[Trajectory | BaseException]:
        """The runs' trajectories, run concurrently; a failure is returned, not raised.
        The runs not stored yet are admitted to the queue together (or none is)."""
        todo = [sc for sc in scs if self.cached(sc, need_radius, need_time) is None]
        if todo:
            group = hashlib.sha256(json.dumps([sc.key() for sc in scs]).encode()).hexdigest()
            self.jobs.submit_group(group[:24], [self.job(sc, need_radius, need_time)
                                                for sc in todo])
        with ThreadPoolExecutor(len(scs)) as pool:
            futs = [pool.submit(self.trajectory, sc, need_radius, need_time) for sc in scs]
            wait(futs)
        return [f.exception() or f.result() for f in futs]

    def _remember_death(self, key: str, err: BaseException) -> None:
        """A run whose pool worker died while it ran (killed by the OS, or at the hard
        limit): kept in the cache, so that a poll (here or after a restart) reports it
        failed instead of running it into the same death; asking again runs it."""
        jid = RUN_FAILURE + key
        self.cache.put_job(jid, "run-failure", {"key": key})
        self.cache.finish_job(jid, "failed", error=str(err))

    def died(self, key: str, retry: bool) -> BaseException | None:
        """The remembered death of run ``key`` (None: none; ``retry`` forgets it)."""
        row = self.cache.get_job(RUN_FAILURE + key)
        if row is None:
            return None
        if retry:
            self.cache.forget_job(RUN_FAILURE + key)
            return None
        from .jobs import WorkerDied

        return WorkerDied(row["error"] or "its pool worker died while it ran")


def _prefix(sc: Scenario, steps: int) -> Scenario:
    """The run of ``sc``'s first ``steps`` protocol steps (to their end: no stop)."""
    if steps == len(sc.protocol) and sc.stop_expelled is None:
        return sc
    return replace(sc, protocol=sc.protocol[:steps], stop_expelled=None)


def _covers(traj: Trajectory, sc: Scenario, need_radius: float | None, need_time: float) -> bool:
    if sc.protocol is not None or sc.program is not None:
        return True
    if need_radius is not None and traj.radius.min() > need_radius:
        return False
    return traj.horizon >= need_time
