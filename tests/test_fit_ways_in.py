"""`thermogel fit swelling|kinetics` and POST /v1/fit/* (issue 14)."""

from __future__ import annotations

import asyncio
import json
import time

import httpx
import numpy as np
import pytest

from api.cli import main
from api.http import create_app
from dosing.fits.gel import front_radius_model
from dosing.units import timescale
from solver.fit.synthetic import synthetic_swelling
from solver.gel import HHT

REPORT_KEYS = {"parameters", "intervals", "rms_orthogonal_K", "warnings", "transitions",
               "correlation", "covariance", "success"}


@pytest.fixture
def env(tmp_path, monkeypatch):
    monkeypatch.setenv("THERMOGEL_GELS", str(tmp_path / "gels"))
    monkeypatch.setenv("THERMOGEL_CACHE", str(tmp_path / "v.sqlite"))
    return tmp_path


def _swelling_csv(path, seed: int = 3):
    d = synthetic_swelling(HHT, scale=41.27, seed=seed)
    path.write_text("temperature_K,radius\n" + "".join(
        f"{t:.4f},{y:.5f}\n" for t, y in zip(d.temperature, d.size, strict=True)))
    return path


def _kinetics_csv(path):
    curve = front_radius_model(HHT, 300.0, 310.0, "swollen")(None)
    tau = timescale(40.0, 310.0, omega=HHT.omega).seconds
    td = np.linspace(0.0, 0.02, 30)
    y = 40.0 * curve(td) * (1 + 0.01 * np.random.default_rng(0).standard_normal(td.size))
    path.write_text("time_s,radius\n" + "".join(
        f"{t * tau:.5f},{v:.5f}\n" for t, v in zip(td, y, strict=True)))
    return path, tau


