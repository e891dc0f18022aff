"""Readers that accept what labs write (issue 27, item 4)."""

from __future__ import annotations

import json
import time
from importlib.resources import files

import numpy as np
import pytest

from api.cli import main
from dosing.fits.csv_tables import MAX_BYTES
from dosing.fits.gel import read_kinetics_csv, read_swelling_csv
from solver.errors import ParameterError


@pytest.mark.parametrize("text, kind, t0, y0", [
    ("temperature_C;diameter_um\n25,0;120,5\n30;110\n", "diameter", 298.15, 120.5),
    ("T (degC),d (mm)\n25,1.2\n40,0.8\n", "diameter", 298.15, 1200.0),
    ("Temperature [K]\tRadius (a.u.)\n300\t3\n310\t2\n", "radius", 300.0, 3.0),
    ("temperature/°C,radius/um\n25,3\n35,2\n", "radius", 298.15, 3.0),
    ("300,1.2\n310,0.8\n", "radius", 300.0, 1.2),           # no header, kelvin
    ("25;1,2\n40;0,8\n", "radius", 298.15, 1.2),            # no header, degC, decimal comma
    ("\ufefftemperature_K,volume_ratio,weight\n300,8,1\n310,1.5,2\n", "volume_ratio", 300.0, 8.0),
])
def test_lab_tables_are_read(text, kind, t0, y0) -> None:
    d = read_swelling_csv(text)
    assert d.kind == kind
    assert d.temperature[0] == pytest.approx(t0)
    assert d.size[0] == pytest.approx(y0)


def test_kinetics_time_units() -> None:
    d = read_kinetics_csv("t [min];diameter_um\n0;200\n1,5;180\n")
    assert d.time.tolist() == [0.0, 90.0] and d.kind == "diameter"
    assert read_kinetics_csv("time_h,radius\n0,2\n2,1\n").time[1] == 7200.0


@pytest.mark.parametrize("text, where", [
    ("temperature_C;diameter_um\n25;1\n30;x\n", "line 3, column 2 (diameter_um)"),
    ("temperature_C;foo\n25;1\n", "line 1, column 2"),
    ("# note\ntemperature_K,radius\n300,1\n310\n", "line 4"),
    ("temperature_K,radius,diameter\n300,1,2\n", "line 1"),
    ("temperature (fortnights),radius\n300,1\n", "column 1"),
])
def test_bad_tables_name_line_and_column(text, where) -> None:
    with pytest.raises(ParameterError) as exc:
        read_swelling_csv(text)
    assert where in str(exc.value)


def test_a_32_mb_file_is_refused_before_it_is_read(tmp_path) -> None:
    big = tmp_path / "big.csv"
    with big.open("wb") as fh:  # sparse: 32 MB of nothing, cheap to make, slow to read
        fh.write(b"temperature_K,radius\n")
        fh.truncate(32 * 1024 * 1024)
    assert big.stat().st_size > MAX_BYTES
    t = time.perf_counter()
    with pytest.raises(ParameterError, match="refused before reading"):
        read_swelling_csv(big)
    assert time.perf_counter() - t < 0.5  # from its size, not by reading 32 MB


def test_shipped_examples_and_templates_fit_without_editing(tmp_path, monkeypatch,
                                                            capsys) -> None:
    """The shipped lab-style example (degC, diameter in um, semicolons, decimal commas; a
    synthetic HHT gel) fits as it is, and the report says how the file was read."""
    monkeypatch.setenv("THERMOGEL_GELS", str(tmp_path / "gels"))
    data = files("dosing") / "data"
    for name in ("swelling_template.csv", "kinetics_template.csv", "release_template.csv"):
        assert (data / name).is_file()
    ex = str(data / "example_swelling.csv")
    assert "SYNTHETIC" in (data / "example_swelling.csv").read_text()
    assert main(["fit", "swelling", ex, "--json", "--fix", "omega=720"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["read"]["units"] == {"temperature": "degC", "diameter": "um"}
    assert rep["success"] and rep["n_points"] == 35
    # the dry diameter 82.54 um comes back
    lo, hi = rep["intervals"]["scale"]
    assert lo < 82.54 < hi
    d = read_kinetics_csv(data / "example_kinetics.csv")
    assert d.kind == "diameter" and np.all(np.diff(d.time) > 0)
