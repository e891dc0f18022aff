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

from .cache import default_path
from .scenario import code_version

ENV = "THERMOGEL_GELS"
SCHEMA = 1
NAME_RE = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,63}\Z")  # match() from the start; \Z:
# no trailing newline slips through ('$' would accept "abc\n")
RESERVED = "custom"  # the name of a gel given by parameters
NAMES_SHOWN = 5  # stored names an unknown gel's error lists


def default_dir() -> Path:
    """$THERMOGEL_GELS, else gels/ beside the validation cache."""
    env = os.environ.get(ENV)
    return Path(env).expanduser() if env else default_path().parent / "gels"


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
