"""Computations on a pluggable ``concurrent.futures`` executor, deduplicated by key.

Any executor works: the default is a process pool (spawned workers, so a threaded parent
such as a web server forks nothing it should not; each worker ends itself when its parent
is gone, and :meth:`JobRunner.shutdown` stops them); past one machine pass a Dask
``Client(...).get_executor()``.  Submitting a key that is already pending or running
returns the same future.

Admission is by group: a group (one validation: all its runs) is admitted whole or not at
all, and at most ``max_pending`` unfinished groups are accepted; beyond that
:class:`QueueFullError` says what is full and when to retry.

Across processes (two servers, or uvicorn workers, on one cache file) a :class:`Leases`
store makes each key computed once: the process that claims a key's lease runs it and
renews the lease while it runs; every other process waits for the result to appear
(``fetch``) and takes the work over if the lease expires (a crashed holder).
"""

from __future__ import annotations

import multiprocessing
import multiprocessing.spawn as mp_spawn
import os
import socket
import threading
import time
import uuid
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Protocol

DEFAULT_LEASE_SECONDS = 30.0
# How much a background pool's workers lower their own scheduling priority (os.nice): the
# validations they run yield the CPU to the process that owns them (a server answering
# requests) and to the user's foreground work whenever both want it; alone they run at
# full speed.
BACKGROUND_NICENESS = 10
WAIT_POLL_SECONDS = 0.25  # how often a waiting process looks for another's result


class QueueFullError(RuntimeError):
    """Too many unfinished jobs; ``retry_after`` is a suggested wait in seconds."""

    def __init__(self, pending: int, retry_after: float = 5.0, what: str = "validations",
                 limit: int | None = None) -> None:
        self.pending = pending
        self.retry_after = retry_after
        self.what = what
        self.limit = pending if limit is None else limit
        super().__init__(f"the {what} queue is full: {pending} {what} queued or running "
                         f"(at most {self.limit}); retry in {retry_after:g} s")


class Leases(Protocol):
    """A shared store of expiring claims on keys (``dosing.cache.ValidationCache``)."""

    def claim(self, key: str, owner: str, seconds: float) -> bool:
        """Take the lease on ``key`` if it is free, expired, or already ours."""

    def renew(self, keys: Sequence[str], owner: str, seconds: float) -> None:
        """Push the expiry of our leases on ``keys`` ``seconds`` into the future."""

    def release(self, key: str, owner: str) -> None:
        """Drop our lease on ``key``."""


def lease_owner() -> str:
    """This process's lease owner name: host, pid and a random tag."""
    return f"{socket.gethostname()}:{os.getpid()}:{uuid.uuid4().hex[:8]}"


def exit_with_parent(parent_pid: int, interval: float = 1.0) -> None:
    """Start a daemon thread ending this process once its parent ``parent_pid`` is gone
    (the parent was killed and this process was re-parented): no orphans."""

    def watch() -> None:
        while True:
            time.sleep(interval)
            if os.getppid() != parent_pid:
                os._exit(0)

    threading.Thread(target=watch, name="exit-with-parent", daemon=True).start()


_SPAWN_LOCK = threading.Lock()


@contextmanager
def _main_not_reimported() -> Iterator[None]:
    """While processes start here, a spawned child is not told to re-run ``__main__``.

    multiprocessing's spawn makes each child import the parent's main script again (as
    ``__mp_main__``), so a script without an ``if __name__ == "__main__"`` guard would run
    again in every worker, start pools of its own and never finish.  The pool's work is
    importable by name (``dosing.scenario.run_scenario``, ``solver.full.simulate``), so its
    workers need nothing from the script: the README's code runs as pasted.
    """
    with _SPAWN_LOCK:
        original = mp_spawn.get_preparation_data

        def without_main(name: str) -> dict[str, Any]:
            data = original(name)
            data.pop("init_main_from_path", None)
            data.pop("init_main_from_name", None)
            return data

        mp_spawn.get_preparation_data = without_main
        try:
            yield
        finally:
            mp_spawn.get_preparation_data = original


