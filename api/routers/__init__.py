"""Route groups, each a module exposing ``router = fastapi.APIRouter()`` that
:func:`api.http.create_app` includes."""
