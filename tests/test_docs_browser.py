"""The API manual in headless Chromium (issue 37): /docs and /redoc render the service's
operations with every request the browser makes going to the service itself (none to a
CDN, a font host or a validator), and the network blocked beyond it."""

from __future__ import annotations

import tempfile
from pathlib import Path
from urllib.parse import urlsplit

import pytest
from test_page_browser import CHROMIUM, FLAGS, _need_browser, _serve_gracefully


@pytest.mark.parametrize(("page_path", "ready"), [("/docs", ".opblock"),
                                                  ("/redoc", "[data-section-id]")])
def test_the_manual_renders_offline(page_path: str, ready: str, tmp_path: Path) -> None:
    sync_playwright = _need_browser()
    with _serve_gracefully(tmp_path / "cache.sqlite") as url, \
            tempfile.TemporaryDirectory() as profile, sync_playwright() as pw:
        ctx = pw.chromium.launch_persistent_context(profile, executable_path=CHROMIUM,
                                                    args=FLAGS, headless=True)
        try:
            here = urlsplit(url).netloc
            outside: list[str] = []

            def route(r) -> None:  # only the service answers: anything else is refused
                if urlsplit(r.request.url).netloc == here or r.request.url.startswith("data:"):
                    r.continue_()
                else:
                    outside.append(r.request.url)
                    r.abort()

            ctx.route("**/*", route)
            page = ctx.new_page()
            errors: list[str] = []
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(url + page_path)
            page.wait_for_selector(ready, timeout=60_000)
            assert "dose-time" in page.content()
            assert outside == [], outside
            assert errors == [], errors
        finally:
            ctx.close()
