"""A schedule for a batch of beads (issue 26, dosing.batch_schedule) on the fake full solver
(closed-form a(t) whose rate depends on ell and n: each bead size its own trajectory)."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
from dosing_fakes import FakeSolver
from scipy.special import ndtri

from dosing import Planner, ScheduleRequest
from dosing.batch_schedule import batch_schedule_with, schedule_sizes
from dosing.protocol import delivery, heat_cool_protocol
from solver.errors import ParameterError

DOSES, RESTS = [0.3, 0.3, 0.2], [0.5, 0.5]
RADIUS = 2.0  # um: ell = 2e-3 at the mean, so the fake's rate depends on each bead's own ell


@pytest.fixture
def planner(tmp_path):
    fake = FakeSolver()
    p = Planner(cache_path=tmp_path / "c.sqlite", executor=ThreadPoolExecutor(2), solver=fake)
    p.fake = fake
    yield p
    p.close()
    p.jobs.executor.shutdown(wait=True)


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
                 beads: int = 400) -> np.ndarray:
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
            d, rests, req.t_start, req.t_end), grid=s.grid, n=s.n,
            interfacial_length=4e-3 / radius)  # the bead's own: xi_dry 4 nm / a_d
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
