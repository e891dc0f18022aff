"""The installed thermogel version, and the version every answer carries
(dosing.provenance: package, code and solver versions)."""

from __future__ import annotations

from dosing.provenance import package_version, version_info

__all__ = ["package_version", "version_info"]
