"""``thermogel front``: JSON series and clear errors."""

import json

import pytest

from api.cli import main


def test_front_json(capsys) -> None:
    assert main(["front", "--gel", "HHT", "--t-start", "304", "--t-end", "308",
                 "--every", "0.05", "--json", "--paper"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["model"] == "front-leading" and out["start"] == "equilibrium"
    assert len(out["t"]) == len(out["radius"]) == len(out["front"]) == 9
    assert out["front"][-1] == 0.0 and out["t"][1] == 0.05


def test_front_sharp_is_earlier_than_the_papers(capsys) -> None:
    """Sharp-interface front condition: ANB 80 % (a = 1.4750) at 0.0762 against the paper's
    model's 0.0950 (docs/interfacial.md sec. 8)."""
    times = {}
    for extra in (["--paper"], ["--sharp"]):
        assert main(["front", "--t-start", "302", "--t-end", "308", "--target-radius", "1.4750",
                     "--json", *extra]) == 0
        out = json.loads(capsys.readouterr().out)
        times[out["model"]] = out["t"][-1]
    assert times["front-sharp"] == pytest.approx(0.0762, abs=2e-4)
    assert times["front-leading"] == pytest.approx(0.0950, abs=2e-4)
    assert main(["front", "--t-start", "302", "--t-end", "308", "--paper-start",
                 "--start-from-full", "0.01"]) == 2
    assert "paper_start" in capsys.readouterr().err


def test_front_defaults_to_the_well_posed_model(capsys) -> None:
    """One set of defaults: ``front`` answers with the planner's model (front-sharp)."""
    assert main(["front", "--t-start", "302", "--t-end", "308", "--target-radius", "1.4750",
                 "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["model"] == "front-sharp"


def test_front_text_and_not_applicable(capsys) -> None:
    assert main(["front", "--t-start", "302", "--t-end", "308", "--target-radius", "1.47",
                 "--paper"]) == 0
    assert "front-leading" in capsys.readouterr().out
    assert main(["front", "--t-start", "308", "--t-end", "302"]) == 2
    assert "not applicable" in capsys.readouterr().err


@pytest.mark.slow
def test_front_started_from_the_full_solver(capsys) -> None:
    assert main(["front", "--gel", "HHT", "--t-start", "304", "--t-end", "308",
                 "--start-from-full", "0.01", "--paper", "--paper-start", "--target-radius",
                 "1.67",
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["start"] == "full@0.01" and out["t"][0] == 0.01
    assert out["t"][-1] == pytest.approx(0.123, rel=0.04)  # the paper's HHT 80% dose


def test_front_sharp_text(capsys) -> None:
    """The sharp model's text output names the radius at which its front reaches the centre."""
    assert main(["front", "--gel", "HHT", "--t-start", "304", "--t-end", "308", "--sharp"]) == 0
    out = capsys.readouterr().out
    assert "front-sharp" in out and "with radius 1.1" in out


def test_cli_piped_into_head_exits_quietly() -> None:
    """A reader that closes the pipe early (``| head -c 10``) gives no traceback."""
    import subprocess
    import sys

    cmd = (f"{sys.executable} -m api.cli front --gel HHT --t-start 304 --t-end 308 --sharp "
           "--json --every 0.0001 | head -c 10")
    done = subprocess.run(["bash", "-o", "pipefail", "-c", cmd], capture_output=True,
                          text=True, timeout=120)
    assert done.stdout.startswith('{"gel"')
    assert "Traceback" not in done.stderr and "BrokenPipe" not in done.stderr
