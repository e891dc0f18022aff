"""Size distributions of a batch (issue 26): the laws, their weightings and states, a
measured table, and the refusals naming the field."""

import math

import numpy as np
import pytest

from dosing import DoseRequest
from dosing.population.sizes import MAX_ROWS, SizeDistribution, read_sizes_csv
from solver import ParameterError

JUMP = {"gel": "ANB", "t_start": 302.0, "t_end": 308.0}


def test_lognormal_by_mean_and_cv_has_that_number_mean_and_cv() -> None:
    d = SizeDistribution(mean_um=50.0, cv=0.25).resolve(1.0)
    r = d.sample(400_000, seed=3)
    # sampling error of the mean 0.25 / sqrt(4e5) = 4e-4, of the CV about 6e-4
    assert r.mean() == pytest.approx(50.0, rel=2e-3)
    assert r.std() / r.mean() == pytest.approx(0.25, rel=1e-2)
    assert d.mean_um == pytest.approx(50.0, rel=1e-13)


def test_median_and_gsd_is_the_same_lognormal() -> None:
    sig = math.sqrt(math.log1p(0.3**2))
    a = SizeDistribution(mean_um=40.0, cv=0.3).resolve(1.0)
    b = SizeDistribution(median_um=40.0 * math.exp(-0.5 * sig**2), gsd=math.exp(sig)).resolve(1.0)
    p = np.array([0.1, 0.5, 0.9])
    assert np.allclose(a.quantile(p), b.quantile(p), rtol=1e-12)


def test_volume_weighted_lognormal_is_hatch_choate_shifted() -> None:
    # a volume-weighted law: the number-weighted one with ln R shifted by -3 sigma^2
    v = SizeDistribution(mean_um=50.0, cv=0.2, weighting="volume").resolve(1.0)
    sig2 = math.log1p(0.04)
    assert v.mean_um == pytest.approx(50.0 * math.exp(-3.0 * sig2), rel=1e-12)
    # the volume-weighted quadrature reproduces the volume-weighted mean radius
    r, w = v.nodes(32)
    assert np.sum(w * r) == pytest.approx(50.0, rel=1e-10)


def test_swollen_sizes_are_divided_by_the_start_stretch() -> None:
    req = DoseRequest(**JUMP, dose_fraction=0.5,
                      size_distribution={"mean_um": 120.0, "cv": 0.1, "state": "swollen"})
    assert req.bead_dry_radius_um == pytest.approx(120.0 / req.start_radius, rel=1e-12)
    d = req.size_distribution.resolve(req.start_radius)
    assert d.mean_um == pytest.approx(120.0 / req.start_radius, rel=1e-12)


def test_diameters_are_halved_and_units_read() -> None:
    d = SizeDistribution(mean_um="0.1 mm", cv=0.1, measure="diameter").resolve(1.0)
    assert d.mean_um == pytest.approx(50.0, rel=1e-12)


def test_normal_number_weighted_matches_samples_and_is_truncated() -> None:
    d = SizeDistribution(kind="normal", mean_um=50.0, cv=0.6).resolve(1.0)
    r = d.sample(200_000, seed=1)
    assert r.min() > 0.0
    assert float(d.cdf(0.5)) == 0.0  # nothing below the cut (1 % of the mean)
    assert r.mean() == pytest.approx(d.mean_um, rel=5e-3)
    assert d.mean_um > 50.0  # the truncation at > 0 lifts the mean


def test_volume_weighted_normal_quadrature_holds_its_volume_law() -> None:
    d = SizeDistribution(kind="normal", mean_um=50.0, cv=0.1, weighting="volume").resolve(1.0)
    r, w = d.nodes(32)
    assert np.sum(w * r) == pytest.approx(50.0, rel=1e-9)
    assert d.mean_um < 50.0  # by number the small beads count more


def test_table_with_counts_equals_the_expanded_table() -> None:
    a = SizeDistribution(kind="table", sizes_um=[40.0, 50.0, 60.0], counts=[1, 3, 2])
    b = SizeDistribution(kind="table", sizes_um=[40.0, 50.0, 50.0, 50.0, 60.0, 60.0])
    ra, wa = a.resolve(1.0).nodes(0)
    rb, wb = b.resolve(1.0).nodes(0)
    assert np.array_equal(ra, rb) and np.allclose(wa, wb, rtol=1e-14)
    assert a.number_mean_um() == pytest.approx((40 + 150 + 120) / 6, rel=1e-14)
    assert float(a.resolve(1.0).cdf(50.0)) == pytest.approx(4 / 6)


def test_volume_weighted_table_turns_into_numbers() -> None:
    # equal volume fractions in 1 um and 2 um beads: 8 small beads per large one
    d = SizeDistribution(kind="table", sizes_um=[1.0, 2.0], counts=[0.5, 0.5],
                         weighting="volume").resolve(1.0)
    assert float(d.cdf(1.0)) == pytest.approx(8 / 9, rel=1e-14)


