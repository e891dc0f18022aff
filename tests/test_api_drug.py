"""The ``drug`` field of the dose and schedule routes (api/schemas.py DrugOut, api/service.py)."""

from __future__ import annotations

import asyncio
import time

import pytest
from api_support import asgi

from api.http import create_app
from dosing.runs.solute import DrugCache

pytestmark = pytest.mark.anyio

DOSE = {"gel": "ANB", "t_start": 302.0, "t_end": 308.0, "dose_fraction": 0.3,
        "dry_radius_um": 50.0, "interfacial_length": 0.01}





@pytest.fixture
async def clients(planner):
    async with asgi(create_app(planner=planner, warm=False)) as pair:
        yield pair


async def test_drug_dose_answers(clients) -> None:
    _, raw = clients
    r = await raw.post("/v1/dose-time", json={**DOSE, "drug": {"load_ug": 2.0}})
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["drug"] is True and body["dose_ug"] == pytest.approx(0.6)
    assert body["mechanism"].startswith("squeezed out") and body["model"] == "front-sharp"
    diffusing = {**DOSE, "drug": {
        "diffusivity_cm2_s": 1e-6, "load_ug": 1.0, "wait": 0.001}}
    r = await raw.post("/v1/dose-time", json=diffusing)
    assert r.status_code == 202, r.text  # its drug runs are a job: no HTTP thread waits
    url = r.headers["location"]
    assert url == r.json()["validation_url"] and "/dose-" in url
    deadline = time.monotonic() + 900  # a drug run and its check: minutes on a busy machine
    while time.monotonic() < deadline:
        job = (await raw.get(url)).json()
        if job["status"] in ("done", "failed"):
            break
        await asyncio.sleep(0.2)
    assert job["status"] == "done" and job["kind"] == "dose", job
    r = await raw.post("/v1/dose-time", json=diffusing)  # now cached: answered at once
    assert r.status_code == 200, r.text
    got = r.json()
    plain = lambda d: {k: v for k, v in d.items() if k not in ("request", "version")}  # noqa: E731
    assert plain(got) == plain(job["result"])  # the answer; its provenance is the poll's own
    assert "units" in got["request"] and got["version"] == job["version"]
    assert got["model"] == "full" and got["leaked_before_heating"] > 0.0
    # hindered by the gel's own 4 nm dry mesh (r_s = 2.45 nm: r_s / xi = 0.27 swollen)
    assert got["effective_diffusivity_cm2_s"] < 0.7 * got["drug_diffusivity_cm2_s"]
    assert got["peclet"] > 0.0 and "xi_dry = 4 nm" in got["mesh"]


@pytest.mark.parametrize("drug,extra,loc", [
    ({"diffusivity_cm2_s": -1e-7}, {}, ["body", "drug", "diffusivity_cm2_s"]),
    ({"diffusivity_cm2_s": 1.0}, {}, ["body", "drug", "diffusivity_cm2_s"]),
    ({"partition": 0.0}, {}, ["body", "drug", "partition"]),
    ({"release_volume_ul": 1e-5}, {}, ["body", "drug", "release_volume_ul"]),
    ({"load_ug": 1.0}, {"dose_fraction": None, "drug_mass_ug": 1.5}, ["body", "drug_mass_ug"]),
    ({"load_ug": 1.0}, {"dose_fraction": 1.0}, ["body", "dose_fraction"]),
    ({"hindrance": "magic"}, {}, ["body", "drug", "hindrance"]),
])
async def test_bad_drug_is_422_naming_the_field(clients, planner, drug, extra, loc) -> None:
    _, raw = clients
    cache = DrugCache(planner.cache.path)
    before = (len(planner.cache), cache.integrity())
    body = {k: v for k, v in {**DOSE, **extra, "drug": drug}.items() if v is not None}
    r = await raw.post("/v1/dose-time", json=body)
    assert r.status_code == 422, r.text
    assert r.json()["detail"][0]["loc"][:len(loc)] == loc, r.json()
    assert (len(planner.cache), cache.integrity()) == before  # nothing cached is lost
    cache.close()


async def test_drug_schedule_hold_at_once_then_a_job(clients) -> None:
    _, raw = clients
    body = {"gel": "ANB", "t_start": 302.0, "t_end": 308.0, "doses": [0.3, 0.3],
            "rests": [0.5], "dry_radius_um": 50.0, "interfacial_length": 0.01,
            "drug": {"load_ug": 1.0}, "check_protocol": False, "correct": False}
    r = await raw.post("/v1/schedule", json=body)
    assert r.status_code == 200 and len(r.json()["hold"]) == 2, r.text
    r = await raw.post("/v1/schedule", json={**body, "check_protocol": True,
                                              "drug": {"diffusivity_cm2_s": 1e-6}})
    assert r.status_code == 202, r.text
    url = r.json()["validation_url"]
    deadline = time.monotonic() + 120
    while (v := (await raw.get(url)).json())["status"] not in ("done", "failed"):
        assert time.monotonic() < deadline
        await asyncio.sleep(0.2)
    assert v["status"] == "done", v
    check = v["result"]["protocol_check"]
    assert len(check["rest_leak_fractions"]) == 1 and check["mass_balance_error"] < 1e-10
    bad = await raw.post("/v1/schedule", json={**body, "doses": [0.6, 0.5]})
    assert bad.status_code == 422 and bad.json()["detail"][0]["loc"][:2] == ["body", "doses"]
