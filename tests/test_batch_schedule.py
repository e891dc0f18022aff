"""A schedule for a batch of beads (issue 26, dosing.population.cycles) on the fake full solver
(closed-form a(t) whose rate depends on ell and n: each bead size its own trajectory)."""

from __future__ import annotations

import numpy as np
import pytest
from dosing_fakes import FakeSolver
from scipy.special import ndtri

from dosing import ScheduleRequest
from dosing.population.cycles import batch_schedule_with, schedule_sizes
from dosing.question.shooting import delivery, heat_cool_protocol
from solver.errors import ParameterError

DOSES, RESTS = [0.3, 0.3, 0.2], [0.5, 0.5]
RADIUS = 2.0  # um: ell = 2e-3 at the mean, so the fake's rate depends on each bead's own ell


@pytest.fixture
def planner(fake_planner):
    return fake_planner


def _req(**kw) -> ScheduleRequest:
    return ScheduleRequest("ANB", 302.0, 308.0, doses=DOSES, rests=RESTS,
                           dry_radius_um=RADIUS, **kw)


def test_cv_zero_is_the_single_beads_schedule_exactly(planner) -> None:
    req = _req()
    single = planner.schedule(req)
    b = batch_schedule_with(planner, req, {"cv": 0.0})
    assert b.corrected["actuation_times"] == single.corrected["actuation_times"]
    assert b.corrected["delivered_fractions"] == single.corrected["delivered_fractions"]
    assert b.protocol_check["delivered_fractions"] == single.protocol_check[
        "delivered_fractions"]
    assert [h.actuation_time for h in b.hold] == [h.actuation_time for h in single.hold]
    assert b.quadrature.nodes == 1 and b.quadrature.error == 0.0
    assert b.nodes[0]["interfacial_length"] == single.interfacial_length


def _brute_force(req: ScheduleRequest, cv: float, durations: list[float],
                 beads: int = 400, xi_nm: float = 4.0, lattice: bool = False) -> np.ndarray:
    """Each heating's delivery summed over ``beads`` beads at the volume-weighted law's
    quantiles (i + 1/2) / beads (each bead one share of the fluid), every bead its own fake
    run at its own ell and its own tau."""
    sizes = schedule_sizes(req, {"cv": cv})
    law = sizes.law  # ln R = mu + 3 sig^2 + sig z, z standard normal (volume-weighted)
    r = law.r_of(ndtri((np.arange(beads) + 0.5) / beads))
    fake, out = FakeSolver(), np.zeros(len(durations))
    for radius in r:
        rho = (radius / sizes.mean_um) ** 2
        s = req.settings
        d, rests = [x / rho for x in durations], [x / rho for x in req.rests]
        traj = fake(req.gel, req.t_start, protocol=heat_cool_protocol(
            d, rests, req.t_start, req.t_end), grid="lagrangian" if lattice else s.grid,
            n=s.n, interfacial_length=0.0 if lattice else 1e-3 * xi_nm / radius)
        # the bead's own: xi_dry 4 nm / a_d
        out += np.array(delivery(traj, d, rests, req.start_radius).delivered)
    return out / beads


@pytest.mark.parametrize("cv", [0.2, 0.3])
def test_batch_doses_read_back_from_every_bead(planner, cv) -> None:
    req = _req()
    b = batch_schedule_with(planner, req, {"cv": cv})
    got = _brute_force(req, cv, b.corrected["actuation_times"])
    # each dose within the tolerance; and the rule's sum within its quadrature error
    assert got == pytest.approx(DOSES, rel=req.tolerance)
    assert got == pytest.approx(b.corrected["delivered_fractions"],
                                rel=2.0 * b.quadrature.error + 1e-4)  # 400 beads
    assert b.quadrature.converged and b.quadrature.nodes >= 3
    ells = [n["interfacial_length"] for n in b.nodes]
    assert ells == pytest.approx([4e-3 / n["dry_radius_um"] for n in b.nodes], rel=1e-12)
    assert sum(n["volume_weight"] for n in b.nodes) == pytest.approx(1.0, rel=1e-12)


