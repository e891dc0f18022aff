"""``thermogel serve``: the HTTP planner service under uvicorn, on the embedded SQLite cache.

Options reach the app (in every worker process) through environment variables read by
:func:`api.http.app_from_env`; fastapi and uvicorn are imported only when this runs.
"""

from __future__ import annotations

import argparse
import os

from .. import connection_limits as limits

H11_MAX_HEADER_BYTES = 64 * 1024  # request line and headers (uvicorn's h11 limit)


def register(sub: argparse._SubParsersAction) -> None:
    """Add the sub-command."""
    p = sub.add_parser("serve", help="run the HTTP planner service (FastAPI under uvicorn)")
    p.add_argument("--host", default="127.0.0.1",
                   help="interface to bind (default 127.0.0.1; 0.0.0.0 in a container)")
    p.add_argument("--port", type=int, default=8000, help="TCP port (default 8000)")
    p.add_argument("--cache", default=None, metavar="PATH",
                   help="SQLite file of the validation cache (default: the planner's, "
                        "$THERMOGEL_CACHE if set)")
    p.add_argument("--workers", type=int, default=1,
                   help="uvicorn worker processes, each with its own planner on the same "
                        "cache file (default 1)")
    p.add_argument("--max-pending", type=int, default=None,
                   help="validations (each with all its runs) queued or running before 429 "
                        "(default: the planner's, 64)")
    p.add_argument("--max-body-bytes", type=int, default=None,
                   help="request bodies over this size are refused with 413 before they are "
                        "read (default 1 MiB)")
    p.add_argument("--lease-seconds", type=float, default=None,
                   help="how long a crashed server's claim on a run outlives it before "
                        "another server on the same cache takes the run over (default 30)")
    p.add_argument("--token", default=None,
                   help="require 'Authorization: Bearer TOKEN' on every route but /health "
                        "(default $THERMOGEL_API_TOKEN; required when --host is not loopback)")
    p.add_argument("--allowed-hosts", default=None, metavar="H1,H2",
                   help="Host headers to accept, comma-separated, each a name (any port) "
                        "or name:port, '*.domain' or '*' (default on loopback: localhost, "
                        "127.0.0.1, [::1] with any port, against DNS rebinding; beyond "
                        "loopback any; $THERMOGEL_ALLOWED_HOSTS)")
    p.add_argument("--timeout-keep-alive", type=float, default=5.0,
                   help="close a keep-alive connection idle this long, s (default 5)")
    p.add_argument("--limit-concurrency", type=int, default=None,
                   help="open connections in all before 503 as JSON (default "
                        f"{limits.TOTAL})")
    p.add_argument("--max-connections-per-client", type=int, default=None,
                   help="open connections per client address before 429 as JSON with "
                        f"Retry-After (default {limits.PER_CLIENT})")
    p.add_argument("--read-timeout", type=float, default=None,
                   help="a request (line, headers and body) must arrive whole within this "
                        f"many seconds, else 408 and the connection is closed (default "
                        f"{limits.READ_TIMEOUT_S:g})")
    p.add_argument("--log-level", default="info",
                   choices=["critical", "error", "warning", "info", "debug"])
    p.add_argument("--no-warmup", action="store_true",
                   help="skip warming the numba kernels at start-up")
    p.add_argument("--warmup-only", action="store_true",
                   help="warm (and cache on disk) every numba kernel, print the report, exit "
                        "(the Dockerfile runs it at build time)")
    p.set_defaults(func=run)


def configure_env(args: argparse.Namespace) -> None:
    """Pass the options to the app factory through the environment."""
    if args.cache:
        os.environ["THERMOGEL_CACHE"] = os.path.abspath(args.cache)
    if args.max_pending is not None:
        os.environ["THERMOGEL_MAX_PENDING"] = str(args.max_pending)
    if args.max_body_bytes is not None:
        os.environ["THERMOGEL_MAX_BODY"] = str(args.max_body_bytes)
    if args.lease_seconds is not None:
        os.environ["THERMOGEL_LEASE_SECONDS"] = str(args.lease_seconds)
    if args.token:
        os.environ["THERMOGEL_API_TOKEN"] = args.token
    from api.auth import LOOPBACK_HOSTS, is_loopback

    if args.allowed_hosts:
        os.environ["THERMOGEL_ALLOWED_HOSTS"] = args.allowed_hosts
    elif is_loopback(args.host) and not os.environ.get("THERMOGEL_ALLOWED_HOSTS"):
        # DNS rebinding: a page elsewhere may resolve its own name to 127.0.0.1
        os.environ["THERMOGEL_ALLOWED_HOSTS"] = ",".join(
            dict.fromkeys((*LOOPBACK_HOSTS, args.host if ":" not in args.host
                           else f"[{args.host}]")))
    if args.workers > 1:  # its worker processes end themselves if this one is killed
        os.environ["THERMOGEL_SUPERVISOR_PID"] = str(os.getpid())
    os.environ["THERMOGEL_WARMUP"] = "0" if args.no_warmup else "1"


