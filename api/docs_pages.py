"""The API manual served offline: Swagger UI at ``/docs`` and ReDoc at ``/redoc`` load
their scripts, styles and icon from this server (``/docs-assets/``: the minified assets
the ``fastapi-offline`` package ships), never from a CDN, and load no web font; Swagger
UI's validator badge (an image from an outside host) is off, and the pages'
Content-Security-Policy lets the browser load from this server only (ReDoc's footer logo
sits on its CDN).  ``tests/test_docs_offline.py`` parses both pages for outside URLs;
``tests/test_docs_browser.py`` renders them in Chromium with the network beyond the
service refused."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from fastapi import FastAPI, Request
from fastapi.openapi.docs import (
    get_redoc_html,
    get_swagger_ui_html,
    get_swagger_ui_oauth2_redirect_html,
)
from fastapi.responses import HTMLResponse
from fastapi.staticfiles import StaticFiles

ASSETS_URL = "/docs-assets"
DOCS_URL, REDOC_URL = "/docs", "/redoc"
OAUTH2_REDIRECT_URL = "/docs/oauth2-redirect"
SWAGGER_PARAMETERS = {"validatorUrl": None}  # no badge fetched from validator.swagger.io
# the pages may load from this server only: ReDoc's footer names an image on its CDN, which
# the browser then does not fetch (scripts and styles inline in FastAPI's page, the spec's
# worker from a blob)
CSP = ("default-src 'self'; script-src 'self' 'unsafe-inline'; style-src 'self' "
       "'unsafe-inline'; img-src 'self' data:; font-src 'self' data:; connect-src 'self'; "
       "worker-src 'self' blob:; frame-src 'none'; object-src 'none'; base-uri 'self'")


def _offline(page: HTMLResponse) -> HTMLResponse:
    page.headers["Content-Security-Policy"] = CSP
    return page


def assets_dir() -> Path:
    """The folder of the bundled Swagger UI and ReDoc assets (the fastapi-offline package:
    swagger-ui-bundle.js, swagger-ui.css, redoc.standalone.js, favicon.png)."""
    import fastapi_offline

    return Path(fastapi_offline.__file__).resolve().parent / "static"


def install(app: FastAPI) -> None:
    """Serve the manual's pages and their assets from ``app`` (create it with
    ``docs_url=None, redoc_url=None``: FastAPI's own pages load from a CDN)."""
    app.mount(ASSETS_URL, StaticFiles(directory=assets_dir()), name="docs-assets")

    def root(request: Request) -> str:
        return str(request.scope.get("root_path") or "")

    @app.get(DOCS_URL, include_in_schema=False)
    async def swagger_ui(request: Request) -> HTMLResponse:
        r = root(request)
        return _offline(get_swagger_ui_html(
            openapi_url=f"{r}{app.openapi_url}", title=f"{app.title} - API manual",
            swagger_js_url=f"{r}{ASSETS_URL}/swagger-ui-bundle.js",
            swagger_css_url=f"{r}{ASSETS_URL}/swagger-ui.css",
            swagger_favicon_url=f"{r}{ASSETS_URL}/favicon.png",
            oauth2_redirect_url=f"{r}{OAUTH2_REDIRECT_URL}",
            swagger_ui_parameters={**(app.swagger_ui_parameters or {}), **SWAGGER_PARAMETERS}))

    @app.get(OAUTH2_REDIRECT_URL, include_in_schema=False)
    async def swagger_ui_redirect() -> HTMLResponse:
        return get_swagger_ui_oauth2_redirect_html()

    @app.get(REDOC_URL, include_in_schema=False)
    async def redoc(request: Request) -> HTMLResponse:
        r = root(request)
        return _offline(get_redoc_html(openapi_url=f"{r}{app.openapi_url}",
                              title=f"{app.title} - API manual (ReDoc)",
                              redoc_js_url=f"{r}{ASSETS_URL}/redoc.standalone.js",
                              redoc_favicon_url=f"{r}{ASSETS_URL}/favicon.png",
                              with_google_fonts=False))


def offline_kwargs() -> dict[str, Any]:
    """FastAPI(...) keywords that turn off its CDN-loading pages (:func:`install` serves
    them instead)."""
    return {"docs_url": None, "redoc_url": None}
