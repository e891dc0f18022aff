"""Bounded loopback load test of the planner service (issue 6).

Starts ``thermogel serve`` on 127.0.0.1 (a free port, a fresh cache file), queues two
full-solver validations, then sends dose-time requests over ``--concurrency`` keep-alive
connections in two phases:

1. closed loop: each connection sends its next request as soon as the last is answered,
   ``--requests`` in all.  This measures capacity; its median latency is necessarily
   about concurrency / throughput (Little's law).
2. paced (open loop): the same number of requests arriving as a Poisson stream at
   ``--rate`` requests/s (default: half the closed-loop throughput) spread over the same
   connections; latency runs from each request's scheduled time, so time spent waiting
   for a free connection counts (no coordinated omission).

Doses (10-85 % of the stored fluid), bead sizes (10-200 um) and the gel (ANB 302->308 K,
HHT 304->308 K: front-model scenarios) vary per request.  The client is a minimal
HTTP/1.1 keep-alive client on asyncio streams, so that it costs far less CPU than the
server it measures.  Prints throughput, latency percentiles and every non-2xx answer or
transport error; a 429 (queue full) is reported as such, with the server's message, not
raised::

    .venv/bin/python benchmarks/load.py                    # 2,000 requests, 32 connections
    .venv/bin/python benchmarks/load.py --url http://127.0.0.1:8000   # an existing server

Exit status 1 when any request failed.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import random
import socket
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

import httpx
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
IDLE_REOPEN_S = 4.0
SCENARIOS = [("ANB", 302.0, 308.0), ("HHT", 304.0, 308.0)]
# Validations queued before the load starts (a front scenario and a smooth one).
VALIDATIONS = [
    {"gel": "ANB", "t_start": 302.0, "t_end": 308.0, "dose_fraction": 0.5, "validate": True},
    {"gel": "ANB", "t_start": 300.0, "t_end": 303.0, "dose_fraction": 0.2},
]


def free_port() -> int:
    """A free TCP port on the loopback interface."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start_server(cache: Path, workers: int, max_pending: int | None = None,
                 root: Path = ROOT) -> tuple[subprocess.Popen, str]:
    """``thermogel serve`` of the tree ``root`` on a free loopback port; returns once
    /health answers 200."""
    port = free_port()
    cmd = [sys.executable, "-m", "api.cli", "serve", "--port", str(port), "--cache", str(cache),
           "--workers", str(workers), "--log-level", "warning"]
    if max_pending is not None:
        cmd += ["--max-pending", str(max_pending)]
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    if root != ROOT:
        env["PYTHONPATH"] = str(root)
    proc = subprocess.Popen(cmd, cwd=root, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            text=True, env=env)
    url = f"http://127.0.0.1:{port}"
    deadline = time.monotonic() + 180.0
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise SystemExit(f"server exited: {proc.stderr.read()}")
        try:
            if httpx.get(f"{url}/health", timeout=1.0).status_code == 200:
                return proc, url
        except httpx.TransportError:
            time.sleep(0.2)
    proc.kill()
    raise SystemExit("server did not become healthy in 180 s")


def server_cpu(proc: subprocess.Popen | None) -> float | None:
    """CPU seconds (user + system, its threads included) of the server process so far, or
    None (a server this script did not start, or not on Linux)."""
    try:
        with open(f"/proc/{proc.pid}/stat") as f:  # type: ignore[union-attr]
            fields = f.read().rsplit(")", 1)[1].split()
    except (AttributeError, OSError):
        return None
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")  # utime, stime


def payloads(n: int, seed: int) -> list[dict]:
    """``n`` dose-time requests on front scenarios, varied doses and bead sizes."""
    rng = random.Random(seed)
    out = []
    for _ in range(n):
        gel, t0, t1 = rng.choice(SCENARIOS)
        out.append({"gel": gel, "t_start": t0, "t_end": t1,
                    "dose_fraction": round(rng.uniform(0.10, 0.85), 4),
                    "dry_radius_um": round(rng.uniform(10.0, 200.0), 2)})
    return out


