"""The installed thermogel version."""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version


def package_version() -> str:
    """thermogel's version, or 'unknown' when run from an uninstalled tree."""
    try:
        return version("thermogel")
    except PackageNotFoundError:
        return "unknown"
