"""Computations on a pluggable ``concurrent.futures`` executor, deduplicated by key.

:class:`JobRunner`: a process pool by default (spawned workers, a watchdog each) or any
executor (Dask's); one future per pending key; groups admitted whole, at most ``max_pending``
(:class:`QueueFullError`); a broken pool replaced; :class:`Leases` make each key computed
once across processes.  How and why: docs/architecture.md, "The run store"."""

from __future__ import annotations

import json
import multiprocessing
import multiprocessing.spawn as mp_spawn
import os
import pickle
import shutil
import signal
import socket
import tempfile
import threading
import time
import uuid
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Executor, Future, ProcessPoolExecutor, ThreadPoolExecutor
from concurrent.futures.process import BrokenProcessPool
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
    """A shared store of expiring claims on keys (``dosing.runs.cache.ValidationCache``)."""

    def claim(self, key: str, owner: str, seconds: float) -> bool:
        """Take the lease on ``key`` if it is free, expired, or already ours."""

    def renew(self, keys: Sequence[str], owner: str, seconds: float) -> None:
        """Push the expiry of our leases on ``keys`` ``seconds`` into the future."""

    def release(self, key: str, owner: str) -> None:
        """Drop our lease on ``key``."""


class WorkerError(RuntimeError):
    """An error raised in a pool worker that does not pickle: its type and message."""


class WorkerDied(RuntimeError):
    """A job whose pool worker died while it ran (killed by the OS, or by the runner's hard
    time limit); the pool was replaced and the job is failed, not retried."""


def portable_error(exc: BaseException) -> BaseException:
    """``exc`` if it survives pickling (a process pool sends it back), else a
    :class:`WorkerError` naming its type and message."""
    try:
        pickle.loads(pickle.dumps(exc))
    except Exception:
        return WorkerError(f"{type(exc).__name__}: {exc}")
    return exc


_RUN_DIR: str | None = None  # a pool worker's folder of job markers (pool_worker_start)


def _marker(run_dir: str, pid: int) -> str:
    return os.path.join(run_dir, f"{pid}.run")


def run_in_worker(key: str, fn: Callable[..., Any], *args: Any) -> Any:
    """The worker's edge: run ``fn(*args)`` (job ``key``) and send any error back as one
    that pickles (:func:`portable_error`).  While it runs, a marker file in the pool's run
    folder names the job, its process and its start, so the parent knows which job a dead
    worker was running and how long a job has run."""
    marker = None
    if _RUN_DIR is not None:
        marker = _marker(_RUN_DIR, os.getpid())
        try:
            with open(marker + ".tmp", "w") as fh:
                json.dump({"key": key, "pid": os.getpid(), "started": time.time()}, fh)
            os.replace(marker + ".tmp", marker)
        except OSError:
            marker = None
    try:
        return fn(*args)
    except Exception as exc:
        err = portable_error(exc)
        if err is exc:
            raise
        raise err from None
    finally:
        if marker is not None:
            try:
                os.unlink(marker)
            except OSError:
                pass


def running_jobs(run_dir: str | None) -> dict[str, dict[str, Any]]:
    """The jobs a pool's workers are running: key -> {pid, started} (their markers)."""
    out: dict[str, dict[str, Any]] = {}
    if not run_dir:
        return out
    try:
        names = os.listdir(run_dir)
    except OSError:
        return out
    for name in names:
        if not name.endswith(".run"):
            continue
        try:
            with open(os.path.join(run_dir, name)) as fh:
                d = json.load(fh)
            out[str(d["key"])] = {"pid": int(d["pid"]), "started": float(d["started"])}
        except (OSError, ValueError, KeyError, TypeError):
            continue
    return out


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
    """While processes start here, a spawned child is not told to re-run ``__main__``: spawn
    would import the parent's script again (``__mp_main__``), so a script without a main guard
    would rerun in every worker.  The pool's work is importable by name, so the README's code
    runs as pasted."""
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


