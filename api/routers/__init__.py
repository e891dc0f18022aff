"""Routers added to the app by ``app.include_router`` in ``api.http.create_app``."""
