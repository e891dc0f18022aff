"""The store of fitted gels: one JSON file per name (data, fit report, code version).

Directory: ``$THERMOGEL_GELS``, else ``gels/`` beside the validation cache
($THERMOGEL_CACHE's folder, default ~/.cache/thermogel/gels/).  A stored name is usable
wherever a preset name is (``dosing.request.resolve_gel``).
"""

from __future__ import annotations

import json
import os
import re
import tempfile
import time
from pathlib import Path
from typing import Any

from solver.errors import ParameterError
from solver.gel import PRESETS, Gel

from ..runs.scenario import code_version

ENV = "THERMOGEL_GELS"
SCHEMA = 1
NAME_RE = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,63}\Z")  # match() from the start; \Z:
# no trailing newline slips through ('$' would accept "abc\n")
RESERVED = "custom"  # the name of a gel given by parameters
NAMES_SHOWN = 5  # stored names an unknown gel's error lists


def default_dir() -> Path:
    """$THERMOGEL_GELS, else gels/ beside the validation cache (dosing.settings)."""
    from ..settings import settings

    return settings().gels_dir


def check_name(name: str) -> str:
    """A storable gel name: 1-64 letters, digits, '_', '.', '-' (no control character, not
    empty), not a preset's name nor 'custom' in any case."""
    if not isinstance(name, str) or not NAME_RE.match(name):
        raise ParameterError("name", name, "1-64 characters: letters, digits, '_', '.', '-' "
                             "(starting with a letter or digit)")
    if name.upper() in PRESETS or name.lower() == RESERVED:
        raise ParameterError("name", name, "a name other than the presets "
                             + ", ".join(sorted(PRESETS)) + " and 'custom' (in any case)")
    return name


def _some(names: list[str], empty: str) -> str:
    """At most NAMES_SHOWN names, and how many more (an error never lists the whole store)."""
    if not names:
        return empty
    more = len(names) - NAMES_SHOWN
    return ", ".join(names[:NAMES_SHOWN]) + (f" and {more} more" if more > 0 else "")


def _code_version() -> str:
    try:
        from importlib.metadata import version

        pkg = version("thermogel")
    except Exception:
        pkg = "unknown"
    return f"thermogel {pkg}, solver {code_version()}"


