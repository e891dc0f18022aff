"""``thermogel sweep``: axes from lists and ranges, the tables and heat maps written, bad
axes as exit code 2 naming the option, failing points as rows (issue 17)."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from api.cli import main
from api.commands.sweep import parse_axis
from dosing.studies.sweep import SweepGrid, run_sweep


def test_axes_from_lists_and_ranges() -> None:
    assert parse_axis("--dose", "0.1, 0.5,0.9") == [0.1, 0.5, 0.9]
    assert parse_axis("--t-end", "308:310:3") == [308.0, 309.0, 310.0]
    assert parse_axis("--dry-radius-um", "10:1000:3:log") == pytest.approx([10, 100, 1000])


@pytest.mark.parametrize("text", ["308:a:3", "308:310", "1:10:3:lin", "0:10:3:log", "1:2:0"])
def test_a_bad_axis_is_exit_2_naming_the_option(text: str, capsys) -> None:
    rc = main(["sweep", "--t-end", text, "--dry-radius-um", "50", "--dose", "0.5"])
    assert rc == 2 and "--t-end=" in capsys.readouterr().err


def test_sweep_writes_the_tables_and_the_plot(tmp_path: Path, capsys) -> None:
    out = {k: tmp_path / f"s.{k}" for k in ("csv", "json", "png")}
    rc = main(["sweep", "--t-end", "305,308,400", "--dry-radius-um", "20:50:2", "--dose",
               "0.3,1.2", "--csv", str(out["csv"]), "--json", str(out["json"]), "--plot",
               str(out["png"]), "--no-progress"])
    assert rc == 0
    assert "12 points" in capsys.readouterr().err
    want = run_sweep(SweepGrid(t_ends=[305.0, 308.0, 400.0], dry_radii_um=[20.0, 50.0],
                               doses=[0.3, 1.2]))
    data = json.loads(out["json"].read_text())
    assert data["rows"] == want.rows
    rows = list(csv.DictReader(out["csv"].open()))
    assert [r["status"] for r in rows] == [r["status"] for r in want.rows]
    assert {r["field"] for r in rows if r["status"] == "error"} == {"dose_fraction", "t_end"}
    assert out["png"].read_bytes()[:4] == b"\x89PNG"


def test_vary_a_gel_parameter(tmp_path: Path) -> None:
    out = tmp_path / "s.json"
    rc = main(["sweep", "--gel", "ANB", "--gel", "HHT", "--vary", "omega=50,200", "--t-end",
               "308", "--dry-radius-um", "50", "--dose", "0.5", "--json", str(out),
               "--no-progress"])
    assert rc == 0
    rows = json.loads(out.read_text())["rows"]
    assert [r["gel"] for r in rows] == ["ANB omega=50", "ANB omega=200", "HHT omega=50",
                                        "HHT omega=200"]
    assert main(["sweep", "--vary", "omega", "--t-end", "308", "--dry-radius-um", "50",
                 "--dose", "0.5"]) == 2


def test_validate_waits_and_fills_the_truth(tmp_path: Path,
                                            monkeypatch: pytest.MonkeyPatch) -> None:
    """--validate needs-full: the smooth jump's points are validated (here on the fake full
    solver, in this process: the command's planner is built with it) and the table carries
    the truth's time."""
    import functools

    from api_support import fake_full_solver

    import dosing

    out = tmp_path / "s.json"
    with fake_full_solver() as fake:
        monkeypatch.setattr(dosing, "Planner", functools.partial(dosing.Planner, solver=fake))
        rc = main(["sweep", "--t-end", "305,308", "--dry-radius-um", "50", "--dose", "0.3",
                   "--validate", "needs-full", "--cache", str(tmp_path / "c.sqlite"),
                   "--json", str(out), "--no-progress"])
    assert rc == 0
    smooth, front = json.loads(out.read_text())["rows"]
    assert smooth["status"] == "needs-full" and smooth["validation_status"] == "done"
    assert smooth["time"] == smooth["truth_time"] and smooth["seconds"] > 0
    assert front["status"] == "answered" and front["validation_id"] is None
