"""The equilibrium, classify and phase-map commands (issue 2)."""

import json
from pathlib import Path

import pytest

from api.cli import main


def _json(capsys: pytest.CaptureFixture[str], argv: list[str]) -> dict:
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def test_equilibrium_json(capsys: pytest.CaptureFixture[str]) -> None:
    out = _json(capsys, ["equilibrium", "--gel", "ANB", "--temperature", "305", "--json"])
    assert [e["stable"] for e in out["equilibria"]] == [True, False, True]
    assert {"stretch", "porosity", "stable"} <= set(out["equilibria"][0])
    assert [round(t, 1) for t in out["folds"]] == [304.7, 305.8]


def test_classify_json(capsys: pytest.CaptureFixture[str]) -> None:
    out = _json(capsys, ["classify", "--gel", "ANB", "--t-start", "302", "--t-end", "308",
                         "--json"])
    assert (out["direction"], out["behaviour"]) == ("shrink", "front")


def test_custom_gel_and_bad_input(capsys: pytest.CaptureFixture[str]) -> None:
    out = _json(capsys, ["equilibrium", "--omega", "720", "--a0", "-62.22", "--b0", "0.2047",
                         "--a1", "-58.28", "--b1", "0.19044", "--temperature", "308", "--json"])
    assert round(out["equilibria"][0]["stretch"], 2) == 1.16
    assert main(["equilibrium", "--omega", "-1", "--temperature", "308"]) == 2
    assert "omega" in capsys.readouterr().err


def test_phase_map_draws(tmp_path: Path) -> None:
    out = tmp_path / "map.png"
    assert main(["phase-map", "--gel", "HHT", "--out", str(out)]) == 0
    assert out.stat().st_size > 10_000