class GelStore:
    """Fitted gels as JSON files in a directory (module doc)."""

    def __init__(self, directory: str | os.PathLike[str] | None = None) -> None:
        self.dir = Path(directory).expanduser() if directory is not None else default_dir()

    def path(self, name: str) -> Path:
        """The file of one name."""
        return self.dir / f"{check_name(name)}.json"

    def save(self, name: str, gel: Gel, swelling: dict[str, Any] | None = None,
             kinetics: dict[str, Any] | None = None) -> Path:
        """Write (or update) a fitted gel; ``swelling``/``kinetics`` are {data, fit} records.
        Updating keeps the part not given (a kinetics fit adds to a swelling fit)."""
        path = self.path(name)
        old = self.load_record(name) if path.exists() else {}
        record = {"schema": SCHEMA, "name": name,
                  "gel": {**gel.to_dict(), "name": name},
                  "swelling": swelling if swelling is not None else old.get("swelling"),
                  "kinetics": kinetics if kinetics is not None else old.get("kinetics"),
                  "code_version": _code_version(), "created": time.time()}
        record["timescale"] = timescale_of(record)
        record["parameters"] = fitted_parameters(record)
        self.dir.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=self.dir, suffix=".tmp")
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            json.dump(_strict(record), fh, indent=1)
        os.replace(tmp, path)
        return path

    def load_record(self, name: str) -> dict[str, Any]:
        """The stored record; ParameterError naming the stored gels when it is missing."""
        path = self.path(name)
        try:
            return json.loads(path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise ParameterError("gel", name, "a preset (" + ", ".join(sorted(PRESETS))
                                 + ") or a stored fitted gel ("
                                 + _some(self.names(), "none stored yet") + ")"
                                 ) from None
        except (OSError, json.JSONDecodeError) as exc:
            raise ParameterError("gel", name, "a readable stored gel", str(exc)) from exc

    def load(self, name: str) -> Gel:
        """The stored gel."""
        return Gel.from_dict(self.load_record(name)["gel"])

    def names(self) -> list[str]:
        """Every stored name."""
        if not self.dir.is_dir():
            return []
        return sorted(p.stem for p in self.dir.glob("*.json") if NAME_RE.match(p.stem))

    def summaries(self) -> list[dict[str, Any]]:
        """Every stored gel as listed by GET /v1/gels: name, parameters (eq. FloryParam),
        every fitted parameter with its interval, and the timescale a kinetics fit pinned
        (None: uncalibrated).  Unreadable files are skipped."""
        out = []
        for name in self.names():
            try:
                rec = self.load_record(name)
                gel = Gel.from_dict(rec["gel"])
            except (ParameterError, KeyError, TypeError):
                continue
            out.append({"name": name, "gel": gel.to_dict(),
                        "fitted": {k: bool(rec.get(k)) for k in ("swelling", "kinetics")},
                        "parameters": rec.get("parameters") or fitted_parameters(rec),
                        "timescale": rec.get("timescale") or timescale_of(rec),
                        "code_version": rec.get("code_version")})
        return out

    def delete(self, name: str) -> bool:
        """Remove one stored gel; False when there was none."""
        try:
            self.path(name).unlink()
            return True
        except FileNotFoundError:
            return False


def lookup(name: str, store: GelStore | None = None) -> Gel:
    """A preset (case-insensitive) or a stored fitted gel by name; ParameterError (field
    ``gel``) listing both when neither exists."""
    if name.upper() in PRESETS:
        return PRESETS[name.upper()]
    st = store or GelStore()
    if NAME_RE.match(name) and st.path(name).exists():
        return st.load(name)
    raise ParameterError("gel", name, "one of " + ", ".join(sorted(PRESETS))
                         + " or a stored fitted gel ("
                         + _some(st.names(), "none stored yet: thermogel fit ... --save NAME")
                         + ")")


def record_for(gel: Gel, store: GelStore | None = None) -> dict[str, Any] | None:
    """The stored record of a gel that came from the store (same name and parameters)."""
    if gel.name.upper() in PRESETS or gel.name == "custom" or not NAME_RE.match(gel.name):
        return None
    st = store or GelStore()
    if not st.path(gel.name).exists():
        return None
    try:
        rec = st.load_record(gel.name)
        stored = Gel.from_dict(rec["gel"])
    except (ParameterError, KeyError, TypeError):
        return None
    return rec if stored.key() == gel.key() else None


def timescale_of(record: dict[str, Any]) -> dict[str, Any] | None:
    """The effective diffusivity a stored kinetics fit pinned
    (``dosing.fits.gel.diffusivity_report`` fields), or None (no kinetics fit, or one without a
    bead size)."""
    fit = (record.get("kinetics") or {}).get("fit") or {}
    if fit.get("diffusivity_m2_s") is None:
        return None
    return {k: fit.get(k) for k in ("diffusivity_m2_s", "diffusivity_cm2_s",
                                    "diffusivity_interval_cm2_s", "diffusivity_t_k",
                                    "tau_s", "tau_interval_s", "dry_radius_um", "model")}


def fitted_parameters(record: dict[str, Any]) -> dict[str, Any]:
    """Every fitted parameter of a stored gel, with its 95% interval: the swelling fit's
    (Omega, A0, B0, A1, B1, scale), the kinetics fit's (tau, its size scale, beta) and the
    effective diffusivity the kinetics fit pins."""
    out: dict[str, Any] = {}
    for part in ("swelling", "kinetics"):
        fit = (record.get(part) or {}).get("fit") or {}
        for k, v in (fit.get("parameters") or {}).items():
            out[f"{part}.{k}"] = {"value": v, "interval": (fit.get("intervals") or {}).get(k)}
    ts = record.get("timescale") or timescale_of(record)
    if ts:
        out["diffusivity_cm2_s"] = {"value": ts["diffusivity_cm2_s"],
                                    "interval": ts["diffusivity_interval_cm2_s"],
                                    "t_k": ts["diffusivity_t_k"]}
    return out


def calibrated_constants(gel: Gel, constants: Any, store: GelStore | None = None) -> Any:
    """The request's constants with D pinned by the gel's stored kinetics fit (when it has
    one and the request does not give D itself): tau then follows the fit, whatever k0,
    eta and Omega_p say (eq. timescale)."""
    if getattr(constants, "calibrated", True):
        return constants
    rec = record_for(gel, store)
    ts = timescale_of(rec) if rec else None
    if not ts:
        return constants
    from dataclasses import replace

    return replace(constants, diffusivity_m2_s=float(ts["diffusivity_m2_s"]),
                   diffusivity_t_k=float(ts["diffusivity_t_k"]),
                   diffusivity_source=f"kinetics fit of stored gel '{gel.name}'")


def diffusivity_interval(gel: Gel, store: GelStore | None = None
                         ) -> tuple[float, float] | None:
    """The stored kinetics fit's 95% interval of D in cm^2/s (at its own temperature)."""
    rec = record_for(gel, store)
    ts = timescale_of(rec) if rec else None
    iv = ts.get("diffusivity_interval_cm2_s") if ts else None
    return None if not iv else (float(iv[0]), float(iv[1]))


def _strict(obj: Any) -> Any:
    """Non-finite floats to None (strict JSON)."""
    import math

    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _strict(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_strict(v) for v in obj]
    if hasattr(obj, "tolist"):
        return _strict(obj.tolist())
    return obj