class Connection:
    """One HTTP/1.1 keep-alive connection (enough for this server: Content-Length bodies)."""

    def __init__(self, host: str, port: int) -> None:
        self.host, self.port = host, port
        self.reader: asyncio.StreamReader | None = None
        self.writer: asyncio.StreamWriter | None = None
        self.last_used = 0.0

    async def open(self) -> None:
        """(Re)connect."""
        await self.close()
        self.reader, self.writer = await asyncio.open_connection(self.host, self.port)

    async def close(self) -> None:
        """Close the socket if open."""
        if self.writer is not None:
            self.writer.close()
            self.reader = self.writer = None

    async def post(self, path: str, body: bytes) -> int:
        """POST ``body``; return the status code (the answer body is read and dropped).

        A connection idle longer than the server's keep-alive (uvicorn: 5 s) is reopened
        first, as HTTP clients do, so an idle close is not counted as an error.
        """
        if self.writer is None or time.perf_counter() - self.last_used > IDLE_REOPEN_S:
            await self.open()
        self.last_used = time.perf_counter()
        head = (f"POST {path} HTTP/1.1\r\nHost: {self.host}:{self.port}\r\n"
                f"Content-Type: application/json\r\nContent-Length: {len(body)}\r\n\r\n")
        self.writer.write(head.encode() + body)
        raw = await self.reader.readuntil(b"\r\n\r\n")
        lines = raw.decode("latin-1").split("\r\n")
        status = int(lines[0].split(" ", 2)[1])
        headers = dict(line.split(":", 1) for line in lines[1:] if ":" in line)
        length = {k.strip().lower(): v.strip() for k, v in headers.items()}.get("content-length")
        if length is None:
            raise ConnectionError("answer without Content-Length")
        await self.reader.readexactly(int(length))
        self.last_used = time.perf_counter()
        return status


async def run_load(url: str, bodies: list[dict], concurrency: int,
                   rate: float | None = None, seed: int = 0) -> dict:
    """Send every body over ``concurrency`` connections: closed loop, or Poisson arrivals at
    ``rate`` per second (latency from the scheduled time).  Latencies in ms."""
    host, port = url.split("//", 1)[1].rsplit(":", 1)
    conns = [Connection(host, int(port)) for _ in range(concurrency)]
    await asyncio.gather(*(c.open() for c in conns))
    payload = [json.dumps(b).encode() for b in bodies]
    queue: asyncio.Queue = asyncio.Queue()
    latencies: list[float] = []
    statuses: Counter[str] = Counter()
    t_begin = time.perf_counter()
    if rate is None:
        for body in payload:
            queue.put_nowait((None, body))
    else:
        gaps = np.random.default_rng(seed).exponential(1.0 / rate, len(payload))
        due = t_begin + np.cumsum(gaps)

        async def dispatch() -> None:
            for at, body in zip(due, payload, strict=True):
                await asyncio.sleep(max(0.0, at - time.perf_counter()))
                queue.put_nowait((float(at), body))

    async def worker(conn: Connection) -> None:
        while len(latencies) < len(payload):
            try:
                at, body = await asyncio.wait_for(queue.get(), timeout=0.05)
            except asyncio.TimeoutError:
                continue
            t0 = time.perf_counter() if at is None else at
            try:
                statuses[str(await conn.post("/v1/dose-time", body))] += 1
            except (OSError, asyncio.IncompleteReadError, ConnectionError, ValueError) as exc:
                statuses[type(exc).__name__] += 1
                await conn.open()
            latencies.append((time.perf_counter() - t0) * 1e3)

    tasks = [worker(c) for c in conns] + ([dispatch()] if rate is not None else [])
    await asyncio.gather(*tasks)
    wall = time.perf_counter() - t_begin
    await asyncio.gather(*(c.close() for c in conns))
    lat = np.array(latencies)
    errors = sum(v for k, v in statuses.items() if not k.startswith("2") and k != "429")
    return {"mode": "closed loop" if rate is None else f"paced at {rate:.0f} req/s",
            "requests": len(latencies), "concurrency": concurrency, "wall_s": wall,
            "throughput_rps": len(latencies) / wall, "p50_ms": float(np.percentile(lat, 50)),
            "p90_ms": float(np.percentile(lat, 90)), "p99_ms": float(np.percentile(lat, 99)),
            "max_ms": float(lat.max()), "errors": errors, "queue_full_429": statuses["429"],
            "statuses": dict(statuses)}


