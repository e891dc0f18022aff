"""thermogel design experiment (issue 39): the measurement that pins an answer's dominant
parts, its predicted envelope, the two front laws' separation, and the design jobs over
HTTP."""

from __future__ import annotations

import asyncio
import json
import threading
import time
from concurrent.futures import ThreadPoolExecutor

import httpx
import numpy as np
import pytest

from api.cli import main
from dosing import Planner
from dosing.design import ExperimentAsk, design_experiment
from dosing.design.experiment import greedy_times, jump_curves, tau_sd
from dosing.fits.gel import fit_front_laws, kinetics_data
from solver.errors import ParameterError
from solver.gel import HHT

NOISE = 0.01


@pytest.fixture(scope="module")
def planner(tmp_path_factory):
    path = tmp_path_factory.mktemp("exp") / "c.sqlite"
    p = Planner(cache_path=str(path), executor=ThreadPoolExecutor(1))
    p.path = str(path)
    yield p
    p.close()
    p.jobs.executor.shutdown(wait=True)


def test_fisher_interval_matches_simulated_fits() -> None:
    """The Fisher information's sd of log tau against 200 simulated least-squares fits of
    the same curve (the two agree within 15 %), and greedy times beat even spacing."""
    from scipy.optimize import least_squares

    def curve(s):
        return 1.0 + np.exp(-np.asarray(s) / 0.1)

    tau = 100.0
    times = greedy_times(curve, np.array([tau]), NOISE, 12, 2000.0, 1.0, "d-optimal")
    sd = tau_sd(curve, times, tau, NOISE)
    even = np.linspace(0.0, 2000.0, 12)
    assert sd < tau_sd(curve, even, tau, NOISE)
    rng = np.random.default_rng(1)
    y0 = curve(times / tau)
    est = []
    for _ in range(200):
        y = y0 * (1 + NOISE * rng.standard_normal(y0.size))
        r = least_squares(lambda x, y=y: (np.exp(x[1]) * curve(times / np.exp(x[0])) - y)
                          / (NOISE * y), [np.log(tau), 0.0])
        est.append(r.x[0])
    assert np.std(est) == pytest.approx(sd, rel=0.15)


@pytest.mark.slow
def test_hht_design_separates_the_laws_and_the_fit_picks_the_generating_law(planner,
                                                                            capsys) -> None:
    """HHT 304 -> 308 K, 80 %, 50 um, 1 % noise: the recommended experiment separates the two
    front laws by at least 3 noise widths (worst over the tau bracket), and on synthetic data
    made at its times under either law the kinetics fit's law comparison picks the law that
    made them."""
    ask = ExperimentAsk("HHT", 304.0, 308.0, 0.8, 50.0, size_noise=NOISE,
                        jumps=(308.0, 309.5))
    d = design_experiment(ask, planner)
    out = d.to_dict()
    assert out["law_separation_sigma"] >= 3.0 and out["law_decided"]
    assert out["envelope_before_factor"] > 10.0 > out["envelope_after_factor"]
    assert len(out["sampling_table"]) == 20 and out["experiment"]["steps"][1].startswith(
        "Hold at ")
    b = d.best
    cv = jump_curves(planner, HHT, 304.0, b.t_end, "swollen")
    tau = b.tau_nominal_s / 3.0  # inside the timescale bracket, not the nominal
    rng = np.random.default_rng(7)
    for law in ("delayed", "maxwell"):
        y = b.dry_radius_um * cv.law(law, b.times_s / tau)
        y = y * (1 + NOISE * rng.standard_normal(y.size))
        rep = fit_front_laws(kinetics_data(b.times_s, y), "HHT", 304.0, b.t_end,
                             dry_radius_um=b.dry_radius_um, planner=planner,
                             size_rel_sigma=NOISE, delayed_n=200)
        assert rep["preferred"] == law, rep["note"]
        assert rep["delta_aic"] > 2.0
    assert main(["design", "experiment", "--gel", "HHT", "--t-start", "304", "--t-end", "308",
                 "--fraction", "0.8", "--dry-radius-um", "50", "--jumps", "308,309.5",
                 "--cache", planner.path, "--json"]) == 0
    cli = json.loads(capsys.readouterr().out)
    # the lattice run may be the longer one fit_front_laws stored since (its steps differ)
    assert cli["law_separation_sigma"] == pytest.approx(out["law_separation_sigma"], rel=1e-2)


