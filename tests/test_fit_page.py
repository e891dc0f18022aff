"""Fitted gels on the page: listed by GET /v1/gels from the server's store and answered
with their fitted timescale (issue 27).  Same harness as tests/test_page_browser.py."""

from __future__ import annotations

from pathlib import Path

import httpx
import pytest
from test_page_browser import _fill, browser_page

from dosing.fits.gel_store import GelStore
from solver.gel import HHT

D_FIT = 3.0e-13  # m^2/s at 310 K: slower than either reading of the constants


@pytest.mark.slow  # a real server and a browser
def test_fitted_gel_is_listed_and_planned_on_the_page(tmp_path: Path, monkeypatch) -> None:
    gels = tmp_path / "gels"
    monkeypatch.setenv("THERMOGEL_GELS", str(gels))
    GelStore(gels).save("labgel", HHT, kinetics={"data": {}, "fit": {
        "diffusivity_m2_s": D_FIT, "diffusivity_cm2_s": D_FIT * 1e4,
        "diffusivity_interval_cm2_s": [0.95 * D_FIT * 1e4, 1.05 * D_FIT * 1e4],
        "diffusivity_t_k": 310.0, "tau_s": (40e-6) ** 2 / D_FIT, "dry_radius_um": 40.0,
        "model": "front-sharp", "parameters": {"tau": (40e-6) ** 2 / D_FIT}}})
    body = {"gel": "labgel", "t_start": 300.0, "t_end": 310.0, "dose_fraction": 0.5,
            "dry_radius_um": 40.0}
    with browser_page(tmp_path) as (url, page, _, _):  # the page is ready on "/"
        listed = httpx.get(f"{url}/v1/gels", timeout=60).json()["fitted"]
        assert [g["name"] for g in listed] == ["labgel"]
        want = httpx.post(f"{url}/v1/dose-time", json=body, timeout=60).json()
        assert want["timescale_seconds"] == pytest.approx((40e-6) ** 2 / D_FIT)
        assert "labgel (fitted)" in page.inner_text("#gel")
        page.select_option("#gel", "labgel")
        _fill(page, t_start="300", t_end="310", doses="50", dry_radius_um="40")
        page.click("#plan")
        page.wait_for_selector("body[data-state=answered]", timeout=120_000)
        got = float(page.get_attribute("#answer-seconds", "data-value"))
        assert got == pytest.approx(want["seconds"], rel=1e-9)
