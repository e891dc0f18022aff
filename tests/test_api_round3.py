"""Reliability, round three (issue 40, R3-R10): no request can poison, starve or read the
server.  Quick checks through the ASGI transport (the live-server ones are in
tests/test_api_round3_live.py)."""

from __future__ import annotations

import ast
import os
import sys
from typing import Any

import pytest
from api_support import ROOT, asgi, fake_full_solver, fake_planner

from api.http import create_app


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
        text = path.read_text()
        lines = text.splitlines()
        tree = ast.parse(text)
        for node in ast.walk(tree):
            if not isinstance(node, ast.Call):
                continue
            f = node.func
            name = f.id if isinstance(f, ast.Name) else f.attr if isinstance(
                f, ast.Attribute) else ""
            line = lines[node.lineno - 1].lower()
            own_asset = "static" in line or "_asset(" in line  # the package's own pages
            if name in readers and not own_asset:
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



# ----------------------------------------------------------------------------- R6 inputs
def _trace(**kw: Any) -> dict[str, Any]:
    return {**FRONT, "t_end": None, "protocol": [{"step": "trace", **kw}]}


def _sens(vary: dict[str, Any], **kw: Any) -> dict[str, Any]:
    return {"gel": "ANB", "vary": [vary], "samples": 4, "method": "morris", **kw}


def _batch(sd: dict[str, Any]) -> dict[str, Any]:
    return {**FRONT, "dry_radius_um": None, "size_distribution": sd}


TWO = "0,302\n60,308\n"
# the 16 inputs that were a 500 (issue 40, R6), reconstructed from their descriptions
SIXTEEN: list[tuple[str, str, dict[str, Any], list[Any]]] = [
    ("huge CSV field", "/v1/dose-time",
     _trace(csv="time,T\n0," + "1" * 200_000 + "\n60,308\n"), ["body", "protocol", 0]),
    ("CSV field over csv's limit, quoted", "/v1/dose-time",
     _trace(csv='time,T\n0,"' + "1" * 140_000 + '"\n60,308\n'), ["body", "protocol", 0]),
    ("time_unit 5 (CSV)", "/v1/dose-time", _trace(csv=TWO, time_unit=5),
     ["body", "protocol", 0]),
    ("temperature_unit 5 (CSV)", "/v1/dose-time", _trace(csv=TWO, temperature_unit=5),
     ["body", "protocol", 0]),
    ("time_unit 5 (lists)", "/v1/dose-time",
     _trace(time=[0, 60], temperature=[302, 308], time_unit=5), ["body", "protocol", 0]),
    ("temperature_unit [1] (lists)", "/v1/dose-time",
     _trace(time=[0, 60], temperature=[302, 308], temperature_unit=[1]),
     ["body", "protocol", 0]),
    ("log radius 1e-300..1e300", "/v1/sensitivity",
     _sens({"name": "dry_radius_um", "low": 1e-300, "high": 1e300, "log": True}),
     ["body", "vary"]),
    ("log permeability 1e-300..1e300", "/v1/sensitivity",
     _sens({"name": "permeability_m2", "low": 1e-300, "high": 1e300, "log": True}),
     ["body", "vary"]),
    ("t_end 0..1e308", "/v1/sensitivity", _sens({"name": "t_end", "low": 0, "high": 1e308}),
     ["body", "vary"]),
    ("base radius '1e308 um'", "/v1/sensitivity",
     _sens({"name": "a0", "low": 0.1, "high": 0.2}, dry_radius_um="1e308 um"),
     ["body", "dry_radius_um"]),
    ("lognormal mean 5e-324", "/v1/dose-time",
     _batch({"kind": "lognormal", "mean_um": 5e-324, "cv": 0.2}),
     ["body", "size_distribution", "mean_um"]),
    ("normal mean 5e-324", "/v1/dose-time",
     _batch({"kind": "normal", "mean_um": 5e-324, "cv": 0.2}),
     ["body", "size_distribution", "mean_um"]),
    ("lognormal median 5e-324", "/v1/dose-time",
     _batch({"kind": "lognormal", "median_um": 5e-324, "gsd": 2.0}),
     ["body", "size_distribution", "median_um"]),
    ("table size 5e-324", "/v1/dose-time",
     _batch({"kind": "table", "sizes_um": [5e-324, 1.0]}),
     ["body", "size_distribution", "sizes_um", 0]),
    ("table size 1e308", "/v1/dose-time",
     _batch({"kind": "table", "sizes_um": [1e308, 1.0]}),
     ["body", "size_distribution", "sizes_um", 0]),
    ("a binary file through R3", "/v1/dose-time",
     {**FRONT, "t_end": None, "protocol": ["Trace from /bin/sh"]}, ["body", "protocol", 0]),
]


