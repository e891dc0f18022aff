"""``thermogel simulate`` and ``thermogel plot``."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from api.cli import main


def test_simulate_json(capsys: pytest.CaptureFixture) -> None:
    assert main(["simulate", "--gel", "ANB", "--t-start", "302", "--t-end", "308",
                 "--until", "0.01", "--n", "40", "--every", "0.002", "--json", "--paper"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert len(out["t"]) == 6 and len(out["radius"]) == 6 and "phi" not in out
    assert all(x is None or x > 0 for x in out["front"])
    assert out["diagnostics"]["grid"] == "eulerian" and out["diagnostics"]["n"] == 40


def test_simulate_save_and_plot(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    run = tmp_path / "run.npz"
    assert main(["simulate", "--gel", "HHT", "--t-start", "304", "--protocol",
                 "0.01:308,0.01:304", "--grid", "lagrangian", "--n", "40", "--paper",
                 "--out", str(run)]) == 0
    text = capsys.readouterr().out
    assert "lagrangian" in text and run.exists()
    assert main(["plot", str(run), "--out", str(tmp_path / "fig")]) == 0
    assert (tmp_path / "fig" / "porosity_map.png").stat().st_size > 1000
    assert (tmp_path / "fig" / "porosity_profiles.png").exists()


def test_simulate_input_errors_exit_2(capsys: pytest.CaptureFixture) -> None:
    assert main(["simulate", "--t-start", "302", "--t-end", "308"]) == 2
    assert main(["simulate", "--t-start", "302", "--t-end", "308", "--until", "0.1",
                 "--n", "2"]) == 2
    assert "n=2" in capsys.readouterr().err


def test_simulate_solver_failure_exits_3(capsys: pytest.CaptureFixture) -> None:
    assert main(["simulate", "--t-start", "302", "--t-end", "308", "--until", "0.3",
                 "--n", "40", "--max-steps", "20", "--paper"]) == 3
    assert "budget" in capsys.readouterr().err


def test_simulate_defaults_to_the_well_posed_model(capsys: pytest.CaptureFixture) -> None:
    """The default run is the planner's truth without a bead size (moving grid, ell = 1e-4,
    N = 400); --paper is the paper's model; too few moving cells at that ell exit 2."""
    assert main(["simulate", "--gel", "ANB", "--t-start", "302", "--t-end", "308",
                 "--until", "0.002", "--every", "0.001", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)["diagnostics"]
    assert (d["grid"], d["n"], d["interfacial_length"]) == ("moving", 400, 1e-4)
    assert main(["simulate", "--t-start", "302", "--t-end", "308", "--until", "0.1",
                 "--n", "50"]) == 2
    assert "n=50" in capsys.readouterr().err
