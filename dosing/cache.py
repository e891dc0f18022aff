"""The validation cache: full-solver trajectories in SQLite, one row per scenario key.

SQLite in WAL mode on a local file: readers never block the writer, every write is one
``BEGIN IMMEDIATE ... COMMIT`` transaction (a row is there whole or not at all), and a
process killed mid-write leaves the file readable with every committed row intact (the
WAL is rolled back on the next open).  Each thread gets its own connection, each process
opens its own, so concurrent readers and writers are safe.  A row holds the trajectory
as an ``.npz`` blob plus its JSON metadata (scenario, horizon, diagnostics).  A second
table records validation requests, so ids survive a restart.
"""

from __future__ import annotations

import json
import os
import sqlite3
import threading
import time
from pathlib import Path
from typing import Any

from .scenario import Trajectory

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
"""


def default_path() -> Path:
    """$THERMOGEL_CACHE, else ~/.cache/thermogel/validations.sqlite."""
    env = os.environ.get(ENV)
    if env:
        return Path(env).expanduser()
    return Path.home() / ".cache" / "thermogel" / "validations.sqlite"


class ValidationCache:
    """Persistent store of full-solver trajectories keyed by the dimensionless scenario."""

    def __init__(self, path: str | os.PathLike[str] | None = None) -> None:
        self.path = Path(path).expanduser() if path is not None else default_path()
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._local = threading.local()
        self._lock = threading.Lock()
        self._connections: list[sqlite3.Connection] = []
        con = self._con()
        con.executescript(_SCHEMA)

    def _con(self) -> sqlite3.Connection:
        con = getattr(self._local, "con", None)
        if con is None:
            con = sqlite3.connect(self.path, timeout=BUSY_TIMEOUT_S, isolation_level=None,
                                  check_same_thread=False)
            con.execute("PRAGMA journal_mode=WAL")
            con.execute("PRAGMA synchronous=FULL")
            con.execute(f"PRAGMA busy_timeout={int(BUSY_TIMEOUT_S * 1000)}")
            self._local.con = con
            with self._lock:
                self._connections.append(con)
        return con

    def _write(self, sql: str, params: tuple[Any, ...]) -> None:
        con = self._con()
        con.execute("BEGIN IMMEDIATE")
        try:
            con.execute(sql, params)
        except BaseException:
            con.execute("ROLLBACK")
            raise
        con.execute("COMMIT")

    # trajectories ---------------------------------------------------------------------
    def put(self, key: str, meta: dict[str, Any], blob: bytes) -> None:
        """Store (or replace) a scenario's trajectory in one atomic transaction."""
        self._write("INSERT OR REPLACE INTO trajectories (key, meta, data, created) "
                    "VALUES (?, ?, ?, ?)", (key, json.dumps(meta), sqlite3.Binary(blob),
                                            time.time()))

    def put_if_longer(self, key: str, meta: dict[str, Any], blob: bytes) -> bool:
        """Store unless a row with at least this horizon is there (one atomic transaction).

        Two writers extending the same scenario never replace a longer run by a shorter one.
        """
        con = self._con()
        con.execute("BEGIN IMMEDIATE")
        try:
            row = con.execute("SELECT meta FROM trajectories WHERE key = ?", (key,)).fetchone()
            old = -1.0 if row is None else float(json.loads(row[0]).get("horizon", -1.0))
            write = old < float(meta.get("horizon", 0.0))
            if write:
                con.execute("INSERT OR REPLACE INTO trajectories (key, meta, data, created) "
                            "VALUES (?, ?, ?, ?)", (key, json.dumps(meta),
                                                    sqlite3.Binary(blob), time.time()))
        except BaseException:
            con.execute("ROLLBACK")
            raise
        con.execute("COMMIT")
        return write

    def put_trajectory(self, key: str, traj: Trajectory) -> None:
        """Store a :class:`Trajectory` under ``key``."""
        self.put(key, traj.meta, traj.to_npz())

    def get(self, key: str) -> Trajectory | None:
        """The stored trajectory for ``key``, or None."""
        row = self._con().execute("SELECT meta, data FROM trajectories WHERE key = ?",
                                  (key,)).fetchone()
        if row is None:
            return None
        return Trajectory.from_npz(bytes(row[1]), json.loads(row[0]))

    def meta(self, key: str) -> dict[str, Any] | None:
        """The metadata alone (no blob decoding), or None."""
        row = self._con().execute("SELECT meta FROM trajectories WHERE key = ?",
                                  (key,)).fetchone()
        return None if row is None else json.loads(row[0])

    def __contains__(self, key: str) -> bool:
        return self._con().execute("SELECT 1 FROM trajectories WHERE key = ?",
                                   (key,)).fetchone() is not None

    def keys(self) -> list[str]:
        """Every stored scenario key."""
        return [r[0] for r in self._con().execute("SELECT key FROM trajectories ORDER BY created")]

    def __len__(self) -> int:
        return int(self._con().execute("SELECT COUNT(*) FROM trajectories").fetchone()[0])

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

    # housekeeping --------------------------------------------------------------------
    def integrity(self) -> str:
        """SQLite's integrity check ('ok' when the file is sound)."""
        return str(self._con().execute("PRAGMA integrity_check").fetchone()[0])

    def close(self) -> None:
        """Close every connection this object opened."""
        with self._lock:
            for con in self._connections:
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
