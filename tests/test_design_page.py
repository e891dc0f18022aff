"""GET /design in a browser (issue 39): the heating's form finds the jump, the experiment's
form shows the sampling table and offers plan.csv.  Same harness as
tests/test_page_browser.py."""

from __future__ import annotations

import tempfile
from pathlib import Path

import pytest
from test_page_browser import CHROMIUM, FLAGS, _need_browser, _serve_gracefully


@pytest.mark.slow  # a real server and a browser
def test_the_design_page_runs_both_jobs(tmp_path: Path, monkeypatch) -> None:
    sync_playwright = _need_browser()
    monkeypatch.setenv("THERMOGEL_GELS", str(tmp_path / "gels"))
    with _serve_gracefully(tmp_path / "cache.sqlite") as url, \
            tempfile.TemporaryDirectory() as profile, sync_playwright() as pw:
        ctx = pw.chromium.launch_persistent_context(
            profile, executable_path=CHROMIUM, args=FLAGS, headless=True,
            viewport={"width": 1400, "height": 1000})
        try:
            page = ctx.new_page()
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
        finally:
            ctx.close()
