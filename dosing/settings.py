"""thermogel's settings: one :class:`Settings` object read from the environment
(pydantic-settings, prefix ``THERMOGEL_``), its default folders from platformdirs.

Every variable thermogel reads is a field here (the table: docs/architecture.md, "Settings").
An empty variable is unset; a bad value is a ``ParameterError`` naming it.  :func:`settings`
reads the environment anew on each call and imports pydantic then, not with :mod:`dosing`."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from solver.errors import ParameterError

PREFIX = "THERMOGEL_"
APP_NAME = "thermogel"
CACHE_FILE = "validations.sqlite"

if TYPE_CHECKING:  # pragma: no cover
    from pydantic_settings import BaseSettings as _Base
else:
    _Base = object

_CLASS: list[Any] = []


def _settings_class() -> type:
    """The pydantic-settings class (built on first use: pydantic is imported then)."""
    if _CLASS:
        return _CLASS[0]
    from pydantic import Field
    from pydantic_settings import BaseSettings, SettingsConfigDict

    class Settings(BaseSettings):
        """thermogel's settings (module doc): ``THERMOGEL_<FIELD>`` in the environment."""

        model_config = SettingsConfigDict(env_prefix=PREFIX, env_ignore_empty=True,
                                          extra="ignore", case_sensitive=False)

        cache: Path | None = Field(None, description="the validation cache file")
        gels: Path | None = Field(None, description="the stored fitted gels' folder")
        max_pending: int | None = Field(None, ge=0, description="validations queued or "
                                        "running before a 429 (0: the planner's default)")
        max_body: int | None = Field(None, ge=1, description="largest request body, bytes")
        lease_seconds: float | None = Field(None, ge=0.0, description="a run's lease, s")
        warmup: bool = Field(True, description="warm the numba kernels at start-up")
        api_token: str | None = Field(None, description="the service's bearer token")
        allowed_hosts: str | None = Field(None, description="Host names, comma-separated")
        read_timeout: float | None = Field(None, gt=0.0, description="read deadline, s")
        max_connections_per_client: int | None = Field(None, ge=1)
        max_connections: int | None = Field(None, ge=1)
        supervisor_pid: int | None = Field(None, description="the supervisor process")
        artifacts: Path | None = Field(None, description="the browser test's screenshots")
        run_seconds: float | None = Field(None, gt=0.0, description="one full-solver run's "
                                          "wall-clock budget, s (default 600)")

        @property
        def cache_path(self) -> Path:
            """THERMOGEL_CACHE, else the user cache folder's validations.sqlite."""
            if self.cache is not None:
                return self.cache.expanduser()
            from platformdirs import user_cache_path

            return user_cache_path(APP_NAME, appauthor=False) / CACHE_FILE

        @property
        def gels_dir(self) -> Path:
            """THERMOGEL_GELS, else gels/ beside the validation cache."""
            return self.gels.expanduser() if self.gels is not None else \
                self.cache_path.parent / "gels"

        @property
        def hosts(self) -> list[str] | None:
            """THERMOGEL_ALLOWED_HOSTS as a list (None: not set)."""
            out = [h.strip() for h in (self.allowed_hosts or "").split(",") if h.strip()]
            return out or None

    _CLASS.append(Settings)
    return Settings


def settings(**given: Any) -> Any:
    """The settings now: the environment's ``THERMOGEL_*`` (``given`` fields first); a bad
    value is a ``ParameterError`` naming its variable."""
    from pydantic import ValidationError

    cls = _settings_class()
    try:
        return cls(**given)
    except ValidationError as exc:
        err = exc.errors()[0]
        name = PREFIX + "_".join(str(x) for x in err.get("loc", ())).upper()
        raise ParameterError(name, err.get("input"), err.get("msg", "a valid value")) from None


def fields() -> list[str]:
    """The environment variables :class:`Settings` reads."""
    return [PREFIX + name.upper() for name in _settings_class().model_fields]
