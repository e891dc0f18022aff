"""Reliability, round three (issue 40, R3-R10): no request can poison, starve or read the
server.  Quick checks through the ASGI transport (the live-server ones are in
tests/test_api_round3_live.py)."""

from __future__ import annotations

import ast
import os
import sys
import threading
from typing import Any

import pytest
from api_support import ROOT, asgi, fake_full_solver, fake_planner

from api.http import create_app


@pytest.fixture
def anyio_backend() -> str:
    return "asyncio"


@pytest.fixture
def planner(tmp_path):
    with fake_full_solver(delay=0.0) as fake, \
            fake_planner(tmp_path / "c.sqlite", fake, max_pending=4) as p:
        yield p


@pytest.fixture
async def raw(planner):
    async with asgi(create_app(planner=planner, warm=False)) as (_, client):
        yield client


FRONT = {"gel": "ANB", "t_start": 302.0, "t_end": 308.0, "dose_fraction": 0.8,
         "dry_radius_um": 50.0}
RELEASE = {"time_s": [30.0, 60.0, 120.0, 240.0], "released": [0.2, 0.3, 0.4, 0.6],
           "gel": "ANB", "t_start": 300.0, "dry_radius_um": 50.0}


def _locs(r: Any) -> list[list[Any]]:
    return [d["loc"] for d in r.json()["detail"]]


# ----------------------------------------------------------------------------- R3 paths
_OPENED: list[str] = []
_WATCH: dict[str, Any] = {"on": False, "paths": ()}


def _audit(event: str, args: tuple) -> None:  # records opens of the watched paths
    if _WATCH["on"] and event == "open" and args and str(args[0]) in _WATCH["paths"]:
        _OPENED.append(str(args[0]))


sys.addaudithook(_audit)


def _protocol_bodies(path: str) -> dict[str, dict[str, Any]]:
    step = f"Trace from {path}"
    return {
        "/v1/dose-time": {**FRONT, "t_end": None, "protocol": [step]},
        "/v1/schedule": {"gel": "ANB", "t_start": 302.0, "doses": [0.3], "protocol": [step],
                         "dry_radius_um": 50.0},
        "/v1/fit/release": {**RELEASE, "protocol": ["Heat to 308 K at 5 K/min", step]},
    }


@pytest.mark.anyio
async def test_no_route_opens_a_path_a_request_names(raw, tmp_path) -> None:
    """R3: 'Trace from <an existing server file>' (a CSV, a FIFO that would block, a binary
    device) is a 422 naming the step and saying paths are refused, on every route taking a
    protocol; the file is never opened (an audit hook watches the process's opens)."""
    csv = tmp_path / "run.csv"
    csv.write_text("time (s),T (K)\n0,302\n60,308\n")
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    paths = (str(csv), str(fifo), "/dev/zero", "/etc/passwd")
    _WATCH.update(on=True, paths=paths)
    try:
        for path in paths:
            for route, body in _protocol_bodies(path).items():
                r = await raw.post(route, json=body)
                assert r.status_code == 422, (route, path, r.text)
                item = next(d for d in r.json()["detail"] if "trace" in str(d["loc"]))
                idx = body["protocol"].index(f"Trace from {path}")
                assert item["loc"] == ["body", "protocol", idx, "trace"], item
                assert "file paths are refused" in item["valid"], item
                assert "root:" not in r.text and "No such file" not in r.text
    finally:
        _WATCH["on"] = False
    assert _OPENED == []


def test_the_http_layer_parses_protocols_in_one_place_without_files() -> None:
    """R3: in the HTTP layer (api/ but the CLI's commands and the plots), protocols are
    built only by ``api.requests.http_protocol`` (files=False), and nothing opens, reads or
    parses a path: no open(), no CSV/table/trace readers that take paths."""
    readers = {"open", "read_text", "read_bytes", "read_table", "read_sizes_csv",
               "read_release_csv", "swelling_csv", "kinetics_csv", "loadtxt", "genfromtxt"}
    builders = {"Protocol", "parse_step", "parse"}
    found: list[str] = []
    for path in sorted((ROOT / "api").rglob("*.py")):
        rel = path.relative_to(ROOT).as_posix()
        if rel.startswith(("api/commands/", "api/plots/")) or rel == "api/cli.py":
            continue
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if not isinstance(node, ast.Call):
                continue
            f = node.func
            name = f.id if isinstance(f, ast.Name) else f.attr if isinstance(
                f, ast.Attribute) else ""
            if name in readers and rel != "api/routers/page.py":  # the page's own assets
                found.append(f"{rel}:{node.lineno} {name}")
            if name in builders and name != "parse" or (
                    name == "parse" and isinstance(f, ast.Attribute)
                    and getattr(f.value, "id", "") == "Protocol"):
                kw = {k.arg: k.value for k in node.keywords}
                ok = (rel == "api/requests.py" and isinstance(kw.get("files"), ast.Constant)
                      and kw["files"].value is False)
                if not ok:
                    found.append(f"{rel}:{node.lineno} {name}")
    assert found == [], found