def test_the_interfacial_length_and_model_form_parts(planner) -> None:
    """Each part is the largest change of a delivered dose at the found times, here read
    back from 400 beads run one by one at xi_dry 2 and 8 nm, and on the delayed lattice
    (the fake's Lagrangian grid at ell = 0): within the sampling and quadrature errors."""
    req = _req()
    b = batch_schedule_with(planner, req, {"cv": 0.2})
    d = b.corrected["actuation_times"]
    base = _brute_force(req, 0.2, d)
    ell = max(np.max(np.abs(_brute_force(req, 0.2, d, xi_nm=x) / base - 1.0))
              for x in (2.0, 8.0))
    form = np.max(np.abs(_brute_force(req, 0.2, d, lattice=True) / base - 1.0))
    u = b.uncertainty
    assert ell > 1e-3 and form > 1e-3  # the fake's rate depends on both
    assert u["interfacial_length_range"].relative == pytest.approx(ell, abs=2e-4)
    assert u["model_form"].relative == pytest.approx(form, abs=2e-4)
    assert "xi_dry 2-8 nm" in u["interfacial_length_range"].text


def test_the_spread_lengthens_the_schedule(planner) -> None:
    req = _req()
    a = batch_schedule_with(planner, req, {"cv": 0.0}).corrected["actuation_times"]
    b = batch_schedule_with(planner, req, {"cv": 0.3}).corrected["actuation_times"]
    assert all(y > 1.05 * x for x, y in zip(a, b, strict=True))


def test_a_measured_table_is_summed_exactly(planner) -> None:
    req = ScheduleRequest("ANB", 302.0, 308.0, doses=DOSES, rests=RESTS)
    table = {"kind": "table", "sizes_um": [1.5, 2.0, 3.0], "counts": [2, 3, 1]}
    req = _req() if False else ScheduleRequest(
        "ANB", 302.0, 308.0, doses=DOSES, rests=RESTS,
        dry_radius_um=(1.5 * 2 + 2.0 * 3 + 3.0) / 6)
    b = batch_schedule_with(planner, req, table)
    assert b.quadrature.error == 0.0 and b.quadrature.nodes == 3
    assert b.corrected["delivered_fractions"] == pytest.approx(DOSES, rel=req.tolerance)


@pytest.mark.parametrize(("dist", "field"), [
    ({"cv": 2.5}, "size_distribution.cv"),
    ({"cv": -0.1}, "size_distribution.cv"),
    ({"kind": "table", "sizes_um": []}, "size_distribution.sizes_um"),
    ({"kind": "table", "sizes_um": [1.0, -2.0]}, "size_distribution.sizes_um[1]"),
    ({"kind": "table", "sizes_um": list(np.linspace(1.0, 3.0, 13))},
     "size_distribution.sizes_um"),
    ({"cv": 0.2, "mean_um": 3.0}, "dry_radius_um"),
])
def test_bad_batches_are_refused_naming_the_field(planner, dist, field) -> None:
    with pytest.raises(ParameterError) as e:
        batch_schedule_with(planner, _req(), dist)
    assert e.value.field == field
    assert planner.fake.calls == []


def test_a_batch_schedule_needs_its_reference_bead(planner) -> None:
    req = ScheduleRequest("ANB", 302.0, 308.0, doses=DOSES, rests=RESTS)
    with pytest.raises(ParameterError) as e:
        batch_schedule_with(planner, req, {"cv": 0.2})
    assert e.value.field == "dry_radius_um"


# ------------------------------------------------------------------ the ways in
SCHED = ["schedule", "--gel", "ANB", "--t-start", "302", "--t-end", "308", "--doses", "0.3",
         "0.3", "0.2", "--rests", "0.5", "0.5"]


@pytest.fixture
def cli_on_fake(monkeypatch):
    """``thermogel schedule`` with its one-shot planner on a fake solver."""
    import dosing.planner

    fake, real = FakeSolver(), dosing.planner.one_shot
    monkeypatch.setattr(dosing.planner, "one_shot",
                        lambda path, ex, **kw: real(path, ex, solver=fake, **kw))
    return fake


