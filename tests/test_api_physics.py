"""HTTP routes without the planner: /health, /v1/gels, /v1/equilibrium, /v1/classify (issue 6).

Through httpx's ASGI transport.  The service is a thin layer, so its numbers must equal
the solver's own (exact JSON round trip of floats); bad input must be 422 naming the field.
"""

from __future__ import annotations

import subprocess
import sys

import pytest
from api_support import ROOT, asgi

from api.client import ApiError
from api.http import create_app
from solver.equilibrium import equilibria, folds
from solver.gel import ANB, HHT, Gel, Permeability
from solver.phase import classify_jump

pytestmark = pytest.mark.anyio


class _NoPlanner:
    """Stands in for dosing.Planner: these routes never touch it."""

    def close(self) -> None:
        pass



@pytest.fixture(scope="module")
async def clients():
    async with asgi(create_app(planner=_NoPlanner(), warm=True)) as pair:
        yield pair


@pytest.mark.slow  # the warm-up compiles the full solver's kernels on a fresh checkout
async def test_health_reports_warm_kernels(clients) -> None:
    api, _ = clients
    h = await api.health()
    assert h.status == "ok"
    assert h.kernels_warm >= 2  # osmotic_p and osmotic_dp at least (used by every route)
    assert "solver.thermo.osmotic_p" not in h.kernels_cold


async def test_gels_lists_presets_with_folds(clients) -> None:
    api, _ = clients
    out = await api.gels()
    by_name = {g.gel.name: g for g in out.gels}
    assert set(by_name) == {"ANB", "HHT"}
    for gel in (ANB, HHT):
        got = by_name[gel.name]
        assert (got.gel.omega, got.gel.a0, got.gel.b1) == (gel.omega, gel.a0, gel.b1)
        assert [f.temperature for f in got.folds] == [f.temperature for f in folds(gel)]
    # ANB's folds bracket its volume-phase transition: 304.74 K (swell), 305.81 K (shrink)
    assert [(round(f.temperature, 2), f.kind) for f in by_name["ANB"].folds] == [
        (304.74, "swell"), (305.81, "shrink")]


async def test_equilibrium_matches_solver(clients) -> None:
    api, _ = clients
    out = await api.equilibrium(gel="ANB", temperature=305.0)
    want = equilibria(ANB, 305.0)
    assert [(e.stretch, e.stable) for e in out.equilibria] == [(e.stretch, e.stable) for e in want]
    assert [e.stable for e in out.equilibria] == [True, False, True]


async def test_equilibrium_custom_gel(clients) -> None:
    api, _ = clients
    spec = {"base": "HHT", "omega": 500.0, "permeability": "power", "beta": 2.0}
    out = await api.equilibrium(gel=spec, temperature=300.0)
    gel = Gel(500.0, HHT.a0, HHT.b0, HHT.a1, HHT.b1, Permeability("power", 2.0))
    assert [e.stretch for e in out.equilibria] == [e.stretch for e in equilibria(gel, 300.0)]
    assert out.gel.name == "custom" and out.gel.permeability.beta == 2.0


async def test_classify_matches_solver(clients) -> None:
    api, _ = clients
    for gel, t0, t1 in ((ANB, 302.0, 308.0), (HHT, 304.0, 308.0), (ANB, 308.0, 302.0)):
        out = await api.classify(gel=gel.name, t_start=t0, t_end=t1)
        want = classify_jump(gel, t0, t1)
        assert (out.direction, out.behaviour, out.start_stretch) == (
            want.direction, want.behaviour, want.start_stretch)


@pytest.mark.parametrize(("path", "body", "loc"), [
    ("/v1/equilibrium", {"gel": "ANB"}, ["body", "temperature"]),
    ("/v1/equilibrium", {"temperature": 400.0}, ["body", "temperature"]),
    ("/v1/equilibrium", {"temperature": 273.0}, ["body", "temperature"]),
    ("/v1/equilibrium", {"temperature": "warm"}, ["body", "temperature"]),
    ("/v1/equilibrium", {"temperature": 300.0, "gel": "XYZ"}, ["body", "gel"]),
    ("/v1/equilibrium", {"temperature": 300.0, "temp": 1}, ["body", "temp"]),
    ("/v1/equilibrium", {"temperature": 300.0, "gel": {"omega": -1.0}},
     ["body", "gel", "custom", "omega"]),
    ("/v1/classify", {"t_start": 302.0}, ["body", "t_end"]),
    ("/v1/classify", {"t_start": 302.0, "t_end": 500.0}, ["body", "t_end"]),
    ("/v1/classify", {"t_start": 302.0, "t_end": 308.0, "branch": "middle"}, ["body", "branch"]),
    ("/v1/classify", {"t_start": 302.0, "t_end": 308.0, "gel": {"permeability": "power"}},
     ["body", "gel", "custom"]),
])
async def test_bad_input_is_422_naming_the_field(clients, path, body, loc) -> None:
    _, raw = clients
    r = await raw.post(path, json=body)
    assert r.status_code == 422, r.text
    assert loc in [d["loc"] for d in r.json()["detail"]], r.text


async def test_malformed_json_is_422(clients) -> None:
    _, raw = clients
    r = await raw.post("/v1/classify", content=b"{not json", headers={
        "content-type": "application/json"})
    assert r.status_code == 422


async def test_client_raises_api_error_with_fields(clients) -> None:
    api, _ = clients
    with pytest.raises(ApiError) as err:
        await api.classify({"t_start": 302.0, "t_end": 308.0, "gel": "ANB"}, branch=None,
                           gel={"a0": 2000.0})
    assert err.value.status == 422 and err.value.fields == ["gel.a0"]


async def test_openapi_documents_every_field(clients) -> None:
    """Every field of every model has a description (units and bounds): a usable manual."""
    _, raw = clients
    spec = (await raw.get("/openapi.json")).json()
    paths = set(spec["paths"])
    assert {"/health", "/v1/gels", "/v1/equilibrium", "/v1/classify", "/v1/dose-time",
            "/v1/schedule", "/v1/validations/{validation_id}"} <= paths
    undocumented = []
    for name, schema in spec["components"]["schemas"].items():
        if name in ("HTTPValidationError", "ValidationError"):
            continue
        for field, prop in schema.get("properties", {}).items():
            if "description" not in prop and "$ref" not in prop and "allOf" not in prop:
                undocumented.append(f"{name}.{field}")
    assert not undocumented, undocumented


def test_importing_solver_and_dosing_never_imports_fastapi() -> None:
    code = (
        "import importlib, pkgutil, sys\n"
        "for pkg in ('solver', 'dosing'):\n"
        "    m = importlib.import_module(pkg)\n"
        "    for info in pkgutil.walk_packages(m.__path__, pkg + '.'):\n"
        "        importlib.import_module(info.name)\n"
        "bad = sorted(n for n in ('fastapi', 'uvicorn', 'starlette', 'httpx', 'matplotlib')\n"
        "             if n in sys.modules)\n"
        "print(','.join(bad))\n")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                         timeout=120, check=True)
    assert out.stdout.strip() == ""