def test_cli_fit_save_and_dose_by_name(env, capsys) -> None:
    csv = _swelling_csv(env / "s.csv")
    png = env / "fit.png"
    assert main(["fit", "swelling", str(csv), "--json", "--save", "beads1",
                 "--plot", str(png)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert REPORT_KEYS <= set(out)
    assert set(out["parameters"]) == {"omega", "a0", "b0", "a1", "b1", "scale"}
    assert png.stat().st_size > 10_000 and (env / "fit_phase_map.png").exists()
    assert (env / "gels" / "beads1.json").exists()
    kcsv, tau = _kinetics_csv(env / "k.csv")
    assert main(["fit", "kinetics", str(kcsv), "--gel", "beads1", "--t-start", "300",
                 "--t-end", "310", "--dry-radius-um", "40", "--json", "--save",
                 "beads1"]) == 0
    kin = json.loads(capsys.readouterr().out)
    assert kin["model"] == "front-sharp" and kin["intervals"]["tau"][0] > 0
    rec = json.loads((env / "gels" / "beads1.json").read_text())
    assert rec["swelling"] and rec["kinetics"]  # the kinetics fit kept the swelling one
    assert main(["dose", "--gel", "beads1", "--t-start", "300", "--t-end", "310",
                 "--fraction", "0.5", "--dry-radius-um", "40", "--json"]) == 0
    dose = json.loads(capsys.readouterr().out)
    assert dose["parameter_interval"]["time"][0] < dose["time"]
    assert main(["equilibrium", "--gel", "beads1", "--temperature", "305"]) == 0
    assert "beads1 at 305 K" in capsys.readouterr().out


def test_cli_bad_csv_is_exit_2_naming_the_column(env, capsys) -> None:
    bad = env / "b.csv"
    bad.write_text("heat,radius\n300,1\n")
    assert main(["fit", "swelling", str(bad)]) == 2
    assert "line 1, column 1" in (err := capsys.readouterr().err)
    assert "unknown column name(s) 'heat'" in err
    assert main(["dose", "--gel", "nosuch", "--t-start", "300", "--t-end", "310",
                 "--fraction", "0.5"]) == 2
    assert "stored fitted gel" in capsys.readouterr().err



@pytest.mark.anyio
async def test_http_fit_is_a_job(env) -> None:
    d = synthetic_swelling(HHT, scale=0.4127, seed=3)
    body = {"temperature_K": d.temperature.tolist(), "radius": d.size.tolist(),
            "save": "webgel"}
    app = create_app(warm=False, cache_path=str(env / "v.sqlite"))
    async with app.router.lifespan_context(app):
        transport = httpx.ASGITransport(app=app)
        async with httpx.AsyncClient(base_url="http://t", transport=transport) as c:
            r = await c.post("/v1/fit/swelling", json=body)
            assert r.status_code == 202
            url = r.headers["location"]
            deadline = time.monotonic() + 60
            while (j := (await c.get(url)).json())["status"] not in ("done", "failed"):
                assert time.monotonic() < deadline
                await asyncio.sleep(0.1)
            assert j["status"] == "done", j
            assert REPORT_KEYS <= set(j["result"])
            r = await c.post("/v1/fit/swelling", json={**body, "radius": [-1.0] * 30})
            assert r.status_code == 422 and "sizes > 0" in r.text
            r = await c.post("/v1/fit/swelling", json={**body, "radios": body["radius"]})
            assert r.status_code == 422 and "radios" in r.text
            r = await c.post("/v1/fit/swelling", json={**body, "temperature_K": [300.0] * 3,
                                                       "radius": [1.0] * 3})
            assert r.status_code == 422 and "points" in r.text
            assert (await c.get("/v1/fit/jobs/swelling-nope")).status_code == 404
            kin = {"time_s": [0, 100, 200, 400, 800, 1600, 3200, 6400],
                   "radius": [100, 95, 90, 80, 70, 60, 55, 55], "gel": "webgel",
                   "t_start": 300.0, "t_end": 310.0}
            r = await c.post("/v1/fit/kinetics", json=kin)
            assert r.status_code == 202
            r = await c.post("/v1/fit/kinetics", json={**kin, "gel": "nosuch"})
            assert r.status_code == 422 and "webgel" in r.text
    # the finished job is in the cache: a new server (a restart) answers it without refitting
    app2 = create_app(warm=False, cache_path=str(env / "v.sqlite"))
    async with app2.router.lifespan_context(app2):
        transport = httpx.ASGITransport(app=app2)
        async with httpx.AsyncClient(base_url="http://t", transport=transport) as c:
            again = (await c.get(url)).json()
            assert again["status"] == "done" and again["kind"] == "swelling"
            assert again["result"]["parameters"] == j["result"]["parameters"]


@pytest.mark.anyio
async def test_release_fit_same_numbers_every_way_in(env, capsys) -> None:
    """A release curve under a ramp (tests/test_fit_release.py) through Python, the CLI and
    POST /v1/fit/release (a stored job: 202 + Location, polled at /v1/jobs/{id}): the same
    D0, interval and f2; the job's result is typed in the OpenAPI document."""
    from dosing.fits.release import fit_release
    from tests.test_fit_release import COARSE, RAMP, ramp_curve

    t, y = ramp_curve(seed=5)
    py = fit_release(t, y, "ANB", 300.0, None, 50.0, protocol=RAMP, settings=COARSE)
    csv = env / "rel.csv"
    csv.write_text("time_s;released (%)\n" + "".join(
        f"{float(a)!r};{float(100 * b)!r}\n" for a, b in zip(t, y, strict=True)))
    assert main(["fit", "release", str(csv), "--gel", "ANB", "--t-start", "300", "--protocol",
                 RAMP, "--dry-radius-um", "50", "--n", "100", "--rtol", "1e-4", "--json"]) == 0
    cli = json.loads(capsys.readouterr().out)
    body = {"time_s": t.tolist(), "released": (100 * y).tolist(), "released_unit": "percent",
            "gel": "ANB", "t_start": 300.0, "protocol": [RAMP], "dry_radius_um": 50.0,
            "solver_n": 100, "solver_rtol": 1e-4}
    app = create_app(warm=False, cache_path=str(env / "v.sqlite"))
    async with app.router.lifespan_context(app):
        transport = httpx.ASGITransport(app=app)
        async with httpx.AsyncClient(base_url="http://t", transport=transport) as c:
            r = await c.post("/v1/fit/release", json=body)
            assert r.status_code == 202 and r.json()["kind"] == "release"
            url = "/v1/jobs/" + r.json()["id"]
            assert r.headers["location"] == r.json()["status_url"]
            deadline = time.monotonic() + 120
            while (j := (await c.get(url)).json())["status"] not in ("done", "failed"):
                assert time.monotonic() < deadline
                await asyncio.sleep(0.1)
            assert j["status"] == "done", j
            assert (await c.get(r.headers["location"])).json()["result"] == j["result"]
            bad = await c.post("/v1/fit/release", json={**body, "released": [1.0, 2.0]})
            assert bad.status_code == 422 and "released" in bad.text
            bad = await c.post("/v1/fit/release", json={**body, "t_end": 308.0})
            assert bad.status_code == 422 and "t_end" in bad.text
            bad = await c.post("/v1/fit/release", json={**body, "protocol": ["Heat to 2 K"]})
            assert bad.status_code == 422 and "protocol" in bad.text
            schema = (await c.get("/openapi.json")).json()["components"]["schemas"]
            assert "f2" in schema["ReleaseFitReport"]["properties"]
    http = j["result"]
    for rep in (cli, http):
        assert rep["parameters"]["drug_diffusivity_cm2_s"] == pytest.approx(
            py["parameters"]["drug_diffusivity_cm2_s"], rel=1e-9)
        assert rep["intervals"]["drug_diffusivity_cm2_s"] == pytest.approx(
            py["intervals"]["drug_diffusivity_cm2_s"], rel=1e-9)
        assert rep["f2"] == pytest.approx(py["f2"], rel=1e-9)