def test_cli_size_cv_matches_python(cli_on_fake, planner, capsys, tmp_path) -> None:
    import json

    from api.cli import main

    argv = [*SCHED, "--dry-radius-um", str(RADIUS), "--size-cv", "0.2",
            "--cache", str(tmp_path / "cli.sqlite")]
    assert main([*argv, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    want = batch_schedule_with(planner, _req(), {"cv": 0.2}).to_dict()
    assert out["corrected"]["actuation_times"] == want["corrected"]["actuation_times"]
    assert out["quadrature"] == json.loads(json.dumps(want["quadrature"]))
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "a batch (a number-weighted lognormal of dry radii, mean 2 um, CV 0.2)" in text
    assert "quadrature over sizes: Gauss-Hermite" in text and "nodes (dry um" in text


@pytest.mark.parametrize(("extra", "flag"), [
    (["--size-cv", "-0.1", "--dry-radius-um", "2"], "--size-cv"),
    (["--size-cv", "2.5", "--dry-radius-um", "2"], "--size-cv"),
    (["--size-cv", "0.2"], "dry_radius_um"),
    (["--size-cv", "0.2", "--dry-radius-um", "2", "--drug-diffusivity-cm2-s", "1e-7",
      "--wait", "0.1"], "drug.wait"),
    (["--size-cv", "0.2", "--dry-radius-um", "2", "--medium-volume-ml", "1"],
     "--medium-volume-ml"),
])
def test_cli_refusals_name_the_option(cli_on_fake, capsys, tmp_path, extra, flag) -> None:
    from api.cli import main

    assert main([*SCHED, *extra, "--cache", str(tmp_path / "c.sqlite")]) == 2
    assert flag in capsys.readouterr().err
    assert cli_on_fake.calls == []


def test_cli_refuses_an_empty_or_negative_table(cli_on_fake, capsys, tmp_path) -> None:
    from api.cli import main

    for i, text in enumerate(["radius_um\n", "radius_um\n2\n-3\n"]):
        p = tmp_path / f"s{i}.csv"
        p.write_text(text)
        assert main([*SCHED, "--sizes", str(p), "--cache", str(tmp_path / "c.sqlite")]) == 2
        assert "--sizes" in capsys.readouterr().err



@pytest.mark.anyio
async def test_http_size_distribution_matches_python(planner, tmp_path) -> None:

    from api_support import asgi

    from api.http import create_app

    body = {"gel": "ANB", "t_start": 302.0, "t_end": 308.0, "doses": DOSES, "rests": RESTS,
            "dry_radius_um": RADIUS, "size_distribution": {"cv": 0.2}}
    async with asgi(create_app(planner=planner, warm=False)) as (api, raw):
        for bad, loc in [({"cv": 2.5}, "cv"), ({"cv": -1.0}, "cv"),
                         ({"kind": "table", "sizes_um": []}, "sizes_um"),
                         ({"kind": "table", "sizes_um": [2.0, -1.0]}, "sizes_um"),
                         ({"cv": 0.2, "mean_um": 3.0}, "dry_radius_um")]:
            r = await raw.post("/v1/schedule", json={**body, "size_distribution": bad})
            assert r.status_code == 422 and loc in r.text, r.text
        # a drug batch's schedule is planned (issue 35) into a perfect sink, without a wait
        r = await raw.post("/v1/schedule", json={**body, "drug": {"diffusivity_cm2_s": 1e-7,
                                                                  "wait": 0.1}})
        assert r.status_code == 422 and "drug.wait" in r.text, r.text
        assert planner.fake.calls == []
        r = await raw.post("/v1/schedule", json=body)
        assert r.status_code == 202, r.text
        vid = r.json()["validation_id"]
        v = await api.wait_validation(vid, timeout=120.0, interval=0.05)
        assert v.status == "done", v.error
    want = batch_schedule_with(planner, _req(), {"cv": 0.2}).to_dict()
    assert v.result["batch"] is True
    assert v.result["corrected"]["actuation_times"] == want["corrected"]["actuation_times"]
    assert v.result["quadrature"]["nodes"] == want["quadrature"]["nodes"]
    assert v.result["nodes"] == want["nodes"]
