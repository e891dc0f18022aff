"""Helpers for the API tests: an app served through httpx's ASGI transport, a real uvicorn."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time
from collections.abc import AsyncIterator, Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import asynccontextmanager, contextmanager
from pathlib import Path

import httpx
from dosing_fakes import FakeSolver
from fastapi import FastAPI

from api.client import AsyncClient
from dosing import Planner

ROOT = Path(__file__).resolve().parents[1]


@asynccontextmanager
async def asgi(app: FastAPI) -> AsyncIterator[tuple[AsyncClient, httpx.AsyncClient]]:
    """Run the app's lifespan; yield (api client, raw httpx client) on the ASGI transport."""
    async with app.router.lifespan_context(app):
        transport = httpx.ASGITransport(app=app)
        async with AsyncClient("http://test", transport=transport) as api, \
                httpx.AsyncClient(base_url="http://test", transport=transport) as raw:
            yield api, raw


def free_port() -> int:
    """A free TCP port on the loopback interface."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@contextmanager
def serve(cache: Path, *extra: str, timeout: float = 240.0) -> Iterator[str]:
    """Run ``thermogel serve`` on a loopback port; yield its base URL; stop it after
    (SIGTERM: a graceful shutdown that stops the planner's pool; SIGKILL if it hangs)."""
    with serve_process(cache, *extra, timeout=timeout) as (url, _):
        yield url


@contextmanager
def serve_process(cache: Path, *extra: str,
                  timeout: float = 240.0) -> Iterator[tuple[str, subprocess.Popen]]:
    """:func:`serve` yielding (url, process)."""
    port = free_port()
    with _server([sys.executable, "-m", "api.cli", "serve", "--port", str(port), "--cache",
                  str(cache), "--log-level", "warning", *extra], port, timeout,
                 graceful=True) as pair:
        yield pair


@contextmanager
def fake_server(cache: Path, delay: float, timeout: float = 60.0,
                *extra: str) -> Iterator[tuple[str, object]]:
    """The service with fake full-solver jobs (tests/api_fake_server.py, ``extra`` its
    options); yields (url, proc)."""
    port = free_port()
    script = Path(__file__).with_name("api_fake_server.py")
    with _server([sys.executable, str(script), str(port), str(cache), str(delay), *extra],
                 port, timeout) as pair:
        yield pair


@contextmanager
def _server(cmd: list[str], port: int, timeout: float,
            graceful: bool = False) -> Iterator[tuple[str, object]]:
    """Start ``cmd`` (a server on ``port``), wait for /health; afterwards SIGKILL it (or
    SIGTERM first when ``graceful``)."""
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    proc = subprocess.Popen(cmd, cwd=ROOT, env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True)
    url = f"http://127.0.0.1:{port}"
    try:
        wait_healthy(url, proc, timeout)
        yield url, proc
    finally:
        if graceful and proc.poll() is None:
            proc.terminate()
            try:
                proc.wait(timeout=20)
            except subprocess.TimeoutExpired:
                pass
        proc.kill()
        proc.wait(timeout=10)
        if proc.stderr:
            proc.stderr.close()


def wait_healthy(url: str, proc: subprocess.Popen, timeout: float) -> None:
    """Poll /health until 200; fail with the server's stderr if it dies or times out."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise RuntimeError(f"server exited {proc.returncode}: {proc.stderr.read()}")
        try:
            if httpx.get(f"{url}/health", timeout=1.0).status_code == 200:
                return
        except httpx.TransportError:
            pass
        time.sleep(0.1)
    proc.kill()
    raise RuntimeError(f"server not healthy after {timeout} s: {proc.stderr.read()}")


# ----------------------------------------------------------------------------- a fake solver

class SlowFakeSolver(FakeSolver):
    """The dosing tests' closed-form fake of ``solver.full.simulate``, taking ``delay`` s."""

    def __init__(self, delay: float = 0.0, calls_log: Path | None = None) -> None:
        super().__init__()
        self.delay = delay
        self.calls_log = calls_log

    def __call__(self, *args: object, **kwargs: object) -> object:
        if self.calls_log is not None:  # one line per run, appended atomically (O_APPEND)
            with open(self.calls_log, "a") as f:
                f.write(f"{os.getpid()} {kwargs.get('grid')} {kwargs.get('n')} "
                        f"{kwargs.get('interfacial_length')}\n")
        time.sleep(self.delay)
        return super().__call__(*args, **kwargs)


@contextmanager
def fake_full_solver(delay: float = 0.0,
                     calls_log: Path | None = None) -> Iterator[SlowFakeSolver]:
    """The fake full solver for the block (give it to :func:`fake_planner` or
    ``Planner(solver=...)``): every full-solver job runs on it, in milliseconds."""
    yield SlowFakeSolver(delay, calls_log)


@contextmanager
def fake_planner(cache: Path, solver: FakeSolver, cls: type[Planner] = Planner,
                 **kw: object) -> Iterator[Planner]:
    """A planner running its full-solver jobs on ``solver`` on one thread of this process;
    on exit, queued jobs are cancelled and the thread joined."""
    pool = ThreadPoolExecutor(1, thread_name_prefix="fake-full")
    planner = cls(cache_path=cache, executor=pool, solver=solver, **kw)
    try:
        yield planner
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
        planner.close()
