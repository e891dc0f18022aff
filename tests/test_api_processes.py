"""No process survives its owner (issue 15, D3): ``thermogel serve``'s process-pool
workers and their resource tracker end with the server, stopped (SIGTERM) or killed."""

from __future__ import annotations

import time
from pathlib import Path

import httpx
import psutil
import pytest
from api_support import serve_process

SMOOTH = {"gel": "ANB", "t_start": 300.0, "t_end": 303.0, "dose_fraction": 0.2}


def _alive(pids: list[int]) -> list[int]:
    out = []
    for pid in pids:
        try:
            if psutil.Process(pid).status() != psutil.STATUS_ZOMBIE:
                out.append(pid)
        except psutil.NoSuchProcess:
            pass
    return out


@pytest.mark.slow
@pytest.mark.parametrize("how", ["terminate", "kill"])
def test_no_child_outlives_the_server(tmp_path: Path, how: str) -> None:
    """A validation makes the planner spawn its pool; after SIGTERM (graceful: the pool is
    stopped) or SIGKILL (each worker notices its parent is gone) every descendant the
    server had is gone within seconds."""
    with serve_process(tmp_path / "c.sqlite", "--no-warmup") as (url, proc):
        r = httpx.post(f"{url}/v1/dose-time", json=SMOOTH, timeout=60)
        assert r.status_code == 202, r.text
        server = psutil.Process(proc.pid)
        deadline = time.monotonic() + 60
        children: list[int] = []
        while time.monotonic() < deadline:
            children = [p.pid for p in server.children(recursive=True)]
            if len(children) >= 2:  # a pool worker and its resource tracker at least
                break
            time.sleep(0.2)
        assert len(children) >= 2, children
        getattr(proc, how)()
        proc.wait(30)
        deadline = time.monotonic() + 20
        while _alive(children) and time.monotonic() < deadline:
            time.sleep(0.2)
        left = _alive(children)
        print(f"{how}: {len(children)} children before, {len(left)} after")
        assert left == [], [psutil.Process(p).cmdline() for p in left]
