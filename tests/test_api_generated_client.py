"""A client generated from /openapi.json with openapi-python-client calls every route of a
live server (issue 22): typed job results, CSV and SVG bodies, and 404, 413 and 429
answers parsed as the error model.  Skipped, saying why, when the generator is not installed
(the ``test`` extra installs it)."""

from __future__ import annotations

import importlib
import json
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
from api_support import fake_server

from api.http import create_app

GENERATOR = shutil.which("openapi-python-client") or str(
    Path(sys.executable).with_name("openapi-python-client"))


def _generate(tmp: Path) -> object:
    if not Path(GENERATOR).exists():
        pytest.skip("openapi-python-client is not installed (pip install '.[test]')")
    spec = tmp / "spec.json"
    spec.write_text(json.dumps(create_app(warm=False).openapi()))
    config = tmp / "config.json"  # the generator's way to take an SVG body as bytes (CSV,
    # text/csv, is a str without it)
    config.write_text(json.dumps({"content_type_overrides": {
        "image/svg+xml": "application/octet-stream"}}))
    out = subprocess.run([GENERATOR, "generate", "--path", str(spec), "--meta", "none",
                          "--config", str(config),
                          "--output-path", str(tmp / "tgclient")], capture_output=True,
                         text=True, timeout=300)
    assert out.returncode == 0, out.stdout[-2000:] + out.stderr[-2000:]
    sys.path.insert(0, str(tmp))
    return importlib.import_module("tgclient")


def _op(group: str, name: str) -> object:
    return importlib.import_module(f"tgclient.api.{group}.{name}")


def _hold_connections(url: str, n: int) -> list[socket.socket]:
    """``n`` open connections from this address (each sends nothing)."""
    port = int(url.rsplit(":", 1)[1])
    return [socket.create_connection(("127.0.0.1", port)) for _ in range(n)]


def _wait(call: object, name: str, ident: str, group: str = "dosing") -> object:
    deadline = time.monotonic() + 120
    while True:
        r = call(group, name, ident)
        if r.parsed.status in ("done", "failed") or time.monotonic() > deadline:
            return r
        time.sleep(0.2)


