"""Service hardening, round two (issue 22), against live servers on loopback ports.

The acceptance lines that tests/test_api_hardening2.py checks in-process, again over real
sockets: a 10 MB body (413 as JSON), a 100 kB unknown key (a short 422),
``mesh_length_range_nm`` accepted, a tiny validated dose; a full disk (SQLite's
SQLITE_FULL) as a 503 naming the cache with /health degraded; the read deadline and the
per-client connection cap (:mod:`api.connections`); the token and the allowed hosts of a
real ``thermogel serve``, and its refusal to bind beyond loopback without a token.
"""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx
import pytest
from api_support import ROOT, fake_server, free_port, serve

FRONT = {"gel": "ANB", "t_start": 302.0, "t_end": 308.0, "dose_fraction": 0.8,
         "dry_radius_um": 50.0}
SMOOTH = {"gel": "ANB", "t_start": 300.0, "t_end": 303.0, "dose_fraction": 0.2}
EQUILIBRIUM = {"gel": "ANB", "temperature": 305.0}


def _wait_done(c: httpx.Client, url: str, timeout: float = 60.0) -> dict:
    deadline = time.monotonic() + timeout
    while True:
        got = c.get(url).json()
        if got["status"] in ("done", "failed") or time.monotonic() > deadline:
            return got
        time.sleep(0.1)


def test_the_acceptance_requests_on_a_live_server(tmp_path: Path) -> None:
    """On one keep-alive connection: a 10 MB body is a 413 as JSON; a 100 kB unknown key a
    422 under 5 kB; mesh_length_range_nm [2, 8] is accepted; a validated dose of 1e-15 is
    answered before and after its validation, and the same request with 0.5 then too."""
    with fake_server(tmp_path / "c.sqlite", 0.0) as (url, _), \
            httpx.Client(base_url=url, timeout=60) as c:
        big = json.dumps({**FRONT, "pad": "x" * 10_000_000}).encode()
        r = c.post("/v1/dose-time", content=big, headers={"content-type": "application/json"})
        assert r.status_code == 413 and r.headers["content-type"] == "application/json"
        assert r.json()["detail"][0]["type"] == "body_too_large"

        r = c.post("/v1/dose-time", json={**FRONT, "k" * 100_000: 1})
        assert r.status_code == 422 and len(r.content) < 5_000, len(r.content)

        r = c.post("/v1/dose-time", json={**FRONT, "constants": {
            "mesh_length_nm": 4.0, "mesh_length_range_nm": [2, 8]}})
        assert r.status_code == 200, r.text

        tiny = {**FRONT, "dose_fraction": 1e-15, "validate": True}
        for _ in range(2):  # the second time, its validation is done and cached
            r = c.post("/v1/dose-time", json=tiny)
            assert r.status_code == 200, r.text
            assert r.json()["time"] >= 0.0
            assert _wait_done(c, r.json()["validation_url"])["status"] == "done"
        r = c.post("/v1/dose-time", json={**tiny, "dose_fraction": 0.5})
        assert r.status_code == 200, r.text
        assert c.get("/health").json()["status"] == "ok"


def test_a_full_disk_is_503_naming_the_cache_on_a_live_server(tmp_path: Path) -> None:
    """The cache file may not grow (SQLite's max_page_count, as on a full disk): the
    validations' runs fail saying so, a request whose write fails is a 503 naming the cache
    with Retry-After, and /health says degraded and why."""
    with fake_server(tmp_path / "c.sqlite", 0.0, 60.0, "--full-disk") as (url, _), \
            httpx.Client(base_url=url, timeout=60) as c:
        assert c.get("/health").json()["status"] == "ok"
        answers = []
        for i in range(6):  # the first records fit in pages the file has; then it is full
            r = c.post("/v1/dose-time", json={**SMOOTH, "validate": True,
                                              "t_start": 300.0 + 0.1 * i})
            answers.append(r)
            if r.status_code == 503:
                break
            assert r.status_code == 202, r.text
            failed = _wait_done(c, r.json()["validation_url"])
            assert failed["status"] == "failed" and "disk is full" in failed["error"], failed
        assert answers[-1].status_code == 503, [a.status_code for a in answers]
        item = answers[-1].json()["detail"][0]
        assert item["type"] == "cache_unavailable" and item["loc"] == ["cache"]
        assert "validation cache" in item["msg"] and "disk is full" in item["msg"]
        assert int(answers[-1].headers["retry-after"]) >= 1
        health = c.get("/health").json()
        assert health["status"] == "degraded"
        assert "disk is full" in health["planner"]["degraded_because"]


def _read_all(sock: socket.socket) -> bytes:
    data = b""
    while chunk := sock.recv(65536):
        data += chunk
    return data


