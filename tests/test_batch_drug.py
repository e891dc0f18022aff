"""A batch's drug dose into a shared medium through every way in (issue 26):
dosing.population.medium, `thermogel dose` with a drug and --size-cv, POST /v1/dose-time with a drug
and a size_distribution.  Coarse mechanics (Lagrangian, n = 40, ell = 0) keep it quick."""

from __future__ import annotations

import functools
import json

import numpy as np
import pytest
from api_support import asgi

from api.cli import main
from api.http import create_app
from dosing.payload.release import DrugDoseRequest
from dosing.population.medium import HORIZON, batch_dry_volume_ul, drug_batch_dose
from dosing.population.sizes import as_distribution
from dosing.runs.mechanics import jump_mechanics
from dosing.runs.solute import drug_settings
from solver.errors import ParameterError
from solver.gel import as_gel
from solver.solute import Solute, release

DRUG = {"diffusivity_cm2_s": 1e-6, "hindrance": "none"}
SETTINGS = {"grid": "lagrangian", "n": 40, "interfacial_length": 0.0}
TABLE = {"kind": "table", "sizes_um": [40.0, 60.0]}


def _req(drug: dict | None = None, **kw) -> DrugDoseRequest:
    return DrugDoseRequest("ANB", 302, 308, drug or DRUG, dose_fraction=0.5,
                           dry_radius_um=50.0, settings=SETTINGS, **kw)


def test_equal_beads_match_one_bead_in_its_share_of_the_medium() -> None:
    """CV 0 with a medium: the full solute solver's own finite medium (one bead in V / N).
    A slow drug (D0 1e-8 cm^2/s, the gel's own D): its dose comes late enough (~0.05 tau)
    for the kernel's dose time, linear between samples 5e-4 tau apart, to be within 1e-3
    (measured 2.1e-4; the batch's numerical error 5e-5)."""
    req = _req({"diffusivity_cm2_s": 1e-8, "hindrance": "none", "load_ug": 1e-4})
    ans = drug_batch_dose(req, {"cv": 0.0}, 20.0, 1e6)
    # half of 1e6 x 1e-4 ug in 20 mL grown by the fluid expelled by then (< the stored 5.8 mL)
    assert 50.0 / (20e3 + 5.8e3) < ans.medium_concentration_ug_per_ul < 50.0 / 20e3
    sizes = as_distribution({"cv": 0.0, "mean_um": 50.0}).resolve(req.start_radius)
    v0 = 20.0e3 / batch_dry_volume_ul(sizes, 1e6)
    assert ans.medium_over_pore_volume == pytest.approx(v0 / (req.start_radius**3 - 1))
    res = jump_mechanics(req.gel, req.t_start, req.t_end, req.branch,
                         drug_settings(req.settings), HORIZON)
    rel = release(res, Solute(diffusivity=req.solute.diffusivity,
                              hindrance=req.solute.hindrance, release_volume=v0), rtol=1e-10)
    assert ans.time == pytest.approx(rel.time_to_release(0.5), rel=1e-3)  # numerical 2e-4
    assert ans.mass_balance_error < 1e-10
    assert ans.sink_overestimate > 0.0 and ans.quadrature_error == 0.0


def test_cli_and_http_match_python(capsys) -> None:
    ref = drug_batch_dose(_req(), {"cv": 0.2}, 5.0, 1e6).to_dict()
    argv = ["dose", "--gel", "ANB", "--t-start", "302", "--t-end", "308", "--fraction", "0.5",
            "--dry-radius-um", "50", "--size-cv", "0.2", "--drug-diffusivity-cm2-s", "1e-6",
            "--hindrance", "none", "--medium-volume-ml", "5", "--bead-count", "1e6",
            "--grid", "lagrangian", "--n", "40", "--interfacial-length", "0", "--json"]
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["time"] == ref["time"] and out["sink_time"] == ref["sink_time"]
    assert 0.0 < out["sink_overestimate"] < 1.0


def test_cli_refuses_a_medium_without_a_drug_batch(capsys) -> None:
    argv = ["dose", "--gel", "ANB", "--t-start", "302", "--t-end", "308", "--fraction", "0.5",
            "--dry-radius-um", "50", "--medium-volume-ml", "5", "--bead-count", "10"]
    assert main(argv) == 2
    assert "--medium-volume-ml" in capsys.readouterr().err