@pytest.mark.anyio
@pytest.mark.parametrize("what, route, body, loc", SIXTEEN, ids=[c[0] for c in SIXTEEN])
async def test_the_sixteen_inputs_are_4xx_naming_the_field(raw, what, route, body, loc):
    """R6: each of the 16 inputs that gave a 500 is a 422 whose loc names the field."""
    r = await raw.post(route, json=body)
    assert r.status_code == 422, (what, r.text[:400])
    assert any(got[:len(loc)] == loc for got in _locs(r)), (what, _locs(r))


@pytest.mark.anyio
async def test_a_cr_only_trace_is_read(raw) -> None:
    """R6: a trace CSV with CR-only line ends (an old spreadsheet's) is read, not a 500."""
    r = await raw.post("/v1/dose-time", json=_trace(csv="time,T\r0,302\r60,308\r"))
    assert r.status_code in (200, 202), r.text


# ----------------------------------------------------------------------------- R8 units
@pytest.mark.anyio
@pytest.mark.parametrize("step, field", [
    ("Heat to 308 K at 500 percent", "rate"),
    ("Hold at 308 K for 10 radian", "for"),
    ("Bath at 308 K with a time constant of 5 percent", "time_constant"),
    ("Hold at 308 K until radius 5 percent", "until"),
    ("Hold at 308 K until 5 radian released", "until"),
    ("Heat to 308 K at 1e-300 K/tau", "rate"),
    ("Heat to 308 K at 1e300 K/tau", "rate"),
    ("Heat to 308 K at 1e-9 K/tau", "rate"),
    ("Hold at 308 K for 1e6 tau", "for"),  # 2.2e7 s at tau = 22 s (50 um ANB)
])
async def test_bounds_hold_after_unit_conversion(raw, step, field) -> None:
    """R8: a dimensionless unit inside a step ('500 percent', '10 radian') is refused, and a
    rate or duration per tau is bounded by its physical value once tau is known (a rate in
    K/tau was unbounded below: an answer of 7e303 s)."""
    r = await raw.post("/v1/dose-time", json={**FRONT, "t_end": None, "protocol": [step]})
    assert r.status_code == 422, r.text
    assert any(loc[:3] == ["body", "protocol", 0] and (len(loc) < 4 or loc[3] == field)
               for loc in _locs(r)), _locs(r)


@pytest.mark.anyio
async def test_a_batch_mean_below_the_minimum_size_is_refused(raw) -> None:
    """R8: a batch whose mean (after conversion) is below 1e-3 um was answered 0 s."""
    for sd in ({"kind": "normal", "mean_um": 5e-4, "cv": 0.2},
               {"kind": "lognormal", "mean_um": "0.5 nm", "cv": 0.2},
               {"kind": "lognormal", "mean_um": 0.002, "cv": 0.2, "state": "swollen"}):
        r = await raw.post("/v1/dose-time", json=_batch(sd))
        assert r.status_code == 422, (sd, r.text)
        assert all(loc[:2] == ["body", "size_distribution"] or loc == ["body"]
                   for loc in _locs(r)), _locs(r)  # never a size field the request lacks


