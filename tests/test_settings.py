"""One Settings object (dosing.settings: pydantic-settings, prefix THERMOGEL_) reads every
variable thermogel has read, under its old name; default folders from platformdirs."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

from api.connection_limits import ConnectionLimits
from api.http import app_from_env
from dosing.fits.gel_store import default_dir
from dosing.runs.cache import default_path
from dosing.settings import fields, settings
from solver.errors import ParameterError

ROOT = Path(__file__).resolve().parents[1]


def test_every_variable_the_code_names_is_a_setting() -> None:
    named = set()
    for folder in ("api", "dosing", "solver", "thermogel", "tests", "scripts", ".ci"):
        for p in (ROOT / folder).rglob("*"):
            if p.is_file() and p.suffix in (".py", "", ".sh"):
                named |= set(re.findall(r"THERMOGEL_[A-Z_]*[A-Z]", p.read_text(errors="ignore")))
    # the shell scripts' own: .ci/run's pytest-xdist workers, scripts/serve's extras to
    # install; the pool tests' call log (tests/pool_jobs.py)
    named -= {"THERMOGEL_TEST_WORKERS", "THERMOGEL_EXTRAS", "THERMOGEL_TEST_CALLS"}
    assert named <= set(fields()), named - set(fields())


def test_defaults_and_the_old_names(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    for name in fields():
        monkeypatch.delenv(name, raising=False)
    from platformdirs import user_cache_path

    assert default_path() == user_cache_path("thermogel", appauthor=False) / "validations.sqlite"
    assert default_dir() == default_path().parent / "gels"
    monkeypatch.setenv("THERMOGEL_CACHE", str(tmp_path / "c.sqlite"))
    monkeypatch.setenv("THERMOGEL_GELS", "")  # empty: unset
    assert default_path() == tmp_path / "c.sqlite" and default_dir() == tmp_path / "gels"
    monkeypatch.setenv("THERMOGEL_MAX_CONNECTIONS_PER_CLIENT", "3")
    monkeypatch.setenv("THERMOGEL_READ_TIMEOUT", "2.5")
    assert ConnectionLimits.from_env() == ConnectionLimits(read_timeout=2.5, per_client=3)
    monkeypatch.setenv("THERMOGEL_ALLOWED_HOSTS", "a.example, b.example")
    monkeypatch.setenv("THERMOGEL_WARMUP", "0")
    s = settings()
    assert s.hosts == ["a.example", "b.example"] and s.warmup is False
    monkeypatch.setenv("THERMOGEL_MAX_BODY", "2048")
    monkeypatch.setenv("THERMOGEL_API_TOKEN", "secret")
    app = app_from_env()
    assert app.title == "thermogel planner"


def test_a_bad_value_names_its_variable(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("THERMOGEL_MAX_PENDING", "many")
    with pytest.raises(ParameterError) as e:
        settings()
    assert e.value.field == "THERMOGEL_MAX_PENDING"


def test_importing_dosing_reads_no_settings() -> None:
    code = ("import sys, dosing, dosing.runs.cache, dosing.fits.gel_store; "
            "print('pydantic_settings' in sys.modules)")
    out = subprocess.run([__import__("sys").executable, "-c", code], capture_output=True,
                         text=True, cwd=ROOT, check=True).stdout.strip()
    assert out == "False"
