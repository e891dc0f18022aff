"""The service's routers, one per area (FastAPI's "bigger applications" layout).

Each module exposes ``router``; :func:`api.http.create_app` includes them.  A new area is
a new module here and one ``app.include_router(...)`` line there.
"""