def test_dimensionless_units_are_refused_for_physical_fields() -> None:
    from dosing.quantity import to_unit
    from solver.errors import ParameterError

    assert to_unit("308", "temperature", "t") == 308.0  # a bare number: the field's unit
    for text, kind in (("500 percent", "temperature_rate"), ("10 radian", "time"),
                       ("5 %", "length")):
        with pytest.raises(ParameterError):
            to_unit(text, kind, "f")


# ----------------------------------------------------------------------------- R9 fits
@pytest.mark.anyio
@pytest.mark.parametrize("route, body, loc", [
    ("/v1/fit/release", {**RELEASE, "time_s": [], "released": []}, ["body", "time_s"]),
    ("/v1/fit/release", {**RELEASE, "time_s": [1.0, 2.0], "released": [0.1, 0.2]},
     ["body", "time_s"]),
    ("/v1/fit/release", {**RELEASE, "dry_radius_um": 5e-324}, ["body", "dry_radius_um"]),
    ("/v1/fit/release", {**RELEASE, "dry_radius_um": 1e308}, ["body", "dry_radius_um"]),
    ("/v1/fit/kinetics", {"time_s": [], "radius": [], "gel": "ANB", "t_start": 302.0,
                          "t_end": 308.0}, ["body", "time_s"]),
    ("/v1/fit/kinetics", {"time_s": [0.0], "radius": [1.0], "gel": "ANB", "t_start": 302.0,
                          "t_end": 308.0}, ["body", "time_s"]),
])
async def test_fit_inputs_are_refused_at_submission(raw, route, body, loc) -> None:
    """R9: inputs a fit job would refuse are a 422 at submission, not a 202 then a failed
    job."""
    r = await raw.post(route, json=body)
    assert r.status_code == 422, r.text
    assert loc in _locs(r), _locs(r)


def test_job_errors_are_in_plain_words() -> None:
    """R9: a failed job's error names the field in words, never a Python class name."""
    from api.stored_jobs import plain_error
    from solver.errors import ParameterError, SolverError

    msgs = [plain_error(ParameterError("time_s", "2 points", "at least 3 points")),
            plain_error(SolverError("step size underflow")),
            plain_error(ValueError("x and y arrays must be equal in length")),
            plain_error(KeyError("gel"))]
    assert "time_s" in msgs[0] and "at least 3 points" in msgs[0]
    for m in msgs:
        assert not any(name in m for name in ("Error:", "KeyError", "ValueError",
                                              "ParameterError", "Traceback")), m


# ----------------------------------------------------------------------------- R10 locs
def test_error_locations_name_fields_the_request_has() -> None:
    """R10: an error found deep in the planner (a solver's 'targets', a fit's 'data') points
    at the body or the deepest field the request has, never at one it lacks."""
    from api import schemas as s
    from api.errors import known_loc
    from api.sensitivity_schemas import SensitivityRequest

    body = ["body"]
    assert known_loc([*body, "targets"], s.DoseTimeRequest) == body
    assert known_loc([*body, "dose_fraction"], s.DoseTimeRequest) == [*body, "dose_fraction"]
    assert known_loc([*body, "size_distribution", "mean_um"], s.DoseTimeRequest) == \
        [*body, "size_distribution", "mean_um"]
    assert known_loc([*body, "size_distribution", "bogus"], s.DoseTimeRequest) == \
        [*body, "size_distribution"]
    assert known_loc([*body, "protocol", 2, "rate"], s.DoseTimeRequest) == \
        [*body, "protocol", 2, "rate"]
    assert known_loc([*body, "vary", "a0"], SensitivityRequest) == [*body, "vary"]
    assert known_loc([*body, "validate"], s.DoseTimeRequest) == [*body, "validate"]


