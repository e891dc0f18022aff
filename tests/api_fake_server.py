"""A planner service whose full-solver jobs run on the fake solver (for restart tests).

    python tests/api_fake_server.py PORT CACHE_PATH DELAY_SECONDS
"""

from __future__ import annotations

import sys
from pathlib import Path

import uvicorn

sys.path.insert(0, str(Path(__file__).resolve().parent))

from api_support import fake_full_solver, fake_planner  # noqa: E402

from api.http import create_app  # noqa: E402

if __name__ == "__main__":
    port, cache, delay = int(sys.argv[1]), Path(sys.argv[2]), float(sys.argv[3])
    with fake_full_solver(delay), fake_planner(cache) as planner:
        uvicorn.run(create_app(planner=planner, warm=False), host="127.0.0.1", port=port,
                    log_level="warning")
