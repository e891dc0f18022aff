"""The limits of the service's connection guards (:mod:`api.connections`), defined once.

Light (no uvicorn import): ``thermogel serve`` builds its options' defaults from it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any

READ_TIMEOUT_S = 30.0  # a whole request, from its first byte
PER_CLIENT = 64  # open connections per client address
TOTAL = 256  # open connections in all
RETRY_AFTER_S = 2
ENV = {"read_timeout": "THERMOGEL_READ_TIMEOUT",
       "per_client": "THERMOGEL_MAX_CONNECTIONS_PER_CLIENT",
       "total": "THERMOGEL_MAX_CONNECTIONS"}


@dataclass(frozen=True)
class ConnectionLimits:
    """The guards' limits (api.connections' module doc); ``from_env`` / ``to_env`` carry
    them to worker processes."""

    read_timeout: float = READ_TIMEOUT_S
    per_client: int = PER_CLIENT
    total: int = TOTAL

    @classmethod
    def from_env(cls, env: Mapping[str, str] | None = None) -> ConnectionLimits:
        """The limits set in ``env`` (default: the process's environment, read through
        dosing.settings; the defaults for those not set)."""
        if env is None:
            from dosing.settings import settings

            s = settings()
            return cls(**{k: v for k, v in (("read_timeout", s.read_timeout),
                                            ("per_client", s.max_connections_per_client),
                                            ("total", s.max_connections)) if v is not None})
        given: dict[str, Any] = {}
        for f in fields(cls):
            raw = env.get(ENV[f.name])
            if raw:
                given[f.name] = float(raw) if f.name == "read_timeout" else int(raw)
        return cls(**given)

    def to_env(self) -> dict[str, str]:
        """The environment variables that give these limits to a worker process."""
        return {ENV[f.name]: str(getattr(self, f.name)) for f in fields(self)}