class ScriptSafeProcessPool(ProcessPoolExecutor):
    """A spawned process pool whose workers do not re-run the parent's main script
    (:func:`_main_not_reimported`); workers start inside ``submit`` (Python >= 3.9 spawns
    them on demand there), which is where the guard is held.  A callable submitted to it
    must be importable by name (defined in a module, not in the script)."""

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Future:
        with _main_not_reimported():
            return super().submit(fn, *args, **kwargs)


def pool_worker_start(parent_pid: int, niceness: int = 0) -> None:
    """A pool worker's initializer: end with ``parent_pid`` (:func:`exit_with_parent`) and
    lower this process's priority by ``niceness`` (``os.nice``; 0 leaves it, and a
    platform without ``os.nice`` runs at the parent's priority)."""
    exit_with_parent(parent_pid)
    if niceness > 0 and hasattr(os, "nice"):
        try:
            os.nice(niceness)
        except OSError:  # not permitted here: run at the parent's priority
            pass


def default_executor(max_workers: int | None = None,
                     niceness: int = 0) -> ProcessPoolExecutor:
    """A process pool of spawned workers (half the cores, at least one) that do not re-run
    the caller's script; each worker ends itself if this process dies and runs
    ``niceness`` below this process's priority (:func:`pool_worker_start`)."""
    n = max_workers or max(1, (os.cpu_count() or 2) // 2)
    return ScriptSafeProcessPool(max_workers=n, mp_context=multiprocessing.get_context("spawn"),
                                 initializer=pool_worker_start,
                                 initargs=(os.getpid(), int(niceness)))


def stop_executor(executor: Executor) -> None:
    """Cancel queued work and stop ``executor`` now: a process pool's workers are
    terminated and joined (work in flight is abandoned; its lease lapses)."""
    procs = list((getattr(executor, "_processes", None) or {}).values())  # gone after shutdown
    executor.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        if p.is_alive():
            p.terminate()
    for p in procs:
        p.join(timeout=10)
        if p.is_alive():
            p.kill()
            p.join(timeout=5)


def job_state(fut: Future) -> str:
    """'pending', 'running', 'done' or 'failed' for a future."""
    if fut.done():
        return "failed" if fut.cancelled() or fut.exception() is not None else "done"
    return "running" if fut.running() else "pending"


@dataclass
class Job:
    """One computation: ``fn(*args)`` under ``key``.  ``on_done`` runs on the result before
    anyone waiting sees it (e.g. to store it); ``fetch`` returns the result if another
    process already stored it (else None)."""

    key: str
    fn: Callable[..., Any]
    args: tuple[Any, ...] = ()
    on_done: Callable[[Future], None] | None = None
    fetch: Callable[[], Any] | None = None


@dataclass(eq=False)  # compared by identity
class _Entry:
    job: Job
    group: str
    outer: Future
    inner: Future | None = None
    remote: bool = False  # another process holds the lease: we wait for its result
    held: bool = False  # we hold the lease


class JobRunner:
    """Run jobs on an executor; one future per key while it is unfinished."""

    def __init__(self, executor: Executor | None = None, max_pending: int = 64,
                 leases: Leases | None = None, lease_seconds: float = DEFAULT_LEASE_SECONDS,
                 what: str = "validations") -> None:
        if max_pending < 1:
            raise ValueError("max_pending must be >= 1")
        if not lease_seconds > 0:
            raise ValueError("lease_seconds must be > 0")
        self._executor = executor
        self._owns = executor is None
        self.max_pending = int(max_pending)
        self.what = what
        self.leases = leases
        self.lease_seconds = float(lease_seconds)
        self.owner = lease_owner()
        self._jobs: dict[str, _Entry] = {}
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._heartbeat: threading.Thread | None = None
        self._waiting: list[_Entry] = []  # held elsewhere: polled by one waiter thread
        self._waiter: threading.Thread | None = None

    @property
    def executor(self) -> Executor:
        """The executor (the default process pool is created on first use: background
        work, its workers at :data:`BACKGROUND_NICENESS`)."""
        with self._lock:
            if self._executor is None:
                self._executor = default_executor(niceness=BACKGROUND_NICENESS)
            return self._executor

    # ------------------------------------------------------------------ queries
    def _active_groups(self) -> set[str]:
        return {e.group for e in self._jobs.values() if not e.outer.done()}

    def pending(self) -> int:
        """Number of unfinished groups (what ``max_pending`` bounds)."""
        with self._lock:
            return len(self._active_groups())

    def get(self, key: str) -> Future | None:
        """The latest future for ``key`` (finished or not), or None."""
        with self._lock:
            entry = self._jobs.get(key)
        return None if entry is None else entry.outer

    def state(self, key: str) -> str | None:
        """The job's state, or None if never submitted here; 'running' while another
        process computes it."""
        with self._lock:
            entry = self._jobs.get(key)
        if entry is None:
            return None
        if entry.outer.done():
            return job_state(entry.outer)
        if entry.remote:
            return "running"
        inner = entry.inner
        return "running" if inner is not None and (inner.running() or inner.done()) \
            else "pending"

    # ------------------------------------------------------------------ submission
    def submit(self, key: str, fn: Callable[..., Any], *args: Any,
               on_done: Callable[[Future], None] | None = None,
               fetch: Callable[[], Any] | None = None) -> Future:
        """Submit one job (a group of its own) unless ``key`` is unfinished; its future."""
        return self.submit_group(key, [Job(key, fn, args, on_done, fetch)])[0]

    def submit_group(self, group: str, jobs: Sequence[Job]) -> list[Future]:
        """Admit ``jobs`` as one group, whole or not at all (QueueFullError); keys already
        unfinished are not resubmitted.  Returns one future per job."""
        self.executor  # noqa: B018 - create the default pool outside the lock
        with self._lock:
            fresh = [j for j in jobs if j.key not in self._jobs
                     or self._jobs[j.key].outer.done()]
            active = self._active_groups()
            if fresh and group not in active and len(active) >= self.max_pending:
                raise QueueFullError(len(active), what=self.what, limit=self.max_pending)
            started = []
            for j in fresh:
                entry = _Entry(j, group, Future())
                self._jobs[j.key] = entry
                started.append(entry)
            futures = [self._jobs[j.key].outer for j in jobs]
        for entry in started:
            try:
                self._start(entry)
            except Exception as exc:
                self._release(entry)
                self._settle(entry.outer, error=exc)
        return futures

    def _start(self, entry: _Entry) -> None:
        """Run the job here (we hold its lease, or there are no leases) or wait for the
        holder's result."""
        if self.leases is None:
            self._run(entry)
            return
        if self._claim(entry):
            return
        entry.remote = True
        with self._lock:
            self._waiting.append(entry)
            if self._waiter is None and not self._stop.is_set():
                self._waiter = threading.Thread(target=self._wait_remote, daemon=True,
                                                name="lease-waiter")
                self._waiter.start()

    def _claim(self, entry: _Entry) -> bool:
        """Claim the lease and start the job (or take a result that appeared meanwhile);
        False while another process holds it."""
        if not self.leases.claim(entry.job.key, self.owner, self.lease_seconds):
            return False
        entry.held = True
        self._ensure_heartbeat()
        found = self._fetch(entry)
        if found is not None:
            self._release(entry)
            self._settle(entry.outer, result=found)
        else:
            entry.remote = False
            self._run(entry)
        return True

    def _fetch(self, entry: _Entry) -> Any:
        fetch = entry.job.fetch
        return None if fetch is None else fetch()

    def _poll_remote(self, entry: _Entry) -> bool:
        """One look at a job held elsewhere: True once it is settled or taken over."""
        try:
            found = self._fetch(entry)
            if found is not None:
                self._settle(entry.outer, result=found)
                return True
            return self._claim(entry)
        except Exception as exc:
            self._settle(entry.outer, error=exc)
            return True

    def _wait_remote(self) -> None:
        """Poll the jobs other processes hold for their results; take a job over when its
        lease lapses."""
        while not self._stop.wait(WAIT_POLL_SECONDS):
            with self._lock:
                waiting = list(self._waiting)
            finished = [e for e in waiting if e.outer.done() or self._poll_remote(e)]
            with self._lock:
                self._waiting = [e for e in self._waiting if e not in finished]
        with self._lock:
            waiting, self._waiting = self._waiting, []
        for entry in waiting:
            self._settle(entry.outer, error=RuntimeError("the job runner was shut down"))

    def _run(self, entry: _Entry) -> None:
        try:
            inner = self.executor.submit(entry.job.fn, *entry.job.args)
        except Exception as exc:
            self._release(entry)
            self._settle(entry.outer, error=exc)
            return
        entry.inner = inner
        inner.add_done_callback(lambda f: self._finish(f, entry))

    def _finish(self, inner: Future, entry: _Entry) -> None:
        if inner.cancelled():
            self._release(entry)
            self._settle(entry.outer, error=RuntimeError("the job was cancelled"))
            return
        exc = inner.exception()
        if exc is None and entry.job.on_done is not None:
            try:
                entry.job.on_done(inner)
            except Exception as err:
                exc = err
        self._release(entry)  # after on_done: the result is stored before others look
        if exc is not None:
            self._settle(entry.outer, error=exc)
        else:
            self._settle(entry.outer, result=inner.result())

    @staticmethod
    def _settle(fut: Future, result: Any = None, error: BaseException | None = None) -> None:
        if fut.done():
            return
        if error is not None:
            fut.set_exception(error)
        else:
            fut.set_result(result)

    # ------------------------------------------------------------------ leases
    def _release(self, entry: _Entry) -> None:
        if self.leases is not None and entry.held:
            entry.held = False
            try:
                self.leases.release(entry.job.key, self.owner)
            except Exception:
                pass

    def _ensure_heartbeat(self) -> None:
        with self._lock:
            if self._heartbeat is None and not self._stop.is_set():
                self._heartbeat = threading.Thread(target=self._beat, daemon=True,
                                                   name="lease-heartbeat")
                self._heartbeat.start()

    def _beat(self) -> None:
        """Renew our leases every third of their lifetime while their jobs are unfinished."""
        while not self._stop.wait(self.lease_seconds / 3.0):
            with self._lock:
                keys = [k for k, e in self._jobs.items() if e.held and not e.outer.done()]
            if keys and self.leases is not None:
                try:
                    self.leases.renew(keys, self.owner, self.lease_seconds)
                except Exception:
                    pass

    # ------------------------------------------------------------------ shutdown
    def shutdown(self, wait: bool = True) -> None:
        """Stop waiting and renewing; stop the executor if this runner created it (its
        process pool's workers are terminated unless ``wait``: then they finish first)."""
        self._stop.set()
        with self._lock:
            ex, self._executor = (self._executor, None) if self._owns else (None,
                                                                             self._executor)
            held = [e for e in self._jobs.values() if e.held and not e.outer.done()]
        if ex is not None:
            if wait:
                ex.shutdown(wait=True)
            else:
                stop_executor(ex)
        for entry in held:
            self._release(entry)
        if not wait:  # nobody waits forever on work that was abandoned
            with self._lock:
                unfinished = [e.outer for e in self._jobs.values() if not e.outer.done()]
            for fut in unfinished:
                self._settle(fut, error=RuntimeError("the job runner was shut down"))