def test_the_plan_csv_and_impossible_designs(planner, tmp_path, capsys) -> None:
    """--out writes the sampling table a lab fills in (fit kinetics reads it back once the
    radii are there); impossible designs are refused naming the field."""
    csv = tmp_path / "plan.csv"
    assert main(["design", "experiment", "--gel", "ANB", "--t-start", "302", "--t-end", "308",
                 "--fraction", "0.8", "--dry-radius-um", "50", "--size-noise", "0.005",
                 "--jumps", "308", "--n-points", "8", "--out", str(csv),
                 "--cache", planner.path]) == 0
    text = capsys.readouterr().out
    assert "measure: Rest at 302 K for 30 min; Hold at 308 K" in text
    lines = [x for x in csv.read_text().splitlines() if not x.startswith("#")]
    assert lines[0] == "time_s,radius_um" and len(lines) == 9
    # filled in (here with the expected Maxwell radii), fit kinetics reads it as it is
    exp = [float(x.split(": ")[1].split(" / ")[0]) for x in csv.read_text().splitlines()
           if x.startswith("#   ")]
    filled = tmp_path / "filled.csv"
    filled.write_text("\n".join([x for x in csv.read_text().splitlines() if x[0] == "#"]
                                + ["time_s,radius_um"]
                                + [f"{x.rstrip(',')},{r:.6g}" for x, r in
                                   zip(lines[1:], exp, strict=True)]) + "\n")
    assert main(["fit", "kinetics", str(filled), "--gel", "ANB", "--t-start", "302",
                 "--t-end", "308", "--dry-radius-um", "50", "--size-rel-sigma", "0.005",
                 "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["n_points"] == 8
    with pytest.raises(ParameterError) as e:
        ExperimentAsk("ANB", 302.0, 308.0, 0.8, 50.0, n_points=50, min_interval_s=100.0,
                      max_duration_s=600.0)
    assert e.value.field == "n_points"
    with pytest.raises(ParameterError) as e:
        design_experiment(ExperimentAsk("ANB", 302.0, 308.0, 0.8, 50.0, jumps=(304.0,)),
                          planner)
    assert e.value.field == "jumps"
    with pytest.raises(ParameterError) as e:
        ExperimentAsk("ANB", 302.0, 308.0, 0.8, 50.0, size_noise=0.0)
    assert e.value.field == "size_noise"


@pytest.mark.anyio
async def test_design_jobs_over_http(tmp_path, monkeypatch) -> None:
    """POST /v1/design/heating and /v1/design/experiment are stored jobs: 202 + Location,
    polled at /v1/design/jobs/{id} and /v1/jobs/{id}; a bad body is a 422 naming the field;
    a full job queue is a 429; a finished job survives a restart."""
    import api.service as service
    from api import stored_jobs
    from api.http import create_app

    monkeypatch.setenv("THERMOGEL_GELS", str(tmp_path / "gels"))
    cache = str(tmp_path / "v.sqlite")
    body = {"gel": "ANB", "t_start": 302.0, "fraction": 0.5, "at_seconds": 60.0,
            "dry_radius_um": 50.0, "full": False, "constants": {"paper": True}}
    app = create_app(warm=False, cache_path=cache)
    async with app.router.lifespan_context(app):
        transport = httpx.ASGITransport(app=app)
        async with httpx.AsyncClient(base_url="http://t", transport=transport) as c:
            r = await c.post("/v1/design/heating", json=body)
            assert r.status_code == 202, r.text
            url = r.headers["location"]
            deadline = time.monotonic() + 120
            while (j := (await c.get(url)).json())["status"] not in ("done", "failed"):
                assert time.monotonic() < deadline
                await asyncio.sleep(0.2)
            assert j["status"] == "done", j
            assert 307.0 < j["result"]["t_end_K"] < 308.0
            jid = url.rsplit("/", 1)[1]
            same = (await c.get(f"/v1/jobs/{jid}")).json()
            assert same["result"]["t_end_K"] == j["result"]["t_end_K"]
            r = await c.post("/v1/design/heating", json={**body, "mode": "ramp"})
            assert r.status_code == 422 and "t_end" in r.text
            r = await c.post("/v1/design/experiment", json={
                "gel": "ANB", "t_start": 302.0, "t_end": 308.0, "fraction": 0.8,
                "dry_radius_um": 50.0, "size_noise": 0.0})
            assert r.status_code == 422 and "size_noise" in r.text
            assert (await c.get("/v1/design/jobs/design-heating-nope")).status_code == 404
            page = await c.get("/design")  # the page over the two routes, no network
            assert page.status_code == 200 and "/v1/design/experiment" in page.text
            assert "http://" not in page.text and "https://" not in page.text
    # a restart: the finished job is answered from the cache
    app2 = create_app(warm=False, cache_path=cache)
    async with app2.router.lifespan_context(app2):
        transport = httpx.ASGITransport(app=app2)
        async with httpx.AsyncClient(base_url="http://t", transport=transport) as c:
            again = (await c.get(url)).json()
            assert again["status"] == "done"
            assert again["result"]["t_end_K"] == j["result"]["t_end_K"]
    # the queue bounded: with one slot held, the next design job is a 429
    gate = threading.Event()
    kind = stored_jobs.KINDS["design-heating"]

    def held(planner, b):
        gate.wait(30)
        return {"held": True}

    monkeypatch.setitem(stored_jobs.KINDS, "design-heating",
                        stored_jobs.JobKind(kind.name, kind.request, held))
    monkeypatch.setattr(service, "JOB_QUEUE", 1)
    app3 = create_app(warm=False, cache_path=str(tmp_path / "w.sqlite"))
    try:
        async with app3.router.lifespan_context(app3):
            transport = httpx.ASGITransport(app=app3)
            async with httpx.AsyncClient(base_url="http://t", transport=transport) as c:
                assert (await c.post("/v1/design/heating", json=body)).status_code == 202
                r = await c.post("/v1/design/heating", json={**body, "at_seconds": 61.0})
                assert r.status_code == 429, r.text
                gate.set()
    finally:
        gate.set()
