"""CPU per dose request through the service's ASGI app, in process, trees side by side.

No server and no sockets: each tree's app (``api.http.create_app(cache_path=...)``, its
lifespan run, its kernels warm) runs in a long-lived interpreter of its own
(``PYTHONPATH`` set to the tree) and answers ``--requests`` of load.py's dose requests,
``--concurrency`` at a time, per round; the rounds alternate between the trees (ABBA...) so
that the machine's changing load falls on all of them alike, and each tree's CPU per request
(``time.process_time``: all its threads) is printed with its median ratio to the first
tree's, paired round by round::

    .venv/bin/python benchmarks/service_overhead.py --tree . --tree /tmp/old --rounds 40

(a revision: ``git worktree add /tmp/old 4aa7d90`` first).  What it leaves out of the live
service: the sockets, HTTP parsing (uvicorn's h11) and the validation pool (load.py).
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]


def _payloads(n: int, seed: int) -> list[bytes]:
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from load import payloads

    return [json.dumps(b).encode() for b in payloads(n, seed)]


async def _call(app: Any, body: bytes) -> int:
    """One POST /v1/dose-time through the ASGI app; its status."""
    sent, status = False, 0

    async def receive() -> dict:
        nonlocal sent
        if not sent:
            sent = True
            return {"type": "http.request", "body": body, "more_body": False}
        await asyncio.sleep(3600)  # no disconnect while the answer is made
        return {"type": "http.disconnect"}

    async def send(message: dict) -> None:
        nonlocal status
        if message["type"] == "http.response.start":
            status = message["status"]

    headers = [(b"host", b"127.0.0.1"), (b"content-type", b"application/json"),
               (b"content-length", str(len(body)).encode())]
    await app({"type": "http", "asgi": {"version": "3.0"}, "http_version": "1.1",
               "method": "POST", "scheme": "http", "path": "/v1/dose-time",
               "raw_path": b"/v1/dose-time", "query_string": b"", "root_path": "",
               "headers": headers, "client": ("127.0.0.1", 5000),
               "server": ("127.0.0.1", 8000)}, receive, send)
    return status


async def _serve_rounds(requests: int, concurrency: int) -> None:
    """The child: build the app, then answer one round per 'go' line on stdin, printing
    its ms of CPU per request."""
    from api.http import create_app

    with tempfile.TemporaryDirectory() as tmp:
        app = create_app(cache_path=f"{tmp}/cache.sqlite", warm=True)
        queue: asyncio.Queue = asyncio.Queue()
        started = asyncio.Event()

        async def lifespan_send(message: dict) -> None:
            if message["type"] == "lifespan.startup.complete":
                started.set()

        await queue.put({"type": "lifespan.startup"})
        life = asyncio.create_task(app({"type": "lifespan", "asgi": {"version": "3.0"}},
                                       queue.get, lifespan_send))
        await started.wait()
        bodies = _payloads(requests, 1)
        gate = asyncio.Semaphore(concurrency)

        async def one(body: bytes) -> None:
            async with gate:
                status = await _call(app, body)
            if status != 200:
                raise SystemExit(f"status {status}")

        for body in _payloads(200, 2):  # warm: first answers of each kind
            await one(body)
        print("ready", flush=True)
        loop = asyncio.get_running_loop()
        while (await loop.run_in_executor(None, sys.stdin.readline)).strip() == "go":
            t0 = time.process_time()
            await asyncio.gather(*(one(b) for b in bodies))
            print((time.process_time() - t0) / len(bodies) * 1e3, flush=True)
        await queue.put({"type": "lifespan.shutdown"})
        await life


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--tree", type=Path, action="append", help="a source tree (repeat)")
    p.add_argument("--rounds", type=int, default=30)
    p.add_argument("--requests", type=int, default=64, help="requests per round")
    p.add_argument("--concurrency", type=int, default=16)
    p.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if not (1 <= args.rounds <= 10_000 and 1 <= args.requests <= 100_000
            and 1 <= args.concurrency <= 512):
        p.error("--rounds 1-10000, --requests 1-100000, --concurrency 1-512")
    if args.child:
        asyncio.run(_serve_rounds(args.requests, args.concurrency))
        return 0
    trees = [t.resolve() for t in (args.tree or [ROOT])]
    procs = []
    try:
        for tree in trees:
            procs.append(subprocess.Popen(
                [sys.executable, str(Path(__file__).resolve()), "--child", "--requests",
                 str(args.requests), "--concurrency", str(args.concurrency)],
                cwd=tree, env={**os.environ, "PYTHONPATH": str(tree)}, text=True,
                stdin=subprocess.PIPE, stdout=subprocess.PIPE))
        for proc in procs:
            while (line := proc.stdout.readline()).strip() != "ready":
                if not line:
                    raise SystemExit("a tree's app did not start")
        got: list[list[float]] = [[] for _ in procs]
        for r in range(args.rounds):
            for i in (range(len(procs)) if r % 2 == 0 else reversed(range(len(procs)))):
                procs[i].stdin.write("go\n")
                procs[i].stdin.flush()
                got[i].append(float(procs[i].stdout.readline()))
    finally:
        for proc in procs:
            if proc.poll() is None:
                proc.stdin.write("stop\n")
                proc.stdin.flush()
        for proc in procs:
            try:
                proc.wait(timeout=60)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
    print(f"CPU per dose request in process ({args.concurrency} concurrent, {args.rounds} "
          f"rounds of {args.requests}, alternating):")
    for tree, values in zip(trees, got, strict=True):
        ratio = statistics.median(a / b for a, b in zip(values, got[0], strict=True))
        print(f"  {str(tree):<40} median {statistics.median(values):.3f} ms, min "
              f"{min(values):.3f} ms; {ratio:.2f}x the first tree's (paired median)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