def test_slow_clients_are_cut_off_and_connections_per_client_capped(tmp_path: Path) -> None:
    """thermogel serve --read-timeout 1 --max-connections-per-client 3: a body sent too
    slowly, and a connection that sends nothing, get a 408 as JSON and are closed about 1 s
    later, while /health answers at once; a fourth connection from this address is a 429
    as JSON with Retry-After, and once connections close, requests are served again."""
    with serve(tmp_path / "c.sqlite", "--no-warmup", "--read-timeout", "1",
               "--max-connections-per-client", "3") as url:
        port = int(url.rsplit(":", 1)[1])
        slow = socket.create_connection(("127.0.0.1", port), timeout=10)
        silent = socket.create_connection(("127.0.0.1", port), timeout=10)
        t0 = time.monotonic()
        slow.sendall(b"POST /v1/equilibrium HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                     b"Content-Type: application/json\r\nContent-Length: 100\r\n\r\n{\"gel\"")
        with httpx.Client(base_url=url, timeout=10) as c:  # the third connection
            h0 = time.monotonic()
            assert c.get("/health").status_code == 200
            assert time.monotonic() - h0 < 0.5
        for sock in (slow, silent):
            answer = _read_all(sock)
            waited = time.monotonic() - t0
            assert 0.8 < waited < 5.0, waited
            head, _, body = answer.partition(b"\r\n\r\n")
            assert head.startswith(b"HTTP/1.1 408") and b"application/json" in head, head
            assert json.loads(body)["detail"][0]["type"] == "request_timeout"
            sock.close()

        held = [socket.create_connection(("127.0.0.1", port)) for _ in range(3)]
        try:
            time.sleep(0.1)
            r = httpx.get(f"{url}/health", timeout=10)
            assert r.status_code == 429 and int(r.headers["retry-after"]) >= 1
            assert r.json()["detail"][0]["type"] == "too_many_connections"
        finally:
            for sock in held:
                sock.close()
        time.sleep(0.3)
        assert httpx.get(f"{url}/health", timeout=10).status_code == 200


def test_token_and_allowed_hosts_on_a_live_server(tmp_path: Path) -> None:
    """thermogel serve --token --allowed-hosts: /health stays open; without the token, or
    with a wrong one, a 401 as JSON; with it, answered; a Host outside the list is a 400 as
    JSON naming the host header."""
    with serve(tmp_path / "c.sqlite", "--no-warmup", "--token", "s3cret",
               "--allowed-hosts", "127.0.0.1,localhost") as url, \
            httpx.Client(base_url=url, timeout=120) as c:
        assert c.get("/health").status_code == 200
        for headers in ({}, {"Authorization": "Bearer wrong"}):
            r = c.post("/v1/equilibrium", json=EQUILIBRIUM, headers=headers)
            assert r.status_code == 401 and r.headers["www-authenticate"] == "Bearer"
            assert r.json()["detail"][0]["type"] == "unauthorized"
        ok = {"Authorization": "Bearer s3cret"}
        assert c.get("/v1/gels", headers=ok).status_code == 200
        r = c.get("/v1/gels", headers={**ok, "Host": "evil.example"})
        assert r.status_code == 400 and r.headers["content-type"] == "application/json"
        assert r.json()["detail"][0]["loc"] == ["header", "host"], r.text


def test_serve_beyond_loopback_without_a_token_refuses_to_start() -> None:
    """thermogel serve --host 0.0.0.0 with no token exits 2 at once, saying why, and never
    listens."""
    port = free_port()
    env = {k: v for k, v in os.environ.items() if k != "THERMOGEL_API_TOKEN"}
    out = subprocess.run([sys.executable, "-m", "api.cli", "serve", "--host", "0.0.0.0",
                          "--port", str(port)], cwd=ROOT, env=env, capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 2, out.stderr
    assert "--token" in out.stderr and "THERMOGEL_API_TOKEN" in out.stderr
    assert "beyond this machine" in out.stderr
    with pytest.raises(httpx.TransportError):
        httpx.get(f"http://127.0.0.1:{port}/health", timeout=2)


def test_a_corrupted_row_is_recomputed_on_a_live_server(tmp_path: Path) -> None:
    """A validated dose's runs are cached; with the server stopped, bytes of one stored
    trajectory are flipped; the restarted server detects it (checksum), computes that run
    again (202, then done) and answers the same time as before."""
    import sqlite3

    cache, log = tmp_path / "c.sqlite", tmp_path / "calls.log"
    body = {**SMOOTH, "validation_method": "direct"}
    with fake_server(cache, 0.0, 60.0, "--calls", str(log)) as (url, _), \
            httpx.Client(base_url=url, timeout=60) as c:
        r = c.post("/v1/dose-time", json=body)
        assert r.status_code == 202, r.text
        assert _wait_done(c, r.json()["validation_url"])["status"] == "done"
        first = c.post("/v1/dose-time", json=body).json()
        assert first["model"] == "full"
    runs = len(log.read_text().splitlines())
    with sqlite3.connect(cache) as con:
        key, blob = con.execute("SELECT key, data FROM trajectories LIMIT 1").fetchone()
        bad = bytearray(blob)
        bad[len(bad) // 2] ^= 0xFF
        con.execute("UPDATE trajectories SET data = ? WHERE key = ?", (bytes(bad), key))
    with fake_server(cache, 0.0, 60.0, "--calls", str(log)) as (url, _), \
            httpx.Client(base_url=url, timeout=60) as c:
        r = c.post("/v1/dose-time", json=body)
        if r.status_code == 202:
            assert _wait_done(c, r.json()["validation_url"])["status"] == "done"
            r = c.post("/v1/dose-time", json=body)
        assert r.status_code == 200, r.text
        again = r.json()
    assert len(log.read_text().splitlines()) > runs  # the damaged run was computed again
    assert again["model"] == "full" and again["time"] == first["time"]
