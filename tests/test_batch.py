"""The batch's dose from the front model (issue 26): CV 0 is the single bead, the quadrature
converges and agrees with a brute-force sum over 10,000 beads, the spread figures."""

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.stats import qmc

from dosing import DoseRequest
from dosing.model_choice import front_answer, front_run
from dosing.population.front import (
    NODE_LADDER,
    batch_answer,
    batch_release,
    convergence_table,
    exact_release_fraction,
    release_fraction,
)

JUMP = {"gel": "ANB", "t_start": 302.0, "t_end": 308.0}


def _req(f: float, **dist) -> DoseRequest:
    size = {} if dist.get("kind") == "table" else {"dry_radius_um": 50.0}
    return DoseRequest(**JUMP, dose_fraction=f, size_distribution=dist or None, **size)


def _fr(req: DoseRequest):
    return front_run(req.gel, req.t_start, req.t_end, req.branch, req.settings.regularized)


@pytest.mark.parametrize("f", [0.1, 0.3, 0.8])
def test_cv_zero_is_the_single_bead_exactly(f) -> None:
    single = front_answer(_req(f))
    for kind in ("lognormal", "normal"):
        b = batch_answer(_req(f, kind=kind, cv=0.0))
        assert b.time == single.time and b.seconds == single.seconds
        assert b.quadrature.nodes == 1 and b.quadrature.error == 0.0
        assert b.fraction_delivered == 1.0 and b.delay == 0.0
    # a table of equal beads too
    t = batch_answer(_req(f, kind="table", sizes_um=[50.0] * 7))
    assert t.time == single.time


def test_tabulated_release_matches_the_exact_curve() -> None:
    fr = _fr(_req(0.5))
    s = np.concatenate([np.geomspace(1e-9, 1e-2, 500), np.linspace(0.0, 0.4, 5001)])
    err = np.abs(release_fraction(fr, s) - exact_release_fraction(fr, s)).max()
    assert err < 1e-7  # TABLE_POINTS' stated accuracy (measured 2e-8)


def _brute_force(req: DoseRequest, n: int = 10_000) -> tuple[float, np.ndarray, float]:
    """The batch's dose time summed over n beads drawn (scrambled Halton points through
    the number-weighted quantile) on the exact curve; their radii; the reference bead's
    own time."""
    sizes = req.size_distribution.resolve(req.start_radius)
    u = qmc.Halton(d=1, scramble=True, seed=7).random(n).ravel()
    r = np.asarray(sizes.quantile(u))
    fr = _fr(req)
    single = float(fr.time_to_fraction(req.fraction))
    rho, vol = (r / sizes.mean_um) ** 2, r**3 / np.sum(r**3)

    def v(t: float) -> float:
        return float(exact_release_fraction(fr, t / rho) @ vol) - req.fraction

    return brentq(v, single * rho.min(), single * rho.max(), xtol=1e-14), r, single


@pytest.mark.parametrize("kind,cv,f", [("lognormal", 0.2, 0.8), ("lognormal", 0.3, 0.3),
                                       ("lognormal", 0.3, 0.8), ("normal", 0.3, 0.5)])
def test_quadrature_agrees_with_ten_thousand_beads(kind, cv, f) -> None:
    req = _req(f, kind=kind, cv=cv)
    b = batch_answer(req)
    t_bf, r, single = _brute_force(req)
    assert b.time == pytest.approx(t_bf, rel=5e-3)  # the issue's 0.5 %
    # the fraction of beads that have delivered their own dose by the batch's time
    own = (r / b.reference_dry_radius_um) ** 2 * single
    assert b.fraction_delivered == pytest.approx(np.mean(own <= b.time), abs=5e-3)


def test_quadrature_convergence_table() -> None:
    """Doubling the nodes per panel (8 ... 256): the dose time converges fast (the panels
    split at the kink), the answer's error estimate bounds its distance from the finest
    rung, and the coarse rungs are really off (the table measures something)."""
    req = _req(0.8, cv=0.3)
    b = batch_answer(req)
    sizes = req.size_distribution.resolve(req.start_radius)
    fr = _fr(req)
    table = convergence_table(fr, sizes, 0.8, b.mean_bead_time)
    nodes = [n for n, _ in table]
    ts = np.array([t for _, t in table])
    errs = np.abs(ts - ts[-1]) / ts[-1]
    assert nodes == [2 * k for k in NODE_LADDER]  # two panels (the kink inside the span)
    # measured: 2.7e-4, 2.8e-7, then ~1e-9 (the floor of the tabulated F and the root's
    # tolerance)
    assert errs[0] > 1e-4 and errs[1] > 1e-7  # 8 and 16 per panel: not converged
    assert np.all(errs[2:-1] < 1e-8)  # 32 per panel and more: converged
    q = b.quadrature
    assert q.converged and q.error < 1e-6 and q.nodes == 128
    assert abs(b.time - ts[-1]) / ts[-1] < max(q.error, 1e-9)
    # the split rule beats an unsplit Gauss-Hermite rule with as many nodes
    r, w = sizes.law.hermite(q.nodes)
    rho = (r / sizes.mean_um) ** 2
    t_gh = brentq(lambda t: float(release_fraction(fr, t / rho) @ w) - 0.8, 0.05, 0.3,
                  xtol=1e-14)
    assert abs(t_gh - ts[-1]) / ts[-1] > 100 * abs(b.time - ts[-1]) / ts[-1]


