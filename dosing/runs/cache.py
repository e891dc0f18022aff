"""The validation cache: full-solver trajectories in SQLite, one row per scenario key.

SQLite in WAL mode, one transaction per write, a connection per thread and process; tables of
trajectories (an ``.npz`` blob, JSON metadata, a SHA-256 checked on read), validations, leases
and jobs.  Crash safety, checksums and the tables: docs/architecture.md, "The run store"."""

from __future__ import annotations

import hashlib
import itertools
import json
import logging
import os
import socket
import sqlite3
import threading
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from solver.errors import ParameterError

from .scenario import Trajectory, decode

log = logging.getLogger("thermogel.cache")

ENV = "THERMOGEL_CACHE"
BUSY_TIMEOUT_S = 60.0

_SCHEMA = """
CREATE TABLE IF NOT EXISTS trajectories (
    key TEXT PRIMARY KEY,
    meta TEXT NOT NULL,
    data BLOB NOT NULL,
    created REAL NOT NULL
);
CREATE TABLE IF NOT EXISTS validations (
    id TEXT PRIMARY KEY,
    record TEXT NOT NULL,
    created REAL NOT NULL
);
CREATE TABLE IF NOT EXISTS leases (
    key TEXT PRIMARY KEY,
    owner TEXT NOT NULL,
    expires REAL NOT NULL
);
CREATE TABLE IF NOT EXISTS starts (
    prefix TEXT PRIMARY KEY,
    scenario TEXT NOT NULL,
    steps INTEGER NOT NULL
);
CREATE TABLE IF NOT EXISTS jobs (
    id TEXT PRIMARY KEY,
    kind TEXT NOT NULL,
    request TEXT NOT NULL,
    status TEXT NOT NULL,
    result TEXT,
    error TEXT,
    created REAL NOT NULL,
    updated REAL NOT NULL
);
"""
JOB_STATES = ("pending", "done", "failed")
CACHE_VALID = "a writable SQLite file whose directory exists or can be created"
_SERIALS = itertools.count(1)  # each connection's number (a generation token names it)


def _owner_gone(owner: str) -> bool:
    """True when a lease owner ('host:pid:tag') is a process of this host that has ended."""
    host, _, rest = owner.partition(":")
    pid_text = rest.partition(":")[0]
    if host != socket.gethostname() or not pid_text.isdigit():
        return False
    pid = int(pid_text)
    if pid == os.getpid():
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except OSError:  # exists (another user's) or cannot tell
        return False
    return False


def row_checksum(meta_text: str, blob: bytes) -> str:
    """SHA-256 of a trajectory row's stored metadata text and blob."""
    h = hashlib.sha256(meta_text.encode("utf-8"))
    h.update(b"\0")
    h.update(blob)
    return h.hexdigest()


def _add_checksum_column(con: sqlite3.Connection) -> None:
    """Add the trajectories' ``sha256`` column to a file made before it (idempotent)."""
    cols = {r[1] for r in con.execute("PRAGMA table_info(trajectories)")}
    if "sha256" in cols:
        return
    try:
        con.execute("ALTER TABLE trajectories ADD COLUMN sha256 TEXT")
    except sqlite3.OperationalError as exc:  # another process added it meanwhile
        if "duplicate column" not in str(exc):
            raise


def default_path() -> Path:
    """$THERMOGEL_CACHE, else the user cache folder's validations.sqlite
    (~/.cache/thermogel/ on Linux; dosing.settings)."""
    from ..settings import settings

    return settings().cache_path


def _sound(meta_text: Any, blob: bytes, digest: str | None) -> bool:
    """True if a row's checksum matches (rows without one: if their metadata parses)."""
    if not isinstance(meta_text, str):
        return False
    if digest is not None:
        return row_checksum(meta_text, bytes(blob)) == digest
    try:
        json.loads(meta_text)
    except ValueError:
        return False
    return True


