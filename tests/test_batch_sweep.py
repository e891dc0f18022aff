"""Sweeps with the batch's CV as an axis (issue 26): dosing.studies.sweep's size_cvs and
`thermogel sweep --size-cv` (the CV x dose design map: the spread a dose tolerates)."""

from __future__ import annotations

import pytest

from api.cli import main
from dosing import DoseRequest
from dosing.population.front import batch_answer
from dosing.studies.sweep import SweepGrid, run_sweep
from solver.errors import ParameterError


def test_cv_axis_rows_are_the_batch_answers() -> None:
    grid = SweepGrid(t_ends=[308.0], dry_radii_um=[50.0], doses=[0.5, 0.8],
                     size_cvs=[0.0, 0.2])
    assert grid.shape == (1, 1, 1, 2, 2) and grid.size == 4
    rows = run_sweep(grid).rows
    single = run_sweep(SweepGrid(t_ends=[308.0], dry_radii_um=[50.0], doses=[0.5, 0.8])).rows
    for row in rows:
        assert row["status"] == "answered"
        one = single[row["index"] // 2]
        if row["size_cv"] == 0.0:  # CV 0: the single bead's answer exactly
            assert row["time"] == one["time"] and row["batch_delay"] == 0.0
        else:
            ref = batch_answer(DoseRequest("ANB", 302.0, 308.0,
                                           dose_fraction=row["dose_fraction"],
                                           size_distribution={"cv": 0.2, "mean_um": 50.0}))
            assert row["time"] == ref.time and row["batch_delay"] == ref.delay
            assert row["time"] > one["time"]


@pytest.mark.parametrize("cvs,field", [([0.1, -0.1], "size_cvs[1]"), ([3.0], "size_cvs[0]"),
                                       ([], "size_cvs")])
def test_bad_cv_axis_names_the_entry(cvs: list, field: str) -> None:
    with pytest.raises(ParameterError) as exc:
        SweepGrid(t_ends=[308.0], dry_radii_um=[50.0], doses=[0.5], size_cvs=cvs)
    assert exc.value.field == field


def test_cli_sweep_draws_the_cv_map(tmp_path, capsys) -> None:
    png, csv = tmp_path / "m.png", tmp_path / "m.csv"
    argv = ["sweep", "--t-end", "308", "--dry-radius-um", "50", "--dose", "0.3,0.8",
            "--size-cv", "0:0.3:4", "--plot", str(png), "--csv", str(csv), "--no-progress"]
    assert main(argv) == 0
    assert png.stat().st_size > 1000
    text = csv.read_text().splitlines()
    assert len(text) == 1 + 8 and "size_cv [1]" in text[0] and "batch_delay [1]" in text[0]
    assert main([*argv[:-5], "--out", str(tmp_path / "m.nc")]) == 2
    assert "--out" in capsys.readouterr().err
