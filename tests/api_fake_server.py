"""A planner service whose full-solver jobs run on the fake solver (for restart tests).

    python tests/api_fake_server.py PORT CACHE_PATH DELAY_SECONDS [--lease S] [--calls FILE]

``--lease``: lease lifetime of the planner's runs (s); ``--calls``: append one line per
fake solver call to FILE (to count runs across several server processes).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import uvicorn

sys.path.insert(0, str(Path(__file__).resolve().parent))

from api_support import fake_full_solver, fake_planner

from api.http import create_app

if __name__ == "__main__":
    p = argparse.ArgumentParser()
    p.add_argument("port", type=int)
    p.add_argument("cache", type=Path)
    p.add_argument("delay", type=float)
    p.add_argument("--lease", type=float, default=None)
    p.add_argument("--calls", type=Path, default=None)
    a = p.parse_args()
    kw = {} if a.lease is None else {"lease_seconds": a.lease}
    with fake_full_solver(a.delay, calls_log=a.calls) as fake, \
            fake_planner(a.cache, fake, **kw) as planner:
        uvicorn.run(create_app(planner=planner, warm=False, **kw), host="127.0.0.1",
                    port=a.port, log_level="warning")
