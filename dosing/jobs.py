"""Computations on a pluggable ``concurrent.futures`` executor, deduplicated by key.

Any executor works: the default is a process pool (spawned workers, so a threaded parent
such as a web server forks nothing it should not); past one machine pass a Dask
``Client(...).get_executor()``.  Submitting a key that is already pending or running
returns the same future; at most ``max_pending`` unfinished jobs are accepted, beyond that
:class:`QueueFullError` says when to retry.
"""

from __future__ import annotations

import multiprocessing
import os
import threading
from collections.abc import Callable
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from typing import Any


class QueueFullError(RuntimeError):
    """Too many unfinished jobs; ``retry_after`` is a suggested wait in seconds."""

    def __init__(self, pending: int, retry_after: float = 5.0) -> None:
        self.pending = pending
        self.retry_after = retry_after
        super().__init__(f"{pending} validations are queued or running: retry in "
                         f"{retry_after:g} s")


def default_executor(max_workers: int | None = None) -> ProcessPoolExecutor:
    """A process pool of spawned workers (half the cores, at least one)."""
    n = max_workers or max(1, (os.cpu_count() or 2) // 2)
    return ProcessPoolExecutor(max_workers=n, mp_context=multiprocessing.get_context("spawn"))


def job_state(fut: Future) -> str:
    """'pending', 'running', 'done' or 'failed' for a future."""
    if fut.done():
        return "failed" if fut.cancelled() or fut.exception() is not None else "done"
    return "running" if fut.running() else "pending"


class JobRunner:
    """Run ``fn(*args)`` per key on an executor; one future per key while it is unfinished."""

    def __init__(self, executor: Executor | None = None, max_pending: int = 64) -> None:
        if max_pending < 1:
            raise ValueError("max_pending must be >= 1")
        self._executor = executor
        self._owns = executor is None
        self.max_pending = int(max_pending)
        self._jobs: dict[str, tuple[Future, Future]] = {}  # key -> (executor's, ours)
        self._lock = threading.Lock()

    @property
    def executor(self) -> Executor:
        """The executor (the default process pool is created on first use)."""
        with self._lock:
            if self._executor is None:
                self._executor = default_executor()
            return self._executor

    def pending(self) -> int:
        """Number of unfinished jobs."""
        with self._lock:
            return sum(not f.done() for _, f in self._jobs.values())

    def get(self, key: str) -> Future | None:
        """The latest future for ``key`` (finished or not), or None."""
        with self._lock:
            pair = self._jobs.get(key)
        return None if pair is None else pair[1]

    def submit(self, key: str, fn: Callable[..., Any], *args: Any,
               on_done: Callable[[Future], None] | None = None) -> Future:
        """Submit unless ``key`` is already pending or running; return its future.

        ``on_done`` runs once when the job finishes (e.g. to store the result), before
        the future is reported done to anyone waiting on the returned one.
        """
        executor = self.executor
        with self._lock:
            old = self._jobs.get(key)
            if old is not None and not old[1].done():
                return old[1]
            unfinished = sum(not f.done() for _, f in self._jobs.values())
            if unfinished >= self.max_pending:
                raise QueueFullError(unfinished)
            inner = executor.submit(fn, *args)
            outer: Future = Future()
            self._jobs[key] = (inner, outer)
        inner.add_done_callback(lambda f: self._finish(f, outer, on_done))
        return outer

    @staticmethod
    def _finish(inner: Future, outer: Future, on_done: Callable[[Future], None] | None) -> None:
        if inner.cancelled():
            outer.set_exception(RuntimeError("the job was cancelled"))
            return
        exc = inner.exception()
        if exc is None and on_done is not None:
            try:
                on_done(inner)
            except Exception as err:  # noqa: BLE001 - reported through the future
                exc = err
        if exc is not None:
            outer.set_exception(exc)
        else:
            outer.set_result(inner.result())

    def state(self, key: str) -> str | None:
        """The job's state, or None if never submitted here."""
        with self._lock:
            pair = self._jobs.get(key)
        if pair is None:
            return None
        inner, outer = pair
        if outer.done():
            return job_state(outer)
        return "running" if inner.running() or inner.done() else "pending"

    def shutdown(self, wait: bool = True) -> None:
        """Shut down the executor if this runner created it."""
        with self._lock:
            ex, self._executor = (self._executor, None) if self._owns else (None,
                                                                             self._executor)
        if ex is not None:
            ex.shutdown(wait=wait, cancel_futures=not wait)