def test_the_issue_figures_and_spread() -> None:
    """ANB 302 -> 308 K, number-weighted lognormal of mean dry radius 50 um: CV 0.2 delays
    the 80 % dose by about a quarter, CV 0.3 by about two thirds (the issue, with the
    truth; the front model measures 0.245 and 0.631); the 30 % and 50 % doses by a sixth
    to nearly a half."""
    d02 = batch_answer(_req(0.8, cv=0.2)).delay
    d03 = batch_answer(_req(0.8, cv=0.3)).delay
    assert 0.2 < d02 < 0.3 and 0.55 < d03 < 0.75
    assert 0.14 < batch_answer(_req(0.3, cv=0.2)).delay < 0.22
    assert 0.4 < batch_answer(_req(0.5, cv=0.3)).delay < 0.5
    delays = [batch_answer(_req(0.8, cv=c)).delay for c in (0.05, 0.1, 0.2, 0.3)]
    assert np.all(np.diff(delays) > 0)
    b = batch_answer(_req(0.8, cv=0.2))
    p10, p50, p90 = b.percentile_times
    assert p10 < p50 < b.mean_bead_time < p90 and p10 < b.time < p90
    assert p50 == pytest.approx((b.percentile_radii_um[1] / 50.0) ** 2 * b.mean_bead_time,
                                rel=1e-12)
    assert b.seconds == pytest.approx(b.time * b.timescale_seconds, rel=1e-14)


def test_two_size_table_is_the_hand_sum() -> None:
    req = _req(0.5, kind="table", sizes_um=[30.0, 60.0], counts=[3, 1])
    b = batch_answer(req)
    fr = _fr(req)
    ref = (3 * 30.0 + 60.0) / 4
    rho = (np.array([30.0, 60.0]) / ref) ** 2
    vol = np.array([3 * 30.0**3, 60.0**3])
    vol /= vol.sum()
    t = brentq(lambda t: float(exact_release_fraction(fr, t / rho) @ vol) - 0.5, 1e-4, 1.0,
               xtol=1e-15)
    assert b.time == pytest.approx(t, rel=1e-6)  # the table's interpolation (< 1e-7 in F)
    assert b.quadrature.error == 0.0 and b.quadrature.nodes == 2
    assert b.fraction_delivered == pytest.approx(0.75)  # the three small beads, not the big


def test_release_curves_reach_the_dose_at_the_dose_time() -> None:
    req = _req(0.8, cv=0.2)
    b = batch_answer(req)
    t = np.linspace(0.0, 0.3, 301)
    c = batch_release(req, np.append(t, b.time))
    v = np.array(c["batch"])
    assert v[-1] == pytest.approx(0.8, abs=1e-9)
    assert np.all(np.diff(v[:-1]) >= -1e-12) and v[0] == 0.0
    p10, p90 = np.array(c["size_classes"]["p10"]), np.array(c["size_classes"]["p90"])
    assert np.all(p10[:-1] >= p90[:-1] - 1e-12)  # small beads release first


def test_design_map_and_the_tolerated_spread() -> None:
    from dosing.studies.batch_design import design_map, tolerated_cv, with_cv

    base = _req(0.8)
    m = design_map(base, [0.0, 0.1, 0.2], [0.3, 0.8])
    d = np.array(m["delay"])
    assert np.all(d[:, 0] == 0.0) and np.all(np.diff(d, axis=1) > 0)
    assert d[1, 2] == batch_answer(_req(0.8, cv=0.2)).delay  # the map is the answers
    c = tolerated_cv(base, 0.1)
    assert batch_answer(with_cv(base, c)).delay == pytest.approx(0.1, abs=1e-6)
    assert 0.1 < c < 0.2  # CV 0.1 delays the 80 % dose 5.6 %, CV 0.2 24 %