def _parent_of(pid: int) -> int | None:
    """The parent pid of process ``pid`` (Linux: /proc; else None)."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as fh:
            stat = fh.read()
    except OSError:
        return None
    try:
        return int(stat[stat.rindex(b")") + 2:].split()[1])
    except (ValueError, IndexError):
        return None


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True
    return True


def kill_with_parent(parent_pid: int, interval: float = 0.5) -> int | None:
    """Fork a watchdog that SIGKILLs this process once ``parent_pid`` is no longer its parent and
    ends itself once this process is gone; its pid (None where there is no fork).  A process, not
    a thread (:func:`exit_with_parent`): a compiled loop may hold the GIL.  It closes every
    inherited descriptor (none of the pool's pipes) and makes only system calls."""
    if not hasattr(os, "fork"):
        return None
    me = os.getpid()
    pid = os.fork()
    if pid:
        return pid
    try:  # the watchdog: only system calls from here on
        os.closerange(3, 65536)
        linux = os.path.exists(f"/proc/{me}/stat")
        while True:
            time.sleep(interval)
            if os.getppid() != me:  # the worker is gone
                os._exit(0)
            gone = (_parent_of(me) != parent_pid) if linux else not _alive(parent_pid)
            if gone:
                try:
                    os.kill(me, signal.SIGKILL)
                finally:
                    os._exit(0)
    except BaseException:
        os._exit(0)
    return None  # not reached


def pool_worker_start(parent_pid: int, niceness: int = 0, run_dir: str | None = None) -> None:
    """A pool worker's initializer: end with ``parent_pid`` (a watchdog process,
    :func:`kill_with_parent`, and :func:`exit_with_parent`), keep the markers of the jobs it
    runs in ``run_dir`` (:func:`run_in_worker`) and lower this process's priority by
    ``niceness`` (``os.nice``; 0 leaves it, and a platform without ``os.nice`` runs at the
    parent's priority)."""
    global _RUN_DIR
    _RUN_DIR = run_dir
    kill_with_parent(parent_pid)
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
    run_dir = tempfile.mkdtemp(prefix="thermogel-pool-")
    pool = ScriptSafeProcessPool(max_workers=n, mp_context=multiprocessing.get_context("spawn"),
                                 initializer=pool_worker_start,
                                 initargs=(os.getpid(), int(niceness), run_dir))
    pool.run_dir = run_dir  # type: ignore[attr-defined]
    return pool


def stop_executor(executor: Executor) -> None:
    """Cancel queued work and stop ``executor`` now: a process pool's workers are
    terminated and joined (work in flight is abandoned; its lease lapses)."""
    procs = list((getattr(executor, "_processes", None) or {}).values())  # gone after shutdown
    try:
        executor.shutdown(wait=False, cancel_futures=True)
    except Exception:  # a broken pool's internals may be gone already
        pass
    for p in procs:
        if p.is_alive():
            p.terminate()
    for p in procs:
        p.join(timeout=10)
        if p.is_alive():
            p.kill()
            p.join(timeout=5)
    run_dir = getattr(executor, "run_dir", None)
    if run_dir:
        shutil.rmtree(run_dir, ignore_errors=True)


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
    executor: Executor | None = None  # where it was submitted last
    retries: int = 0  # times re-queued after a broken pool it was not running in


class JobRunner:
    """Run jobs on an executor; one future per key while it is unfinished."""

    def __init__(self, executor: Executor | None = None, max_pending: int = 64,
                 leases: Leases | None = None, lease_seconds: float = DEFAULT_LEASE_SECONDS,
                 what: str = "validations", hard_seconds: float | None = None) -> None:
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
        # a job running longer than this in a process-pool worker is killed (its own budget
        # failed to stop it); None: never
        self.hard_seconds = hard_seconds
        self._reaper: threading.Thread | None = None
        self._killed: dict[str, str] = {}  # key -> why the runner killed its worker
        self._suspects: dict[Executor, dict[str, dict[str, Any]]] = {}  # broken pool -> its jobs
        self._restarts = 0
        self._last_break: str | None = None
        self._broken: str | None = None  # the pool is broken and not replaced: why
        # called with (key, error) when a job's worker died while it ran (or was killed at
        # the hard limit): the planner remembers it, so a poll after a restart does not run
        # it into the same death (dosing.planner)
        self.on_worker_died: Callable[[str, BaseException], None] | None = None
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
        for attempt in range(2):
            ex = self.executor
            try:
                if isinstance(ex, ThreadPoolExecutor):
                    inner = ex.submit(entry.job.fn, *entry.job.args)
                else:  # the worker's edge: errors come back, markers name the job
                    inner = ex.submit(run_in_worker, entry.job.key, entry.job.fn,
                                      *entry.job.args)
                    self._ensure_reaper(ex)
            except BrokenProcessPool as exc:
                if attempt == 0 and self._replace(ex, str(exc)):
                    continue
                self._release(entry)
                self._settle(entry.outer, error=exc)
                return
            except Exception as exc:
                self._release(entry)
                self._settle(entry.outer, error=exc)
                return
            break
        entry.executor = ex
        entry.inner = inner
        inner.add_done_callback(lambda f: self._finish(f, entry))

    # ------------------------------------------------------------------ a broken pool
    def _replace(self, broken: Executor, why: str) -> bool:
        """Note that ``broken`` broke (the jobs its workers were running are suspects) and,
        if it is this runner's own pool, replace it; True once a working pool is in place."""
        with self._lock:
            first = broken not in self._suspects
            if first:
                run_dir = getattr(broken, "run_dir", None)
                self._suspects[broken] = running_jobs(run_dir)
                self._restarts += 1
                self._last_break = f"{time.strftime('%H:%M:%S')}: {why}"
            if self._executor is not broken:  # replaced already (or shut down)
                return self._executor is not None or not self._owns
            if not self._owns:
                self._broken = why
                return False
            self._executor = None
        stopper = threading.Thread(target=stop_executor, args=(broken,), daemon=True,
                                   name="stop-broken-pool")
        stopper.start()
        self.executor  # noqa: B018 - the replacement (its workers start on demand)
        return True

    def _broken_pool(self, entry: _Entry, exc: BaseException) -> bool:
        """A job's future failed with a broken pool: replace the pool, then fail the job if
        it was running in the dead worker (or was re-queued twice), else queue it again.
        True if it was queued again."""
        broken = entry.executor
        if broken is None or self._stop.is_set():
            return False
        replaced = self._replace(broken, str(exc))
        with self._lock:
            suspects = self._suspects.get(broken, {})
            killed = self._killed.pop(entry.job.key, None)
        was_running = entry.job.key in suspects
        if replaced and not was_running and entry.retries < 2:
            entry.retries += 1
            self._run(entry)
            return True
        pid = suspects.get(entry.job.key, {}).get("pid")
        why = killed or (f"its worker (pid {pid}) died while it ran" if was_running else
                         "the process pool broke before it could run")
        pool = "replaced" if replaced else "not replaced (a pool this runner was lent)"
        err = WorkerDied(f"the job failed: {why}; the pool was {pool}, and this job is not "
                         "run again unless asked again")
        if (was_running or killed) and self.on_worker_died is not None:
            try:
                self.on_worker_died(entry.job.key, err)
            except Exception:
                pass
        self._release(entry)
        self._settle(entry.outer, error=err)
        return True

    def pool_status(self) -> dict[str, Any]:
        """The pool's health: 'ok', or 'degraded' while a broken pool is not replaced;
        how often it was replaced and the last break's cause."""
        return {"status": "degraded" if self._broken else "ok",
                "broken_because": self._broken, "restarts": self._restarts,
                "last_break": self._last_break}

    def _ensure_reaper(self, ex: Executor) -> None:
        if self.hard_seconds is None or getattr(ex, "run_dir", None) is None:
            return
        with self._lock:
            if self._reaper is None and not self._stop.is_set():
                self._reaper = threading.Thread(target=self._reap, daemon=True,
                                                name="hard-limit")
                self._reaper.start()

    def _reap(self) -> None:
        """Kill a worker whose job has run past ``hard_seconds`` (the job's own budget did
        not stop it): the pool breaks, is replaced, and that job is failed."""
        while not self._stop.wait(1.0):
            ex = self._executor
            limit = self.hard_seconds
            if ex is None or limit is None:
                continue
            now = time.time()
            for key, run in running_jobs(getattr(ex, "run_dir", None)).items():
                age = now - run["started"]
                if age > limit:
                    with self._lock:
                        self._killed[key] = (f"killed after {age:.0f} s, past its hard "
                                             f"limit of {limit:.0f} s (the run did not stop "
                                             "at its own budget)")
                    try:
                        os.kill(run["pid"], signal.SIGKILL)
                    except OSError:
                        pass

    def _finish(self, inner: Future, entry: _Entry) -> None:
        if inner.cancelled():
            self._release(entry)
            self._settle(entry.outer, error=RuntimeError("the job was cancelled"))
            return
        exc = inner.exception()
        if isinstance(exc, BrokenProcessPool) and self._broken_pool(entry, exc):
            return
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