def connection_limits(args: argparse.Namespace) -> limits.ConnectionLimits:
    """The connection guards' limits (api.connections) from the options."""
    given = {"total": args.limit_concurrency, "per_client": args.max_connections_per_client,
             "read_timeout": args.read_timeout}
    return limits.ConnectionLimits(**{k: v for k, v in given.items() if v is not None})


def log_config(level: str = "info") -> dict:
    """uvicorn's logging configuration with the service's own loggers (``thermogel.*``:
    the warm-up's progress) written as uvicorn writes its own ("INFO:     ..."), at the
    level of ``--log-level``."""
    import copy

    from uvicorn.config import LOGGING_CONFIG

    config = copy.deepcopy(LOGGING_CONFIG)
    config["loggers"]["thermogel"] = {"handlers": ["default"], "propagate": False,
                                      "level": "DEBUG" if level == "trace" else level.upper()}
    return config


def warm_only() -> int:
    """Warm every kernel (a throw-away planner on a temporary cache for the front-model
    dose), then print the report."""
    import tempfile

    from api.warmup import warm_up
    from dosing import Planner

    from .common import print_json

    with tempfile.TemporaryDirectory() as tmp, Planner(cache_path=f"{tmp}/c.sqlite") as p:
        report = warm_up(p)
    print_json(report.to_dict())
    return 0


def run(args: argparse.Namespace) -> int:
    """Start uvicorn (blocks until stopped)."""
    from solver.errors import ParameterError

    if not (0 <= args.port <= 65535):
        raise ParameterError("--port", args.port, "0-65535")
    if args.workers < 1:
        raise ParameterError("--workers", args.workers, "an integer >= 1")
    if args.max_pending is not None and args.max_pending < 1:
        raise ParameterError("--max-pending", args.max_pending, "an integer >= 1")
    if args.max_body_bytes is not None and args.max_body_bytes < 1:
        raise ParameterError("--max-body-bytes", args.max_body_bytes, "an integer >= 1")
    if args.lease_seconds is not None and not 0.1 <= args.lease_seconds <= 3600:
        raise ParameterError("--lease-seconds", args.lease_seconds, "0.1-3600 s")
    if args.warmup_only:
        return warm_only()
    from api.auth import is_loopback
    from dosing.settings import settings

    if not is_loopback(args.host) and not (args.token or settings().api_token):
        raise ParameterError("--token", None, "a token (--token or $THERMOGEL_API_TOKEN)",
                             f"--host {args.host} is reachable beyond this machine, so the "
                             "service needs a token: clients then send 'Authorization: "
                             "Bearer <token>'; refusing to start without one")
    if not 0.1 <= args.timeout_keep_alive <= 600:
        raise ParameterError("--timeout-keep-alive", args.timeout_keep_alive, "0.1-600 s")
    if args.limit_concurrency is not None and args.limit_concurrency < 8:
        raise ParameterError("--limit-concurrency", args.limit_concurrency, "an integer >= 8")
    if args.max_connections_per_client is not None and args.max_connections_per_client < 1:
        raise ParameterError("--max-connections-per-client", args.max_connections_per_client,
                             "an integer >= 1")
    if args.read_timeout is not None and not 0.1 <= args.read_timeout <= 3600:
        raise ParameterError("--read-timeout", args.read_timeout, "0.1-3600 s")
    from .common import checked_cache

    checked_cache(args.cache)
    configure_env(args)
    import uvicorn

    from api.connections import uvicorn_options

    uvicorn.run("api.http:app_from_env", factory=True, host=args.host, port=args.port,
                workers=args.workers, log_level=args.log_level, timeout_graceful_shutdown=10,
                log_config=log_config(args.log_level),
                timeout_keep_alive=args.timeout_keep_alive,
                h11_max_incomplete_event_size=H11_MAX_HEADER_BYTES,
                **uvicorn_options(connection_limits(args)))
    return 0
