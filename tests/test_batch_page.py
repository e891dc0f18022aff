"""The planner page's batch input (issue 26): a size CV gives the batch's answer, read back
against the JSON route; a CV out of range is refused in the page, naming the field, with no
request.  Headless Chromium as in tests/test_page_browser.py (skipped without it, except in
CI); the service's side is checked without a browser too."""

from __future__ import annotations

from pathlib import Path

import httpx
import pytest
from fastapi.testclient import TestClient
from test_page_browser import (
    FRONT,
    _artifacts,
    _fill,
    browser_page,
    refused_in_the_page,
)

from api.http import create_app


def test_the_page_has_the_input_and_the_bounds_it_reads() -> None:
    with TestClient(create_app(warm=False)) as c:
        html = c.get("/").text
        js = c.get("/static/app.js").text if c.get("/static/app.js").status_code == 200 \
            else ""
        cv = c.get("/openapi.json").json()["components"]["schemas"]["SizeDistributionIn"][
            "properties"]["cv"]
    assert 'id="size_cv"' in html and 'id="answer-batch"' in html
    assert cv["anyOf"][0]["minimum"] == 0.0 and cv["anyOf"][0]["maximum"] == 2.0
    assert not js or "size_distribution" in js


@pytest.mark.slow  # a real server and a browser
def test_batch_in_headless_chromium(tmp_path: Path) -> None:
    with browser_page(tmp_path) as (url, page, errors, sent):
        page.select_option("#gel", "ANB")
        _fill(page, t_start="302", t_end="308", doses="80", dry_radius_um="50",
              size_cv="0.2")
        page.click("#plan")
        page.wait_for_selector("body[data-state=answered]", timeout=120_000)
        want = httpx.post(f"{url}/v1/dose-time", json={
            **FRONT, "size_distribution": {"kind": "lognormal", "cv": 0.2}},
            timeout=60).json()
        assert float(page.get_attribute("#answer-batch", "data-value")) == \
            want["batch"]["time"]
        assert float(page.get_attribute("#answer-seconds", "data-value")) == want["seconds"]
        assert "of the beads have delivered" in page.inner_text("#answer-batch")
        page.screenshot(path=str(_artifacts() / "page-batch.png"), full_page=True)
        assert "size CV" in refused_in_the_page(page, sent, "#plan", "data-state",
                                                size_cv="2.5")
        _fill(page, size_cv="")  # one bead again: no batch shown
        page.click("#plan")
        page.wait_for_selector("body[data-state=answered]", timeout=120_000)
        assert page.locator("#answer-batch").is_hidden()
        assert errors == []