@pytest.mark.anyio
async def test_health_is_degraded_on_a_malformed_cache(planner, raw, monkeypatch) -> None:
    """R10: /health says 'degraded' once a request met a malformed cache (it said 'ok'
    while the log said otherwise)."""
    import sqlite3

    def malformed(*args: object, **kwargs: object) -> None:
        raise sqlite3.DatabaseError("database disk image is malformed")

    assert (await raw.get("/health")).json()["status"] == "ok"
    monkeypatch.setattr(planner.cache, "get_many", malformed, raising=False)
    monkeypatch.setattr(planner.cache, "get", malformed)
    r = await raw.post("/v1/dose-time", json={**FRONT, "t_start": 300.0, "t_end": 303.0,
                                              "dose_fraction": 0.2})
    assert r.status_code == 503, r.text
    h = (await raw.get("/health")).json()
    assert h["status"] == "degraded" and "malformed" in h["planner"]["degraded_because"]


@pytest.mark.anyio
async def test_health_is_degraded_on_a_cache_failure_logged_off_the_requests(raw) -> None:
    """R10: a malformed cache met off the requests (a job thread, a validation) and logged
    makes /health 'degraded' too."""
    import logging
    import sqlite3

    assert (await raw.get("/health")).json()["status"] == "ok"
    try:
        raise sqlite3.DatabaseError("database disk image is malformed")
    except sqlite3.Error:
        logging.getLogger("thermogel.cache").exception("a job met the cache")
    h = (await raw.get("/health")).json()
    assert h["status"] == "degraded" and "malformed" in h["planner"]["degraded_because"]


def test_a_release_fit_the_data_do_not_pin_has_a_finite_interval() -> None:
    """Found by the fuzz: a release curve D0 does not move (a flat model) made the fit's
    interval exp(q + t sd) overflow (a job failing on an OverflowError); it is D0's whole
    range instead, with a warning."""
    import numpy as np

    from dosing.fits.release import D_BOUNDS, _fit_log_d0

    t = np.array([30.0, 60.0, 120.0])
    y = np.array([0.2, 0.3, 0.4])
    rep = _fit_log_d0(t, y, lambda d0, tt: np.full(np.shape(tt), 0.3), 1e-7)
    lo, hi = rep["intervals"]["drug_diffusivity_cm2_s"]
    assert D_BOUNDS[0] <= lo <= hi <= D_BOUNDS[1] * (1 + 1e-9)
    assert np.isfinite(rep["stderr"]["drug_diffusivity_cm2_s"])
    assert any("do not pin" in w for w in rep["warnings"])


@pytest.mark.anyio
async def test_a_solver_field_is_not_a_request_location(raw) -> None:
    """R10 over HTTP: a batch whose smallest sizes make a solver bound fail (the program's
    'steps[0].rate' in K per tau) points at the body, not at 'steps' the request lacks."""
    r = await raw.post("/v1/dose-time", json={
        "gel": "ANB", "t_start": 302.0, "dry_radius_um": 50.0, "dose_fraction": 0.9,
        "protocol": ["Heat to 308 K at 5 K/min"], "size_distribution": {"cv": 2.0}})
    assert r.status_code in (202, 422), r.text
    if r.status_code == 422:
        from api import schemas as s

        fields = set(s.DoseTimeRequest.model_fields) | {"validate"}
        assert all(len(loc) == 1 or loc[1] in fields for loc in _locs(r)), _locs(r)


def test_validation_run_errors_are_in_plain_words() -> None:
    """R9: a validation's failed run says why without a Python class name."""
    from dosing.validation import run_failure
    from solver.errors import SolverError

    for exc in (SolverError("step size underflow"), OSError("worker lost"), RuntimeError(""),
                None):
        msg = run_failure(exc)
        assert msg and not any(n in msg for n in ("SolverError", "OSError", "RuntimeError",
                                                  "Error:")), msg