def queue_validations(url: str) -> tuple[list[str], list[str]]:
    """Queue the full-solver validations that run while the load is on: their ids, and
    the refusals (a 429 when the queue is full: reported, not raised)."""
    ids, refused = [], []
    with httpx.Client(base_url=url, timeout=60.0) as c:
        for body in VALIDATIONS:
            r = c.post("/v1/dose-time", json=body)
            if r.status_code == 429:
                refused.append(f"429 (retry after {r.headers.get('retry-after')} s): "
                               f"{r.json().get('detail')}")
                continue
            r.raise_for_status()
            if r.json().get("validation_id"):
                ids.append(r.json()["validation_id"])
    return ids, refused


def validation_states(url: str, ids: list[str]) -> dict[str, str]:
    """Each queued validation's state after the load."""
    with httpx.Client(base_url=url, timeout=60.0) as c:
        return {i: c.get(f"/v1/validations/{i}").json()["status"] for i in ids}


def _print(res: dict) -> None:
    if "server_cpu_ms_per_request" in res:
        print(f"server CPU per request: {res['server_cpu_ms_per_request']:.3f} ms")
    print(f"{res['mode']}: {res['requests']} dose-time requests over {res['concurrency']} "
          f"connections in {res['wall_s']:.2f} s = {res['throughput_rps']:.0f} req/s; "
          f"latency p50 {res['p50_ms']:.1f} ms, p90 {res['p90_ms']:.1f} ms, "
          f"p99 {res['p99_ms']:.1f} ms, max {res['max_ms']:.1f} ms; errors {res['errors']}, "
          f"429 (queue full) {res['queue_full_429']} {res['statuses']}")


def main(argv: list[str] | None = None) -> int:
    """Run the load test and print its figures (text, or one JSON object)."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--requests", type=int, default=2000, help="requests per phase")
    p.add_argument("--concurrency", type=int, default=32, help="client connections")
    p.add_argument("--rate", type=float, default=None,
                   help="paced phase arrival rate, req/s (default: half the closed-loop rate)")
    p.add_argument("--warmup", type=int, default=200, help="requests sent first, not counted")
    p.add_argument("--workers", type=int, default=1, help="uvicorn workers of the server")
    p.add_argument("--max-pending", type=int, default=None,
                   help="the started server's validation queue (default: its own)")
    p.add_argument("--url", default=None, help="an already running server (else one starts)")
    p.add_argument("--tree", type=Path, default=ROOT,
                   help="the source tree whose server starts (default this one; "
                        "benchmarks/speed.py measures other revisions with this client)")
    p.add_argument("--no-validations", action="store_true",
                   help="queue no validations (the server's own cost alone, no pool running)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--json", action="store_true")
    args = p.parse_args(argv)
    if not (1 <= args.requests <= 100_000 and 1 <= args.concurrency <= 512):
        p.error("--requests 1-100000 and --concurrency 1-512")
    if args.rate is not None and not (0.1 <= args.rate <= 1e5):
        p.error("--rate 0.1-100000")
    proc = None
    tmp = tempfile.TemporaryDirectory()
    try:
        url = args.url
        if url is None:
            proc, url = start_server(Path(tmp.name) / "cache.sqlite", args.workers,
                                     args.max_pending, args.tree.resolve())
        ids, refused = ([], []) if args.no_validations else queue_validations(url)
        if args.warmup > 0:
            asyncio.run(run_load(url, payloads(args.warmup, args.seed + 1), args.concurrency))
        cpu0 = server_cpu(proc)
        closed = asyncio.run(run_load(url, payloads(args.requests, args.seed), args.concurrency))
        if cpu0 is not None:  # the server process's own CPU (its pool's runs left out)
            closed["server_cpu_ms_per_request"] = \
                1e3 * (server_cpu(proc) - cpu0) / closed["requests"]
        rate = args.rate or 0.5 * closed["throughput_rps"]
        paced = asyncio.run(run_load(url, payloads(args.requests, args.seed + 2),
                                     args.concurrency, rate=rate, seed=args.seed))
        states = validation_states(url, ids)
    finally:
        if proc is not None:
            proc.terminate()
            try:
                proc.wait(timeout=15)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        tmp.cleanup()
    if args.json:
        print(json.dumps({"closed_loop": closed, "paced": paced, "validations": states,
                          "validations_refused": refused}))
    else:
        _print(closed)
        _print(paced)
        print(f"validations queued meanwhile: {states}")
        for why in refused:
            print(f"validation refused: {why}")
    return 1 if closed["errors"] or paced["errors"] else 0


if __name__ == "__main__":
    sys.exit(main())
