"""The service's routers, one per area (FastAPI's "bigger applications" layout).

Each module exposes ``router``; :func:`api.http.create_app` registers their routes on the
app (:func:`api.http.add_routes`).  A new area is a new module here and its router in
that list.
"""
