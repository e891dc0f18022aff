"""A validated batch answer (issue 26): the truth per interfacial-length band, its
three-part uncertainty and the quadrature error, on the fake full solver (closed-form a(t)
whose rate depends on ell and n, so each part is a known number)."""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
from dosing_fakes import ELL_C, ELL_ORDER, MOVING_C, RATES, FakeSolver
from scipy.optimize import brentq

from dosing import DoseRequest, Planner
from dosing.population.bands import band_edges, validated_batch

JUMP = {"gel": "ANB", "t_start": 302.0, "t_end": 308.0}


@pytest.fixture
def planner(tmp_path):
    p = Planner(cache_path=tmp_path / "c.sqlite", executor=ThreadPoolExecutor(2),
                solver=FakeSolver())
    yield p
    p.close()
    p.jobs.executor.shutdown(wait=True)


def _rate(ell: float, n: int) -> float:
    return RATES["moving"] / (1.0 + ELL_C * ell**ELL_ORDER) / (1.0 + MOVING_C / n)


@pytest.mark.parametrize("every_band", [False, True])
def test_bands_follow_each_beads_own_ell(planner, every_band) -> None:
    req = DoseRequest(**JUMP, dose_fraction=0.5, dry_radius_um=10.0,
                      size_distribution={"cv": 0.3})
    b = validated_batch(planner, req, every_band=every_band)
    sizes = req.size_distribution.resolve(req.start_radius)
    edges, reps = band_edges(sizes)
    assert len(reps) == 3 and np.all(np.diff(reps) > 0)
    ells = [x["interfacial_length"] for x in b.uncertainty["bands"]]
    assert ells == pytest.approx([4e-3 / r for r in reps], rel=1e-12)  # xi 4 nm / a_d
    # the same sum written out on the fake's closed form: F_b = F_end (1 - exp(-k_b s))
    a0, af = req.start_radius, req.jump.final_radius
    f_end = (a0**3 - af**3) / (a0**3 - 1.0)
    r = np.asarray(sizes.quantile((np.arange(200_000) + 0.5) / 200_000))
    k = np.array([_rate(e, 400) for e in ells])[np.searchsorted(edges, r)]
    rho, vol = (r / sizes.mean_um) ** 2, r**3 / np.sum(r**3)
    t = brentq(lambda t: float((f_end * (1 - np.exp(-k * t / rho))) @ vol) - 0.5, 1e-4, 10.0,
               xtol=1e-14)
    assert b.time == pytest.approx(t, rel=2e-4)  # 2e5 stratified beads, the fake's samples
    assert b.model == "truth-bands"
    u = b.uncertainty
    # numerical: every band at n / 2 cells; the fake's times scale as 1 + 2 / n
    assert u["numerical"].relative == pytest.approx((1 + 2 / 200) / (1 + 2 / 400) - 1,
                                                    rel=0.05)
    # interfacial length: xi 2 and 8 nm with n / 2 cells (as module truth runs them); the
    # fake's times as (1 + 200 ell^1.5)(1 + 2 / n): the batch's change lies within the bands'
    ratios = [(1 + ELL_C * (x * e) ** ELL_ORDER) / (1 + ELL_C * e**ELL_ORDER)
              * (1 + MOVING_C / 200) / (1 + MOVING_C / 400) - 1
              for e in ells for x in (0.5, 2.0)]
    assert min(ratios) * 0.95 <= u["interfacial_length_range"].relative <= max(ratios) * 1.05
    assert u["quadrature"].relative < 1e-5
    assert u["model_form"].relative is not None
    assert 0.0 < b.fraction_delivered < 1.0


def test_one_size_is_the_single_bead_validation(planner) -> None:
    req = DoseRequest(**JUMP, dose_fraction=0.5, dry_radius_um=20.0,
                      size_distribution={"cv": 0.0})
    b = validated_batch(planner, req)
    single = planner.dose(DoseRequest(**JUMP, dose_fraction=0.5, dry_radius_um=20.0),
                          validate=True)
    assert b.time == pytest.approx(single.validation.time, rel=1e-6)
    assert b.delay == pytest.approx(0.0, abs=1e-9)
    assert b.uncertainty["numerical"].relative == pytest.approx(
        single.uncertainty.numerical.relative, rel=1e-3)
    assert math.isfinite(b.seconds)
