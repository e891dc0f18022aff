"""Plots fit for a paper (issue 25): the fit's band without the stray sliver near the dry
state, phase-map boundaries computed as curves (they agree with the region test on a
grid), the sweep's error map stating its prior and drawing iso-time contours, the
validation's dot chart, one style and three formats."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from api.plots import style
from api.plots.fit import _band_rows, size_label
from api.plots.phase_map import draw_phase_map, region_bounds, region_masks
from api.plots.sweep import draw_sweep
from api.plots.validation import draw_validation
from dosing.studies.sweep import SweepGrid, run_sweep
from solver.gel import ANB


@pytest.mark.parametrize("fmt", ["png", "svg", "pdf"])
def test_every_format_is_written(tmp_path: Path, fmt: str) -> None:
    plt = style.pyplot()
    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1])
    p = style.save(fig, tmp_path / "f", fmt)
    head = p.read_bytes()[:5]
    assert p.suffix == "." + fmt
    assert {"png": b"\x89PNG", "svg": b"<?xml", "pdf": b"%PDF-"}[fmt] in head
    with pytest.raises(ValueError, match="one of png, svg, pdf"):
        style.save(fig, tmp_path / "f.gif")


def test_fit_band_drops_the_dry_state_sliver_and_keeps_the_rest() -> None:
    size = np.linspace(0.41, 1.35, 50)
    temp = np.linspace(290.0, 330.0, 50)  # T(lambda) grows toward the dry state
    half = np.full(50, 1.0)
    half[:2] = 100.0  # near the dry state the band's edges leave the axis
    half[-3:] = 15.0  # a wide band at the swollen end is real and kept (clipped)
    b = _band_rows({"size": size, "temperature": temp, "lower": temp - half,
                    "upper": temp + half}, 288.0, 322.0)
    assert b["size"].min() > size[1]  # the two sliver rows are gone
    assert np.all(b["temperature"] <= 322.0)
    assert size_label("radius", None) == "radius (data units)"
    assert size_label("diameter", "um") == "diameter (um)"


def test_phase_boundaries_agree_with_the_region_test() -> None:
    temps = np.linspace(296.0, 316.0, 81)
    lams = np.linspace(1.05, 2.8, 60)
    spin, coex = region_masks(ANB, temps, lams)
    b = region_bounds(ANB, lams)
    for name, mask in (("spinodal", spin), ("coexistence", coex)):
        above, below = b[name]
        curve = ((temps[None, :] > np.nan_to_num(above, nan=np.inf)[:, None])
                 | (temps[None, :] < np.nan_to_num(below, nan=-np.inf)[:, None]))
        wrong = curve != mask
        # disagreement only where the grid cell touches the boundary (one T step)
        dt = temps[1] - temps[0]
        near = np.zeros_like(wrong)
        for edge in (above, below):
            near |= np.abs(temps[None, :] - np.nan_to_num(edge, nan=1e9)[:, None]) <= dt
        assert mask.any() and not np.any(wrong & ~near), name


def test_phase_map_draws(tmp_path: Path) -> None:
    p = draw_phase_map(ANB, tmp_path / "pm.svg", jump=(302.0, 2.29, 308.0, 1.3))
    text = Path(p).read_text()
    assert "stable equilibrium" in text


def test_sweep_states_the_prior_and_draws_iso_time_contours(tmp_path: Path) -> None:
    res = run_sweep(SweepGrid(t_ends=np.linspace(307.5, 311.0, 5),
                              dry_radii_um=np.geomspace(10, 200, 5), doses=[0.3, 0.8]))
    p = draw_sweep(res.to_dict(), tmp_path / "sw.svg")
    text = Path(p).read_text()
    assert text.count("prior (not validated)") == 2  # one per dose, stated as a prior
    assert "iso-time" in text and "20 s" in text  # a labelled contour


def test_validation_is_a_dot_chart_with_seconds(tmp_path: Path) -> None:
    ans = {"time": 0.0762, "model": "front-sharp", "dose_fraction": 0.8,
           "error_estimate": 0.03, "timescale_seconds": 2205.0,
           "validation": {"method": "direct", "interfacial_length": 8e-5, "time": 0.0777,
                          "error": 0.004,
                          "uncertainty": {"interfacial_lengths": [4e-5, 1.6e-4],
                                          "interfacial_length_times": [0.0771, 0.079],
                                          "delayed_transition_time": 0.116}}}
    text = Path(draw_validation(ans, tmp_path / "v.svg")).read_text()
    for label in ("truth: ell = 8e-05", "end of the mesh-length range", "delayed transition",
                  "answer (front-sharp)", "time to the dose (s)"):
        assert label in text, label