def test_a_generated_client_calls_every_route(tmp_path: Path) -> None:
    """Every operation, with typed results (validation report, schedule, fit report, sweep
    rows), the CSV and SVG bodies, and a 404, a 413 and a 429 parsed as the error model."""
    pkg = _generate(tmp_path)
    models = importlib.import_module("tgclient.models")
    with fake_server(tmp_path / "c.sqlite", 0.0, 60.0, "--per-client", "4") as (url, _):
        c = pkg.Client(base_url=url, raise_on_unexpected_status=True, timeout=None)
        called = set()

        def call(group: str, name: str, *args: object, want: tuple[int, ...] = (200,),
                 client: object = c, **kw: object) -> object:
            r = _op(group, name).sync_detailed(*args, client=client, **kw)
            assert r.status_code in want, (name, r.status_code, r.content[:300])
            if r.status_code >= 400:  # every error answer parses as the error model
                assert type(r.parsed).__name__ == "ErrorResponse", (name, r.parsed)
            called.add(name)
            return r

        call("service", "health_health_get")
        call("physics", "gels_v1_gels_get")
        call("physics", "equilibrium_v1_equilibrium_post", body=models.EquilibriumRequest
             .from_dict({"gel": "ANB", "temperature": 305.0}))
        call("physics", "classify_v1_classify_post", body=models.ClassifyRequest.from_dict(
            {"gel": "ANB", "t_start": 302.0, "t_end": 308.0}))
        call("physics", "front_curve_v1_front_curve_post", body=models.FrontCurveRequest
             .from_dict({"gel": "ANB", "t_start": 302.0, "t_end": 308.0}))
        svg = call("physics", "phase_map_v1_phase_map_svg_get")
        assert svg.content.startswith(b"<?xml") or b"<svg" in svg.content[:400]
        call("dosing", "dose_v1_dose_time_post", body=models.DoseTimeRequest.from_dict(
            {"gel": "ANB", "t_start": 302.0, "t_end": 308.0, "dose_fraction": 0.8,
             "dry_radius_um": 50.0}))
        pending = call("dosing", "dose_v1_dose_time_post", want=(200, 202),
                       body=models.DoseTimeRequest.from_dict(
                           {"gel": "ANB", "t_start": 300.0, "t_end": 303.0,
                            "dose_fraction": 0.2, "validate": True}))
        v = _wait(call, "validation_route_v1_validations_validation_id_get",
                  pending.parsed.validation_id)
        assert type(v.parsed).__name__ == "DoseValidationJob" and v.parsed.status == "done"
        assert type(v.parsed.result).__name__ == "ValidationReport"
        assert v.parsed.result.time > 0 and type(v.parsed.result.runs[0]).__name__ == "RunCheck"
        call("dosing", "validation_route_v1_validations_validation_id_get", "nope",
             want=(404,))
        sched = call("dosing", "schedule_route_v1_schedule_post", want=(202,),
                     body=models.ScheduleRequest.from_dict(
                         {"gel": "ANB", "t_start": 302.0, "t_end": 308.0, "doses": [0.3, 0.3],
                          "rests": [0.5], "dry_radius_um": 50.0}))
        assert sched.headers["location"] == sched.parsed.validation_url
        job = _wait(call, "validation_route_v1_validations_validation_id_get",
                    sched.parsed.validation_id)
        assert type(job.parsed).__name__ == "ScheduleJob", job.content[:300]
        assert type(job.parsed.result).__name__ == "ScheduleResponse"
        assert len(job.parsed.result.hold) == 2
        fit = call("fit", "fit_swelling_route_v1_fit_swelling_post", want=(202,),
                   body=models.SwellingFitRequest.from_dict(
                       {"temperature_K": [290, 295, 300, 303, 305, 306, 307, 308, 310],
                        "radius": [2.87, 2.69, 2.44, 2.19, 1.95, 1.13, 1.12, 1.11, 1.10],
                        "fixed": {"omega": 100.0}}))
        assert fit.headers["location"] == fit.parsed.status_url
        done = _wait(call, "fit_job_v1_fit_jobs_job_id_get", fit.parsed.id, "fit")
        assert done.parsed.status == "done", done.content[:300]
        assert type(done.parsed.result).__name__ == "FitReport"
        assert "a0" in done.parsed.result.parameters.to_dict()
        call("fit", "fit_release_route_v1_fit_release_post", want=(202,),
             body=models.ReleaseFitRequest.from_dict(
                 {"time_s": [30, 60, 120, 240, 480], "released": [0.21, 0.3, 0.42, 0.57, 0.74],
                  "gel": "ANB", "t_start": 300.0, "dry_radius_um": 50.0}))
        call("fit", "fit_kinetics_route_v1_fit_kinetics_post", want=(202,),
             body=models.KineticsFitRequest.from_dict(
                 {"time_s": [0, 50, 100, 200, 400, 800],
                  "radius": [115, 100, 90, 75, 62, 56], "gel": "ANB", "t_start": 302.0,
                  "t_end": 308.0, "dry_radius_um": 50.0, "model": "front"}))
        emp = call("fit", "fit_empirical_route_v1_fit_empirical_post", want=(202,),
                   body=models.EmpiricalFitRequest.from_dict(
                       {"time": [5, 10, 20, 30, 60, 120, 240], "time_unit": "min",
                        "released": [22, 33, 48, 58, 75, 90, 98], "released_unit": "percent",
                        "models": ["weibull", "first_order"]}))  # issue 38
        done = _wait(call, "fit_job_v1_fit_jobs_job_id_get", emp.parsed.id, "fit")
        assert type(done.parsed).__name__ == "EmpiricalFitJobResponse", done.content[:300]
        assert done.parsed.result.best in ("weibull", "first_order")
        cmp = call("fit", "compare_route_v1_compare_post", body=models.CompareRequest.from_dict(
            {"reference": {"time": [15, 30, 45, 60], "released": [35, 60, 79, 95],
                           "released_unit": "percent"},
             "test": {"time": [15, 30, 45, 60], "units": [[40, 67, 87, 98], [38, 65, 85, 97]],
                      "released_unit": "percent"}}))
        assert 50 < cmp.parsed.f2 < 100 and cmp.parsed.bootstrap is not None
        sweep = call("design_maps", "sweep_v1_sweep_post", want=(202,),
                     body=models.SweepRequest.from_dict(
                         {"t_start": 302.0, "t_ends": [308.0], "dry_radii_um": [50.0],
                          "doses": [0.3, 0.5]}))
        sid = sweep.parsed.sweep_id
        st = _wait(call, "sweep_status_v1_sweeps_sweep_id_get", sid, "design_maps")
        assert st.parsed.status == "done"
        row = st.parsed.result.rows[1]
        assert type(row).__name__ == "SweepRow" and row.dose_fraction == 0.5 and row.time > 0
        csv = call("design_maps", "sweep_csv_v1_sweeps_sweep_id_table_csv_get", sid)
        assert isinstance(csv.parsed, str) and len(csv.parsed.splitlines()) == 3
        assert csv.headers["content-type"].startswith("text/csv")
        plot = call("design_maps", "sweep_plot_v1_sweeps_sweep_id_plot_svg_get", sid)
        assert b"<svg" in plot.parsed.payload.read()[:2000]
        any_job = call("jobs", "job_route_v1_jobs_job_id_get", sid)  # one poll route
        assert type(any_job.parsed).__name__ == "SweepStatus"
        any_job = call("jobs", "job_route_v1_jobs_job_id_get", fit.parsed.id)
        assert type(any_job.parsed).__name__ == "FitJobResponse"
        call("jobs", "job_route_v1_jobs_job_id_get", "fit-nope", want=(404,))
        dh = call("design", "design_heating_route_v1_design_heating_post", want=(202,),
                  body=models.HeatingDesignRequest.from_dict(
                      {"gel": "ANB", "t_start": 302.0, "fraction": 0.5, "at_seconds": 0.5,
                       "dry_radius_um": 50.0, "full": False}))
        done = _wait(call, "design_job_v1_design_jobs_job_id_get", dh.parsed.id, "design")
        assert done.parsed.status == "done", done.content[:300]
        call("design", "design_experiment_route_v1_design_experiment_post", want=(202,),
             body=models.ExperimentDesignRequest.from_dict(
                 {"gel": "ANB", "t_start": 302.0, "t_end": 308.0, "fraction": 0.8,
                  "dry_radius_um": 50.0, "jumps": [308.0], "n_points": 6}))
        call("sensitivity", "post_sensitivity_v1_sensitivity_post",
             body=models.SensitivityRequest.from_dict(
                 {"gel": "ANB", "t_start": 302.0, "t_end": 308.0, "dose_fraction": 0.5,
                  "vary": [{"name": "dry_radius_um", "low": 20.0, "high": 80.0}],
                  "method": "morris", "samples": 4}))
        # a body over the 1 MiB limit: a 413, parsed as the error model
        big = models.EquilibriumRequest.from_dict({"gel": "x" * (2 << 20),
                                                   "temperature": 305.0})
        r = call("physics", "equilibrium_v1_equilibrium_post", body=big, want=(413,))
        assert r.parsed.detail[0].type_ == "body_too_large"
        # beyond the cap of 4 connections from this address: a 429 with Retry-After
        c.get_httpx_client().close()
        held = _hold_connections(url, 4)
        try:
            with pkg.Client(base_url=url, raise_on_unexpected_status=True) as fresh:
                r = call("service", "health_health_get", client=fresh, want=(429,))
            assert int(r.headers["retry-after"]) >= 1
            assert r.parsed.detail[0].type_ == "too_many_connections"
        finally:
            for sock in held:
                sock.close()
        time.sleep(0.3)
        with pkg.Client(base_url=url, raise_on_unexpected_status=True) as fresh:
            call("service", "health_health_get", client=fresh)  # the cap is per open one
    ops = sum(len(o) for o in create_app(warm=False).openapi()["paths"].values())
    assert len(called) == ops == 24, sorted(called)
