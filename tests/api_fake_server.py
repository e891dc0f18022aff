"""A planner service whose full-solver jobs run on the fake solver (for restart tests).

    python tests/api_fake_server.py PORT CACHE_PATH DELAY_SECONDS [--lease S] [--calls FILE]
        [--read-timeout S] [--per-client N] [--max-body B] [--token T] [--full-disk]

``--lease``: lease lifetime of the planner's runs (s); ``--calls``: append one line per
fake solver call to FILE (to count runs across several server processes);
``--read-timeout`` / ``--per-client``: the connection guards (api.connections);
``--max-body``: the body limit; ``--token``: the API token; ``--full-disk``: SQLite's
``max_page_count`` pinned to the file's size on every cache connection, so that a write
needing a new page fails as on a full disk (SQLITE_FULL).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import uvicorn

sys.path.insert(0, str(Path(__file__).resolve().parent))

from api_support import fake_full_solver, fake_planner

from api.connection_limits import ConnectionLimits
from api.connections import uvicorn_options
from api.http import DEFAULT_MAX_BODY, create_app


def _full_disk(cache: object) -> None:
    """Every connection of ``cache`` refuses to grow the file (SQLITE_FULL on a write)."""
    opened = cache._con  # type: ignore[attr-defined]

    def full() -> object:
        con = opened()
        con.execute("PRAGMA max_page_count = 1")  # clamped to the current size
        return con

    cache._con = full  # type: ignore[attr-defined]


if __name__ == "__main__":
    p = argparse.ArgumentParser()
    p.add_argument("port", type=int)
    p.add_argument("cache", type=Path)
    p.add_argument("delay", type=float)
    p.add_argument("--lease", type=float, default=None)
    p.add_argument("--calls", type=Path, default=None)
    p.add_argument("--read-timeout", type=float, default=None)
    p.add_argument("--per-client", type=int, default=None)
    p.add_argument("--max-body", type=int, default=DEFAULT_MAX_BODY)
    p.add_argument("--token", default=None)
    p.add_argument("--full-disk", action="store_true")
    a = p.parse_args()
    kw = {} if a.lease is None else {"lease_seconds": a.lease}
    given = {"read_timeout": a.read_timeout, "per_client": a.per_client}
    limits = ConnectionLimits(**{k: v for k, v in given.items() if v is not None})
    with fake_full_solver(a.delay, calls_log=a.calls) as fake, \
            fake_planner(a.cache, fake, **kw) as planner:
        if a.full_disk:
            _full_disk(planner.cache)
        uvicorn.run(create_app(planner=planner, warm=False, max_body_bytes=a.max_body,
                               api_token=a.token, **kw),
                    host="127.0.0.1", port=a.port, log_level="warning",
                    **uvicorn_options(limits))