class ValidationCache:
    """Persistent store of full-solver trajectories keyed by the dimensionless scenario."""

    def __init__(self, path: str | os.PathLike[str] | None = None) -> None:
        self.path = Path(path).expanduser() if path is not None else default_path()
        self._local = threading.local()
        self._lock = threading.Lock()
        self.corrupt_rows = 0  # damaged rows detected (and dropped) by this object
        self._connections: list[tuple[threading.Thread, sqlite3.Connection]] = []
        try:
            if self.path.is_dir():
                raise sqlite3.OperationalError("it is a directory")
            self.path.parent.mkdir(parents=True, exist_ok=True)
            con = self._con()
            con.executescript(_SCHEMA)
            _add_checksum_column(con)
            con.execute("BEGIN IMMEDIATE")  # a read-only file fails here, not mid-request
            con.execute("ROLLBACK")
        except (sqlite3.Error, OSError) as exc:
            self.close()
            err = ParameterError("cache", str(self.path), CACHE_VALID, f"cannot open it: {exc}")
            err.reason = f"cannot open it: {exc}"
            raise err from None

    def _con(self) -> sqlite3.Connection:
        con = getattr(self._local, "con", None)
        if con is None:
            con = sqlite3.connect(self.path, timeout=BUSY_TIMEOUT_S, isolation_level=None,
                                  check_same_thread=False)
            con.execute("PRAGMA journal_mode=WAL")
            con.execute("PRAGMA synchronous=FULL")
            con.execute(f"PRAGMA busy_timeout={int(BUSY_TIMEOUT_S * 1000)}")
            self._local.con = con
            self._local.serial = next(_SERIALS)
            with self._lock:
                alive = []
                for thread, old in self._connections:  # threads come and go (thread pools)
                    if thread.is_alive():
                        alive.append((thread, old))
                    else:
                        old.close()
                self._connections = [*alive, (threading.current_thread(), con)]
        return con

    @contextmanager
    def _transaction(self) -> Iterator[sqlite3.Connection]:
        """This thread's connection inside one ``BEGIN IMMEDIATE ... COMMIT`` write
        transaction (rolled back if the block raises)."""
        con = self._con()
        con.execute("BEGIN IMMEDIATE")
        try:
            yield con
        except BaseException:
            if con.in_transaction:  # SQLITE_FULL (a full disk) has rolled it back already
                con.execute("ROLLBACK")
            raise
        con.execute("COMMIT")

    def _write(self, sql: str, params: tuple[Any, ...]) -> int:
        """One statement in its own write transaction; the number of rows it changed."""
        with self._transaction() as con:
            return con.execute(sql, params).rowcount

    # trajectories ---------------------------------------------------------------------
    def put(self, key: str, meta: dict[str, Any], blob: bytes) -> None:
        """Store (or replace) a scenario's trajectory in one atomic transaction."""
        text = json.dumps(meta)
        self._write("INSERT OR REPLACE INTO trajectories (key, meta, data, created, sha256) "
                    "VALUES (?, ?, ?, ?, ?)", (key, text, sqlite3.Binary(blob), time.time(),
                                               row_checksum(text, blob)))

    def put_if_longer(self, key: str, meta: dict[str, Any], blob: bytes) -> bool:
        """Store unless a row with at least this horizon is there (one atomic transaction).

        Two writers extending the same scenario never replace a longer run by a shorter one.
        """
        with self._transaction() as con:
            row = con.execute("SELECT meta, data, sha256 FROM trajectories WHERE key = ?",
                              (key,)).fetchone()
            old = -1.0
            if row is not None and _sound(row[0], row[1], row[2]):
                old = float(json.loads(row[0]).get("horizon", -1.0))
            write = old < float(meta.get("horizon", 0.0))
            if write:
                text = json.dumps(meta)
                con.execute("INSERT OR REPLACE INTO trajectories (key, meta, data, created, "
                            "sha256) VALUES (?, ?, ?, ?, ?)",
                            (key, text, sqlite3.Binary(blob), time.time(),
                             row_checksum(text, blob)))
        return write

    def put_trajectory(self, key: str, traj: Trajectory) -> None:
        """Store a :class:`Trajectory` under ``key``."""
        self.put(key, traj.meta, traj.to_npz())

    def _row(self, key: str) -> tuple[dict[str, Any], bytes] | None:
        """(metadata, blob) of a sound row, or None: a row failing its checksum (or whose
        metadata does not parse) is dropped and reported missing (computed again)."""
        row = self._con().execute("SELECT meta, data, sha256 FROM trajectories WHERE key = ?",
                                  (key,)).fetchone()
        if row is None:
            return None
        text, blob, digest = row[0], bytes(row[1]), row[2]
        if not _sound(text, blob, digest):
            log.warning("cache row %s: %d bytes of metadata and %d of data fail the stored "
                        "checksum %s", key, len(text) if isinstance(text, str) else -1,
                        len(blob), digest)
            self._drop_corrupt(key, digest)
            return None
        return json.loads(text), blob

    def _drop_corrupt(self, key: str, digest: str | None) -> None:
        """Delete a damaged row (unless a sound one replaced it meanwhile)."""
        log.warning("cache row %s failed its checksum: dropped, it will be computed again",
                    key)
        self.corrupt_rows += 1
        self._write("DELETE FROM trajectories WHERE key = ? AND sha256 IS ?", (key, digest))

    def get(self, key: str) -> Trajectory | None:
        """The stored trajectory for ``key``, or None (also for a damaged row: dropped)."""
        raw = self._row(key)
        if raw is None:
            return None
        try:
            return decode(raw[1], raw[0])
        except Exception as exc:  # an unchecked (old) row that no longer decodes
            log.warning("cache row %s does not decode (%r): dropped", key, exc)
            self._drop_corrupt(key, self._digest(key))
            return None

    def _digest(self, key: str) -> str | None:
        row = self._con().execute("SELECT sha256 FROM trajectories WHERE key = ?",
                                  (key,)).fetchone()
        return None if row is None else row[0]

    def digests(self, keys: list[str] | tuple[str, ...]) -> dict[str, str | None]:
        """Each key's row checksum (None: no row), with no blob read; remembered while the
        file's version (:meth:`get_many`) stays put.  A caller holding a decoded row knows
        from it whether the row changed (a longer run stored) without reading it again."""
        con = self._con()
        version = self._version(con)
        memo = getattr(self._local, "digests", None)
        if memo is None or memo[0] != version or len(memo[1]) > 4096:
            memo = (version, {})
            self._local.digests = memo
        known = memo[1]
        ask = [k for k in dict.fromkeys(keys) if k not in known]
        for i in range(0, len(ask), 500):  # SQLite's bound-parameter limit
            part = ask[i:i + 500]
            known.update(dict.fromkeys(part))
            marks = ",".join("?" * len(part))
            known.update(con.execute(
                f"SELECT key, sha256 FROM trajectories WHERE key IN ({marks})", part))
        return {k: known[k] for k in keys}

    def get_many(self, keys: list[str] | tuple[str, ...],
                 found: dict[str, str] | None = None
                 ) -> dict[str, tuple[dict[str, Any], bytes]]:
        """(metadata, npz blob) of every stored key among ``keys`` in one query, checksums verified
        (absent keys and damaged rows, dropped, left out; no decoding).  ``found``, if given, gets
        each row's checksum (:meth:`digests`).  Absent keys are remembered while ``PRAGMA
        data_version`` and ``total_changes`` stand still (docs/speed.md sec. 2)."""
        out: dict[str, tuple[dict[str, Any], bytes]] = {}
        con = self._con()
        uniq = list(dict.fromkeys(keys))
        version = self._version(con)
        absent = getattr(self._local, "absent", None)
        if absent is not None and absent[0] == version:
            if absent[1].issuperset(uniq):
                return out
        else:
            absent = (version, set())
        for i in range(0, len(uniq), 500):  # SQLite's bound-parameter limit
            part = uniq[i:i + 500]
            marks = ",".join("?" * len(part))
            for key, meta, data, digest in con.execute(
                    f"SELECT key, meta, data, sha256 FROM trajectories WHERE key IN ({marks})",
                    part):
                if _sound(meta, bytes(data), digest):
                    out[key] = (json.loads(meta), bytes(data))
                    if found is not None:
                        found[key] = digest
                else:  # damaged: dropped (and so absent: computed again)
                    self._drop_corrupt(key, digest)
        absent[1].update(k for k in uniq if k not in out)
        if len(absent[1]) > 4096:
            absent = (version, {k for k in uniq if k not in out})
        self._local.absent = absent
        return out

    @staticmethod
    def _version(con: sqlite3.Connection) -> tuple[int, int]:
        """What moves when the file may have changed: ``PRAGMA data_version`` (another
        connection, thread or process committed) and this connection's ``total_changes``."""
        return con.execute("PRAGMA data_version").fetchone()[0], con.total_changes

    def generation(self) -> tuple[int, int, int]:
        """A token that changes whenever any row of the file may have changed since this
        thread last asked: this thread's connection (its number: the counters are its own),
        ``PRAGMA data_version`` (another connection, thread or process committed) and the
        connection's ``total_changes`` (its own writes).  One pragma, no row read: what was
        built from the rows under an equal token is still what they would give."""
        con = self._con()
        return (self._local.serial, *self._version(con))

    def stored_runs(self) -> frozenset[tuple[float, float, str, float]] | None:
        """(t_start, t_end, branch, interfacial length) of every stored jump run, from the
        rows' metadata (its ``scenario``), read again only when the file's version
        (:meth:`get_many`) moved; None when a row's metadata does not say (then any run
        may be stored).  A validation whose truth run is not among them is not complete:
        its runs' keys and their lookup are not needed (a bead size never validated)."""
        con = self._con()
        version = self._version(con)
        memo = getattr(self._local, "runs", None)
        if memo is not None and memo[0] == version:
            return memo[1]
        runs: set[tuple[float, float, str, float]] | None = set()
        for (text,) in con.execute("SELECT meta FROM trajectories"):
            try:
                sc = json.loads(text)["scenario"]
                if sc.get("t_end") is not None:  # a jump (not a protocol or program)
                    runs.add((float(sc["t_start"]), float(sc["t_end"]), str(sc["branch"]),
                              float(sc["settings"]["interfacial_length"])))
            except (ValueError, KeyError, TypeError, AttributeError):
                runs = None  # a row that does not say: every run may be stored
                break
        out = None if runs is None else frozenset(runs)
        self._local.runs = (version, out)
        return out

    def get_raw(self, key: str) -> tuple[dict[str, Any], bytes] | None:
        """(metadata, npz blob) as stored, or None (no decoding; checksum verified)."""
        return self._row(key)

    def meta(self, key: str) -> dict[str, Any] | None:
        """The metadata alone (no blob decoding; checksum verified), or None."""
        raw = self._row(key)
        return None if raw is None else raw[0]

    def __contains__(self, key: str) -> bool:
        return self._con().execute("SELECT 1 FROM trajectories WHERE key = ?",
                                   (key,)).fetchone() is not None

    def keys(self) -> list[str]:
        """Every stored scenario key."""
        return [r[0] for r in self._con().execute("SELECT key FROM trajectories ORDER BY created")]

    def __len__(self) -> int:
        return int(self._con().execute("SELECT COUNT(*) FROM trajectories").fetchone()[0])

    # protocol starts (dosing.planner: which stored run kept its state at a prefix) ------
    def put_starts(self, rows: Sequence[tuple[str, dict[str, Any], int]]) -> None:
        """Remember, per protocol prefix key, the run (its scenario) that kept its state
        after that prefix's ``steps`` steps (the last one seen wins)."""
        if not rows:
            return
        with self._transaction() as con:
            con.executemany("INSERT OR REPLACE INTO starts (prefix, scenario, steps) "
                            "VALUES (?, ?, ?)",
                            [(k, json.dumps(sc, sort_keys=True), int(j)) for k, sc, j in rows])

    def get_start(self, prefix: str) -> tuple[dict[str, Any], int] | None:
        """(scenario, steps) of the run remembered for a prefix key, or None."""
        row = self._con().execute("SELECT scenario, steps FROM starts WHERE prefix = ?",
                                  (prefix,)).fetchone()
        return None if row is None else (json.loads(row[0]), int(row[1]))

    # validation records --------------------------------------------------------------
    def put_validation(self, vid: str, record: dict[str, Any]) -> None:
        """Remember a validation request (id -> scenario keys and dose) across restarts."""
        self._write("INSERT OR REPLACE INTO validations (id, record, created) VALUES (?, ?, ?)",
                    (vid, json.dumps(record), time.time()))

    def get_validation(self, vid: str) -> dict[str, Any] | None:
        """The recorded validation request, or None."""
        row = self._con().execute("SELECT record FROM validations WHERE id = ?",
                                  (vid,)).fetchone()
        return None if row is None else json.loads(row[0])

    # leases (dosing.runs.jobs.Leases) -------------------------------------------------------
    def claim(self, key: str, owner: str, seconds: float) -> bool:
        """Take the lease on ``key`` for ``seconds`` if it is free, expired, ours, or held
        by a process of this host that has ended; True if we hold it now."""
        now = time.time()
        with self._transaction() as con:
            row = con.execute("SELECT owner, expires FROM leases WHERE key = ?",
                              (key,)).fetchone()
            free = row is None or row[0] == owner or row[1] < now or _owner_gone(row[0])
            if free:
                con.execute("INSERT OR REPLACE INTO leases (key, owner, expires) "
                            "VALUES (?, ?, ?)", (key, owner, now + seconds))
        return free

    def renew(self, keys: list[str] | tuple[str, ...], owner: str, seconds: float) -> None:
        """Extend our leases on ``keys`` to ``seconds`` from now (one transaction)."""
        with self._transaction() as con:
            con.executemany("UPDATE leases SET expires = ? WHERE key = ? AND owner = ?",
                            [(time.time() + seconds, k, owner) for k in keys])

    def release(self, key: str, owner: str) -> None:
        """Drop our lease on ``key`` (another owner's is left alone)."""
        self._write("DELETE FROM leases WHERE key = ? AND owner = ?", (key, owner))

    def lease(self, key: str) -> tuple[str, float] | None:
        """(owner, expiry time) of the lease on ``key``, or None."""
        row = self._con().execute("SELECT owner, expires FROM leases WHERE key = ?",
                                  (key,)).fetchone()
        return None if row is None else (str(row[0]), float(row[1]))

    # jobs -----------------------------------------------------------------------------
    def put_job(self, job_id: str, kind: str, request: dict[str, Any]) -> bool:
        """Record a job (state 'pending') unless it is there; True if it was new."""
        now = time.time()
        return self._write("INSERT OR IGNORE INTO jobs (id, kind, request, status, created, "
                           "updated) VALUES (?, ?, ?, 'pending', ?, ?)",
                           (job_id, kind, json.dumps(request), now, now)) > 0

    def finish_job(self, job_id: str, status: str, result: dict[str, Any] | None = None,
                   error: str | None = None) -> None:
        """Store a job's outcome: 'done' with its result, or 'failed' with why."""
        if status not in JOB_STATES:
            raise ValueError(f"status must be one of {JOB_STATES}")
        self._write("UPDATE jobs SET status = ?, result = ?, error = ?, updated = ? "
                    "WHERE id = ?", (status, None if result is None else json.dumps(result),
                                     error, time.time(), job_id))

    def forget_job(self, job_id: str) -> None:
        """Drop a job's row (a run's remembered failure, asked for again)."""
        self._write("DELETE FROM jobs WHERE id = ?", (job_id,))

    def get_job(self, job_id: str) -> dict[str, Any] | None:
        """The job: id, kind, request, status, result, error; or None."""
        row = self._con().execute("SELECT id, kind, request, status, result, error FROM jobs "
                                  "WHERE id = ?", (job_id,)).fetchone()
        if row is None:
            return None
        return {"id": row[0], "kind": row[1], "request": json.loads(row[2]), "status": row[3],
                "result": None if row[4] is None else json.loads(row[4]), "error": row[5]}

    # housekeeping --------------------------------------------------------------------
    def integrity(self) -> str:
        """SQLite's integrity check ('ok' when the file is sound)."""
        return str(self._con().execute("PRAGMA integrity_check").fetchone()[0])

    def close(self) -> None:
        """Close the connections of this thread and of threads that have ended; a live
        thread's connection is only let go (closing it under a running statement could
        crash), so it closes when that thread drops it.  Using the cache afterwards opens
        new connections."""
        me = threading.current_thread()
        with self._lock:
            for thread, con in self._connections:
                if thread is me or not thread.is_alive():
                    try:
                        con.close()
                    except sqlite3.Error:
                        pass
            self._connections.clear()
        self._local = threading.local()

    def __enter__(self) -> ValidationCache:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