def test_bad_batch_medium_input_is_refused_naming_the_field() -> None:
    with pytest.raises(ParameterError) as exc:
        drug_batch_dose(_req(), {"cv": 0.2}, 5.0, None)
    assert exc.value.field == "bead_count"
    with pytest.raises(ParameterError) as exc:
        drug_batch_dose(_req(), {"cv": 0.2}, "5 K", 1e6)
    assert exc.value.field == "medium_volume_ml"
    with pytest.raises(ParameterError) as exc:
        drug_batch_dose(_req(wait=0.1), {"cv": 0.2})
    assert exc.value.field == "wait"



@pytest.mark.anyio
async def test_http_refuses_bad_batch_medium_fields(tmp_path) -> None:
    from concurrent.futures import ThreadPoolExecutor

    from dosing import Planner

    body = {"gel": "ANB", "t_start": 302, "t_end": 308, "dose_fraction": 0.5,
            "dry_radius_um": 50, "drug": DRUG, "size_distribution": {"cv": 0.2}}
    planner = Planner(cache_path=str(tmp_path / "c.sqlite"), executor=ThreadPoolExecutor(1))
    try:
        async with asgi(create_app(planner=planner, warm=False)) as (_, raw):
            for extra, field in (({"medium_volume_ml": 5}, "bead_count"),
                                 ({"medium_volume_ml": 1e9, "bead_count": 10},
                                  "medium_volume_ml"),
                                 ({"bead_count": 0.5, "medium_volume_ml": 1}, "bead_count")):
                r = await raw.post("/v1/dose-time", json={**body, **extra})
                assert r.status_code == 422, r.text
                assert field in r.text
            r = await raw.post("/v1/dose-time", json={**body, "drug": None,
                                                      "medium_volume_ml": 5, "bead_count": 10})
            assert r.status_code == 422 and "medium_volume_ml" in r.text
    finally:
        planner.close()
        planner.jobs.executor.shutdown(wait=True)


def _dose_time_blocking(tmp_path, body: dict) -> dict:
    """The service's dose_time on ``body`` with no job state: a stored job's run, here
    blocking, on a planner of its own (closed afterwards)."""
    from concurrent.futures import ThreadPoolExecutor

    from api.schemas import DoseTimeRequest
    from api.service import dose_time
    from dosing import Planner

    planner = Planner(cache_path=str(tmp_path / "c.sqlite"), executor=ThreadPoolExecutor(1))
    try:
        return dose_time(planner, DoseTimeRequest(**body))
    finally:
        planner.close()
        planner.jobs.executor.shutdown(wait=True)


def test_http_job_answers_the_python_batch(tmp_path) -> None:
    """The stored drug-dose job's run (api.service, state None: blocking) is drug_batch_dose
    at the request's default settings (the truth's mechanics)."""
    body = {"gel": "ANB", "t_start": 302, "t_end": 308, "dose_fraction": 0.5,
            "drug": DRUG, "size_distribution": TABLE, "medium_volume_ml": "20 mL",
            "bead_count": 1e6}
    out = _dose_time_blocking(tmp_path, body)
    ref = drug_batch_dose(DrugDoseRequest("ANB", 302, 308, DRUG, dose_fraction=0.5),
                          TABLE, 20.0, 1e6)
    assert out["batch"]["time"] == ref.time and out["batch"]["medium_volume_ml"] == 20.0


# --------------------------------------------- each band at its own ell, the three parts
@functools.lru_cache(maxsize=16)
def _coarse(temp: float, n: int):
    from dosing.runs.scenario import SolverSettings
    from dosing.runs.solute import simulate_protocol

    return simulate_protocol(as_gel("ANB"), 302.0, [(0.5, temp)], "swollen",
                             SolverSettings(grid="lagrangian", n=n, interfacial_length=0.0))


