"""GET /design in a browser (issue 39): the heating's form finds the jump, the experiment's
form shows the sampling table and offers plan.csv.  Same harness as
tests/test_page_browser.py."""

from __future__ import annotations

from pathlib import Path

import pytest
from test_page_browser import browser_page


@pytest.mark.slow  # a real server and a browser
def test_the_design_page_runs_both_jobs(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv("THERMOGEL_GELS", str(tmp_path / "gels"))
    with browser_page(tmp_path) as (url, page, _, _):
        page.goto(url + "/design")
        page.click("#run-heating")
        page.wait_for_function(
            "document.querySelector('#heating-out').textContent.includes('envelope')",
            timeout=120_000)
        assert "Hold at 307.7" in page.inner_text("#heating-out")  # 50 % at 0.5 s (tau 22 s)
        page.fill("#experiment [name=max_duration_s]", "1200")
        page.click("#run-experiment")
        page.wait_for_function(
            "document.querySelectorAll('#experiment-table tr').length > 5",
            timeout=240_000)
        assert "noise widths" in page.inner_text("#experiment-out")
        assert page.is_visible("#experiment-csv")
