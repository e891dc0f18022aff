"""The API manual is served offline (issue 37): GET /docs and /redoc load nothing from
outside the server: every script, style sheet, icon and font they name is a path on this
server, and those assets are served (and name no outside URL they would fetch)."""

from __future__ import annotations

import re
from html.parser import HTMLParser

import pytest
from api_support import asgi

from api.http import create_app

LOADS = {"script": "src", "link": "href", "img": "src", "iframe": "src", "source": "src"}
OUTSIDE = re.compile(r"^(?:[a-z][a-z0-9+.-]*:)?//", re.I)


class _Loads(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.urls: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        for name, value in attrs:
            if value and (name == LOADS.get(tag) or name in ("src", "href")):
                self.urls.append(value)


def _loaded(html: str) -> list[str]:
    """Every URL the page loads: tags' src / href, and the URLs its inline scripts pass
    to the UI (url: '...', spec-url, ...), and CSS url(...) and @import."""
    p = _Loads()
    p.feed(html)
    inline = re.findall(r"""(?:url|src|href)\s*[:=(]\s*['"]?([^'")\s,]+)""", html)
    return p.urls + inline + re.findall(r"@import\s+['\"]([^'\"]+)", html)



@pytest.mark.anyio
@pytest.mark.parametrize("page", ["/docs", "/redoc"])
async def test_the_manual_loads_nothing_from_outside(page: str, tmp_path) -> None:
    async with asgi(create_app(cache_path=tmp_path / "c.sqlite", warm=False)) as (_, raw):
        r = await raw.get(page)
        assert r.status_code == 200 and "text/html" in r.headers["content-type"]
        urls = _loaded(r.text)
        assert any(u.endswith((".js", ".css")) for u in urls), urls
        outside = [u for u in urls if OUTSIDE.match(u)]
        assert outside == [], outside
        assert "fonts.googleapis" not in r.text and "cdn.jsdelivr" not in r.text
        # and what the scripts would fetch at run time (ReDoc's footer logo) the browser may not
        assert "default-src 'self'" in r.headers["content-security-policy"]
        assert "img-src 'self' data:;" in r.headers["content-security-policy"]
        for url in urls:
            if url.startswith("/docs-assets/"):
                asset = await raw.get(url)
                assert asset.status_code == 200, url
                assert len(asset.content) > 1000
        spec = await raw.get("/openapi.json")
        assert spec.status_code == 200 and spec.json()["paths"]


@pytest.mark.anyio
async def test_swagger_ui_asks_no_outside_validator(tmp_path) -> None:
    async with asgi(create_app(cache_path=tmp_path / "c.sqlite", warm=False)) as (_, raw):
        html = (await raw.get("/docs")).text
        assert '"validatorUrl": null' in html