def test_the_one_http_parser_refuses_paths_and_takes_data() -> None:
    from api.requests import http_protocol
    from solver.errors import ParameterError

    p = http_protocol(302.0, [{"step": "trace", "csv": "time (s),T (K)\n0,302\n60,308\n"}])
    assert p.steps[0].times_s == (0.0, 60.0)
    with pytest.raises(ParameterError) as e:
        http_protocol(302.0, ["Heat to 305 K at 1 K/min", "Trace from run.csv"])
    assert e.value.field == "protocol[1].trace" and "refused" in e.value.valid


# ----------------------------------------------------------------------------- R10 hosts
@pytest.mark.parametrize("allowed, host, ok", [
    (["localhost", "127.0.0.1", "[::1]"], "localhost:8000", True),
    (["localhost", "127.0.0.1", "[::1]"], "127.0.0.1:51234", True),
    (["localhost", "127.0.0.1", "[::1]"], "[::1]:8000", True),
    (["localhost", "127.0.0.1", "[::1]"], "[::1]", True),
    (["localhost", "127.0.0.1", "[::1]"], "evil.example:8000", False),
    (["localhost", "127.0.0.1", "[::1]"], "localhost.evil.example", False),
    (["localhost", "127.0.0.1", "[::1]"], "", False),
    (["example.org:8443"], "example.org:8443", True),
    (["example.org:8443"], "example.org:8444", False),
    (["example.org:8443"], "example.org", False),
    (["*.example.org"], "api.example.org:80", True),
    (["*.example.org"], "example.org.evil:80", False),
    (["::1"], "[::1]:9", True),
    (["*"], "anything:1", True),
])
def test_host_check(allowed, host, ok) -> None:
    from api.auth import HostCheck

    assert HostCheck(None, allowed).accepts(host) is ok


@pytest.mark.anyio
async def test_allowed_hosts_with_a_port_work_and_others_are_refused(planner) -> None:
    """R10: ``--allowed-hosts test:80`` accepts Host test:80 (Starlette's check refused
    every such entry); another Host is a JSON 400 naming the header."""
    app = create_app(planner=planner, warm=False, allowed_hosts=["test:80", "localhost"])
    async with asgi(app) as (_, raw):
        assert (await raw.get("/health", headers={"Host": "test:80"})).status_code == 200
        assert (await raw.get("/health", headers={"Host": "localhost:1234"})).status_code == 200
        r = await raw.get("/health", headers={"Host": "rebound.example:80"})
        assert r.status_code == 400 and _locs(r) == [["header", "host"]]


def test_a_loopback_server_checks_the_host_by_default(monkeypatch) -> None:
    """R10: ``thermogel serve`` on loopback accepts only localhost, 127.0.0.1 and [::1]
    (any port) unless told otherwise; beyond loopback (with a token) any Host."""
    import argparse

    from api.commands import serve as serve_cmd

    parser = argparse.ArgumentParser()
    serve_cmd.register(parser.add_subparsers())
    for argv, want in ((["serve"], "localhost,127.0.0.1,[::1]"),
                       (["serve", "--host", "::1"], "localhost,127.0.0.1,[::1]"),
                       (["serve", "--allowed-hosts", "a.example:80"], "a.example:80"),
                       (["serve", "--host", "0.0.0.0", "--token", "t"], None)):
        monkeypatch.delenv("THERMOGEL_ALLOWED_HOSTS", raising=False)
        for k in ("THERMOGEL_API_TOKEN", "THERMOGEL_WARMUP"):
            monkeypatch.setenv(k, os.environ.get(k, ""))
        serve_cmd.configure_env(parser.parse_args(argv))
        assert os.environ.get("THERMOGEL_ALLOWED_HOSTS") == want, argv


_ = threading  # used by later sections
