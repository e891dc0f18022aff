"""The CLI refuses what the HTTP service refuses, with the same bounds (issue 15, D8), and a
bad ``--cache`` is exit 2 naming it (D7)."""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest

from api.cli import main

JUMP = ["--t-start", "302", "--t-end", "308"]


@pytest.mark.parametrize(("argv", "flag"), [
    (["dose", "--omega", "1e6", *JUMP, "--fraction", "0.5"], "--omega"),
    (["dose", "--beta", "50", *JUMP, "--fraction", "0.5"], "--beta"),
    (["dose", *JUMP, "--fraction", "1.5"], "--fraction"),
    (["dose", *JUMP, "--fraction", "0.5", "--viscosity", "20"], "--viscosity"),
    (["dose", *JUMP, "--fraction", "0.5", "--k0-m2", "1"], "--k0-m2"),
    (["dose", *JUMP, "--fraction", "0.5", "--dry-radius-um", "1e9"], "--dry-radius-um"),
    (["dose", "--t-start", "302", "--t-end", "400", "--fraction", "0.5"], "--t-end"),
    (["dose", *JUMP, "--fraction", "0.5", "--interfacial-length", "0.5"],  # SolverSettings'
     "settings.interfacial_length"),                                      # (moves with --n)
    (["schedule", *JUMP, "--doses", *["0.00001"] * 10_000, "--no-check", "--no-correct"],
     "--doses"),
    (["schedule", *JUMP, "--doses", "0.3", "0.3", "--tolerance", "0.5"], "--tolerance"),
])
def test_cli_uses_the_http_bounds(argv, flag, capsys) -> None:
    t0 = time.perf_counter()
    assert main(argv) == 2
    assert time.perf_counter() - t0 < 5.0  # refused up front, not after running
    err = capsys.readouterr().err
    assert f"thermogel: error: {flag}=" in err, err


def _bad_caches(tmp_path: Path) -> list[Path]:
    junk = tmp_path / "junk.sqlite"
    junk.write_bytes(b"not a database " * 100)
    out = [tmp_path, junk]
    if os.geteuid() != 0:  # root writes read-only files
        ro = tmp_path / "ro.sqlite"
        assert main(["dose", *JUMP, "--fraction", "0.5", "--cache", str(ro)]) == 0
        ro.chmod(0o444)
        out.append(ro)
    return out


@pytest.mark.parametrize("command", [["dose", *JUMP, "--fraction", "0.5"],
                                     ["schedule", *JUMP, "--doses", "0.3"],
                                     ["serve", "--port", "8199", "--no-warmup"]])
def test_bad_cache_path_is_exit_2_naming_cache(tmp_path: Path, command, capsys) -> None:
    for bad in _bad_caches(tmp_path):
        assert main([*command, "--cache", str(bad)]) == 2
        err = capsys.readouterr().err
        assert err.startswith("thermogel: error: --cache=") and "Traceback" not in err, err
