"""Size tables are read as their header says (issue 37): dry or swollen, radius or diameter,
the unit; a header naming neither radius nor diameter is refused naming the column; the
answer states what it read and what it became."""

from __future__ import annotations

import json

import pytest

from api.cli import main
from dosing.population.sizes import read_header, read_sizes_csv
from solver.equilibrium import equilibrium
from solver.errors import ParameterError
from solver.gel import ANB

DRY = [40.0, 50.0, 60.0]
A0 = equilibrium(ANB, 302.0, "swollen").stretch


def _tables() -> dict[str, str]:
    col = lambda head, xs: head + "\n" + "".join(f"{x!r}\n" for x in xs)  # noqa: E731
    return {
        "dry radius (um)": col("dry radius (um)", DRY),
        "radius_um": col("radius_um", DRY),
        "dry diameter (um)": col("dry diameter (um)", [2 * r for r in DRY]),
        "swollen diameter (um)": col("swollen diameter (um)", [2 * r * A0 for r in DRY]),
        "Swollen radius [mm]": col("Swollen radius [mm]", [r * A0 / 1000 for r in DRY]),
        "d_nm": col("d_nm", [2000 * r for r in DRY]),
    }


@pytest.mark.parametrize(("head", "state", "measure", "unit"), [
    ("dry radius (um)", "dry", "radius", "um"), ("radius_um", None, "radius", "um"),
    ("dry diameter (um)", "dry", "diameter", "um"),
    ("swollen diameter (um)", "swollen", "diameter", "um"),
    ("Diameter (mm)", None, "diameter", "mm"), ("r_nm", None, "radius", "nm"),
    ("bead size: swollen radius [µm]", "swollen", "radius", "µm"),
])
def test_headers_say_state_measure_and_unit(head, state, measure, unit) -> None:
    h = read_header(head)
    assert (h.state, h.measure, h.unit) == (state, measure, unit)


@pytest.mark.parametrize("head", ["size (um)", "value", "radius diameter", "dry swollen radius",
                                  "colour radius"])
def test_a_header_naming_no_measure_is_refused_naming_the_column(head) -> None:
    with pytest.raises(ParameterError) as e:
        read_sizes_csv(f"{head}\n40\n50\n")
    assert f"column '{head}'" in e.value.field
    assert "radius" in str(e.value) and "diameter" in str(e.value) and "swollen" in str(e.value)


def test_a_state_against_the_request_is_refused() -> None:
    with pytest.raises(ParameterError) as e:
        read_sizes_csv("dry radius (um)\n40\n", state="swollen")
    assert "dry radius (um)" in e.value.field


def test_the_same_beads_answer_the_same_seconds_whatever_the_header(tmp_path, capsys) -> None:
    seconds, described = {}, {}
    for head, text in _tables().items():
        p = tmp_path / f"{abs(hash(head))}.csv"
        p.write_text(text)
        assert main(["dose", "--gel", "ANB", "--t-start", "302", "--t-end", "308",
                     "--fraction", "0.8", "--sizes", str(p), "--json"]) == 0
        out = json.loads(capsys.readouterr().out)
        seconds[head] = out["seconds"]
        described[head] = out["batch"]["description"]
    ref = seconds["dry radius (um)"]
    for head, s in seconds.items():
        assert s == pytest.approx(ref, rel=1e-6), (head, s, ref)
    text = described["swollen diameter (um)"]
    assert "3 swollen diameters (um)" in text and "'swollen diameter (um)'" in text
    assert "302 K" in text and "converted to dry radii 40-60 um" in text
    assert "3 dry radii (um)" in described["dry radius (um)"]


def test_the_cli_refuses_an_unknown_header_naming_the_column(tmp_path, capsys) -> None:
    p = tmp_path / "s.csv"
    p.write_text("size (um)\n40\n50\n")
    assert main(["dose", "--gel", "ANB", "--t-start", "302", "--t-end", "308",
                 "--fraction", "0.8", "--sizes", str(p)]) == 2
    assert "column 'size (um)'" in capsys.readouterr().err