def test_csv_diameters_with_a_unit_and_counts(tmp_path) -> None:
    p = tmp_path / "sizes.csv"
    p.write_text("diameter (mm),count\n0.08,1\n0.1,3\n0.12,2\n")
    d = read_sizes_csv(str(p))
    assert d.measure == "diameter"
    assert d.resolve(1.0).mean_um == pytest.approx((40 + 150 + 120) / 6, rel=1e-12)
    # no header: radii in um, one bead per row
    assert read_sizes_csv("40\n50\n60\n").number_mean_um() == pytest.approx(50.0)


@pytest.mark.parametrize("spec,field", [
    ({"cv": -0.1, "mean_um": 50.0}, "size_distribution.cv"),
    ({"cv": 2.5, "mean_um": 50.0}, "size_distribution.cv"),
    ({"cv": float("nan"), "mean_um": 50.0}, "size_distribution.cv"),
    ({"kind": "table", "sizes_um": []}, "size_distribution.sizes_um"),
    ({"kind": "table", "sizes_um": [40.0, -5.0]}, "size_distribution.sizes_um[1]"),
    ({"kind": "table", "sizes_um": [40.0, 50.0], "counts": [1, -1]},
     "size_distribution.counts[1]"),
    ({"kind": "table", "sizes_um": [40.0], "counts": [0]}, "size_distribution.counts"),
    ({"kind": "table", "sizes_um": [40.0] * (MAX_ROWS + 1)}, "size_distribution.sizes_um"),
    ({"kind": "weibull", "cv": 0.1}, "size_distribution.kind"),
    ({"cv": 0.1, "weighting": "mass"}, "size_distribution.weighting"),
    ({"cv": 0.1, "state": "wet"}, "size_distribution.state"),
    ({"cv": 0.1, "mean_um": "50 K"}, "size_distribution.mean_um"),
    ({"cv": 0.1, "sizes_um": [1.0]}, "size_distribution.sizes_um"),
    ({"median_um": 50.0, "gsd": 0.5}, "size_distribution.gsd"),
    ({"kind": "normal", "mean_um": 50.0}, "size_distribution.cv"),
    ({"mean_um": 50.0, "cv": 0.1, "colour": "red"}, "size_distribution.colour"),
])
def test_bad_distributions_are_refused_naming_the_field(spec, field) -> None:
    with pytest.raises(ParameterError) as e:
        DoseRequest(**JUMP, dose_fraction=0.5, size_distribution=spec)
    assert e.value.field == field


def test_csv_over_the_row_limit_is_refused() -> None:
    with pytest.raises(ParameterError) as e:
        read_sizes_csv("radius_um\n" + "50\n" * (MAX_ROWS + 1))
    assert e.value.field == "size_distribution.sizes_um"


@pytest.mark.parametrize("kw,field", [
    ({"dose_volume_ul": 1e-3, "dry_radius_um": 50.0}, "dose_fraction"),  # a batch: fractions
    ({"dose_fraction": 0.5}, "size_distribution.mean_um"),  # a CV and no size anywhere
    ({"dose_fraction": 0.5, "swollen_radius_um": 100.0}, "swollen_radius_um"),  # dry spread
])
def test_batch_request_refusals(kw, field) -> None:
    with pytest.raises(ParameterError) as e:
        DoseRequest(**JUMP, size_distribution={"cv": 0.2}, **kw)
    assert e.value.field == field


def test_a_spread_without_a_size_takes_the_request_size() -> None:
    r = DoseRequest(**JUMP, dose_fraction=0.5, dry_radius_um=50.0,
                    size_distribution={"kind": "normal", "sd_um": 10.0})
    assert r.size_distribution.mean_um == 50.0 and r.size_distribution.sd_um == 10.0
    with pytest.raises(ParameterError) as e:  # the request's size is a number-weighted mean
        DoseRequest(**JUMP, dose_fraction=0.5, dry_radius_um=50.0,
                    size_distribution={"cv": 0.2, "weighting": "volume"})
    assert e.value.field == "size_distribution.weighting"


def test_a_size_on_both_must_agree() -> None:
    ok = DoseRequest(**JUMP, dose_fraction=0.5, dry_radius_um=50.0,
                     size_distribution={"mean_um": 50.0, "cv": 0.2})
    assert ok.bead_dry_radius_um == 50.0
    with pytest.raises(ParameterError) as e:
        DoseRequest(**JUMP, dose_fraction=0.5, dry_radius_um=40.0,
                    size_distribution={"mean_um": 50.0, "cv": 0.2})
    assert e.value.field == "dry_radius_um"