def _stand_in(settings) -> tuple[float, int]:
    """A coarse real run standing in for the truth at ``settings``: its jump 1e4 x ell K
    deeper (so every band, ell and the delayed lattice has its own, known mechanics), on
    n / 10 cells (the check n / 2 on half as many)."""
    return 308.0 + 1e4 * settings.interfacial_length, max(settings.n // 10, 20)


@pytest.fixture
def coarse_mechanics(monkeypatch):
    import dosing.population.medium as bd

    calls = []

    def mech(gel, t_start, t_end, branch, settings, horizon):
        calls.append(settings)
        return _coarse(*_stand_in(settings))

    monkeypatch.setattr(bd, "jump_mechanics", mech)
    return calls


@pytest.mark.parametrize("medium", [None, 2.0])
def test_each_band_runs_at_its_own_ell_and_the_three_parts(coarse_mechanics, medium) -> None:
    """The direct truth (the default settings): the batch's bands each at the ell of their
    bead (xi_dry / a_d), every class on its band's mechanics (the answer recomputed here
    from the runs by hand), and each part of the uncertainty the batch's change when every
    class follows one of the central band's other runs (n / 2 cells; xi 2 and 8 nm; the
    delayed lattice)."""
    from dosing.population.bands import band_edges
    from dosing.population.medium import CLASSES, POINTS, START, batch_classes
    from solver.solute import coupled_release, node_volumes

    req = DrugDoseRequest("ANB", 302, 308, DRUG, dose_fraction=0.5, dry_radius_um=50.0)
    assert req.settings.direct
    count = None if medium is None else 1e5
    ans = drug_batch_dose(req, {"cv": 0.3}, medium, count)
    sizes = as_distribution({"cv": 0.3, "mean_um": 50.0}).resolve(req.start_radius)
    edges, reps = band_edges(sizes)
    ells = [b["interfacial_length"] for b in ans.bands]
    assert ells == pytest.approx([4e-3 / r for r in reps], rel=1e-12) and len(set(ells)) == 3
    v0 = None if medium is None else medium * 1e3 / batch_dry_volume_ul(sizes, 1e5)
    rho, nu = batch_classes(sizes, CLASSES[0])
    t_max = 0.5 * float(batch_classes(sizes, CLASSES[-1])[0].max())
    times = np.concatenate(([0.0], np.geomspace(t_max * START, t_max, POINTS)))

    def batch_time(runs, band) -> float:
        s = [np.asarray(r.t, dtype=float) for r in runs]
        mr = coupled_release(s, [node_volumes(r) for r in runs], req.solute, rho, nu, v0,
                             times, sub=2, points=0, band=band)
        return mr.time_to_release(0.5)

    band = np.searchsorted(edges, sizes.mean_um * np.sqrt(rho))
    mine = [_coarse(308.0 + 1e4 * e, 40) for e in ells]
    assert ans.time == batch_time(mine, band)
    one = np.zeros_like(band)
    t0 = batch_time([mine[1]], one)
    assert abs(ans.time / t0 - 1.0) > 1e-3  # the bands' own ells matter here
    u = ans.uncertainty
    check = batch_time([_coarse(308.0 + 1e4 * ells[1], 20)], one)
    assert u["numerical"].relative == pytest.approx(
        abs(check / t0 - 1.0) + ans.numerical_error, rel=1e-9)
    ell_runs = [batch_time([_coarse(308.0 + 1e4 * ells[1] * x, 40)], one) for x in (0.5, 2.0)]
    assert u["interfacial_length_range"].relative == pytest.approx(
        max(abs(t / t0 - 1.0) for t in ell_runs), rel=1e-9)
    assert u["model_form"].relative == pytest.approx(
        abs(batch_time([_coarse(308.0, 40)], one) / t0 - 1.0), rel=1e-9)
    assert all(p.relative > 0.0 for p in u.values())
    assert "interfacial length" in ans.note and "model form" in ans.note


# ----------------------------------------------------------------- under a heating protocol
RAMP = ["Heat to 308 K at 5 K/min"]


def _protocol_req(**kw) -> DrugDoseRequest:
    return DrugDoseRequest("ANB", 302, None, DRUG, dose_fraction=0.5, dry_radius_um=50.0,
                           settings=SETTINGS, protocol=RAMP, **kw)


def test_under_a_protocol_cv_zero_is_the_single_beads_drug_dose(tmp_path) -> None:
    """One size: the coupled solve on the protocol's mechanics against the single bead's
    drug dose under the protocol (the adaptive solute solver on the same mechanics):
    measured 5.8e-5 apart, the coupled solve's numerical error (steps halved) 9e-6."""
    from concurrent.futures import ThreadPoolExecutor

    from dosing import Planner
    from dosing.payload.release import plan_drug_dose

    req = _protocol_req()
    with Planner(cache_path=tmp_path / "c.sqlite", executor=ThreadPoolExecutor(1)) as p:
        one = plan_drug_dose(p, req)
    ans = drug_batch_dose(req, {"cv": 0.0})
    assert ans.time == pytest.approx(one.time, rel=5e-4)
    assert ans.classes == 1 and ans.quadrature_error == 0.0 and ans.numerical_error < 1e-4
    assert "under the protocol" in ans.note.lower() or "Under the protocol" in ans.note


def test_under_a_protocol_each_size_runs_its_own_program() -> None:
    """CV 0.2 into a sink: the batch's time T solves sum_k v_k F_k(T / rho_k) = f with F_k
    each node's own release on its own run of the protocol (the adaptive solute solver),
    every node a different dimensionless program; later than its mean bead; a shared medium
    conserves the drug and the sink sum overstates it."""
    from dosing.population.cycles import rule
    from dosing.population.medium import protocol_batch_time
    from solver.solute import release

    req = _protocol_req()
    sizes = as_distribution({"cv": 0.2, "mean_um": 50.0}).resolve(req.start_radius)
    res = protocol_batch_time(req, sizes, None)
    r, v, _ = rule(sizes, res["nodes"])
    assert np.array_equal(r, res["radii"]) and res["nodes"] == 3
    taus = [m.tau_s for m in res["runs"]]
    assert taus == pytest.approx([taus[1] * (x / r[1]) ** 2 for x in r], rel=1e-12)
    t = res["time"]
    got = sum(w * release(m.result, req.solute).released_at(t / (x / sizes.mean_um) ** 2)
              for w, x, m in zip(v, r, res["runs"], strict=True))
    assert got == pytest.approx(0.5, rel=1e-3)
    single = drug_batch_dose(req, {"cv": 0.0}).time
    ans = drug_batch_dose(req, {"cv": 0.2})
    assert ans.time == t and ans.time > 1.1 * single
    assert ans.quadrature_error < 1e-3 and ans.uncertainty["numerical"].relative < 1e-3
    shared = drug_batch_dose(req, {"cv": 0.2}, 1.0, 1e5)
    assert shared.mass_balance_error < 1e-10 and shared.sink_overestimate > 0.0
    assert shared.time > ans.time and shared.sink_time == ans.time


def test_a_drug_batch_under_a_protocol_is_the_same_answer_by_every_way_in(
        tmp_path, capsys, monkeypatch) -> None:
    """`thermogel dose --protocol ... --size-cv ... --drug-...` gives the Python answer of
    drug_batch_dose; the HTTP body (its stored 'drug-dose' job, run here blocking) reaches the
    same function with the same protocol, drug and sizes (HTTP runs at the truth's settings,
    too costly here: the call is recorded instead)."""
    import dosing.population.medium as batch_drug

    ans = drug_batch_dose(_protocol_req(), {"cv": 0.2})
    argv = ["dose", "--gel", "ANB", "--t-start", "302", "--protocol", RAMP[0], "--fraction",
            "0.5", "--dry-radius-um", "50", "--size-cv", "0.2", "--drug-diffusivity-cm2-s",
            "1e-6", "--hindrance", "none", "--grid", "lagrangian", "--n", "40",
            "--interfacial-length", "0", "--json"]
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["time"] == ans.time and out["model"] == ans.model
    calls = []
    monkeypatch.setattr(batch_drug, "drug_batch_dose",
                        lambda req, dist, *rest: calls.append((req, dist)) or ans)
    body = {"gel": "ANB", "t_start": 302, "protocol": RAMP, "dose_fraction": 0.5,
            "dry_radius_um": 50, "drug": DRUG, "size_distribution": {"cv": 0.2}}
    got = _dose_time_blocking(tmp_path, body)
    assert got["batch"]["time"] == ans.time
    (req, dist), = calls
    ref = _protocol_req()
    assert req.heating == ref.heating and req.solute == ref.solute
    assert dist["cv"] == 0.2 and req.dose_fraction == 0.5
