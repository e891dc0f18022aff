"""`thermogel dose` / `thermogel schedule` and the README's Python example (issue 5)."""

import json
import re
from pathlib import Path

import pytest

from api.cli import main
from dosing.units import timescale

README = Path(__file__).resolve().parents[1] / "README.md"


def _json(capsys: pytest.CaptureFixture, argv: list[str]) -> dict:
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def test_dose_json_front_model(capsys, tmp_path: Path) -> None:
    out = _json(capsys, ["dose", "--gel", "ANB", "--t-start", "302", "--t-end", "308",
                         "--fraction", "0.8", "--dry-radius-um", "50", "--json",
                         "--validation-method", "ladder", "--cache", str(tmp_path / "c.sqlite")])
    assert out["model"] == "front-sharp" and out["validation"] is None
    assert out["interfacial_length"] == 0.005 and "limit ell -> 0" in out["truth"]
    assert out["final_radius"] == pytest.approx(1.4750, abs=1e-4)
    assert out["seconds"] == pytest.approx(out["time"] * timescale(50, 308, omega=100.0).seconds,
                                            rel=1e-12)
    assert "eta Omega_p R^2" in out["timescale_formula"]


def test_dose_text_and_errors(capsys, tmp_path: Path) -> None:
    assert main(["dose", "--gel", "ANB", "--t-start", "302", "--t-end", "308", "--fraction",
                 "0.5", "--swollen-radius-um", "100", "--viscosity", "water",
                 "--validation-method", "ladder", "--cache", str(tmp_path / "c.sqlite"),
                 "--explain"]) == 0
    text = capsys.readouterr().out
    lead = text.splitlines()[:3]  # issue 36: the envelope, the dominant part, how to pin it
    assert lead[0].startswith("50% of the bead's fluid after ") and " s (point " in lead[0]
    assert lead[1].startswith("dominant uncertainty: timescale x")
    assert lead[2].startswith("to pin it: ") and "fit kinetics" in lead[2]
    assert "front-sharp model: heat for t =" in text and " s\n" in text and "tau =" in text
    assert "truth: the regularized model's sharp-interface limit" in text
    assert main(["dose", "--gel", "ANB", "--t-start", "302", "--t-end", "308",
                 "--fraction", "1.5", "--cache", str(tmp_path / "c.sqlite")]) == 2
    assert "dose_fraction" in capsys.readouterr().err
    assert main(["dose", "--gel", "ANB", "--t-start", "308", "--t-end", "302",
                 "--fraction", "0.5", "--cache", str(tmp_path / "c.sqlite")]) == 2
    assert "t_end" in capsys.readouterr().err
    assert main(["dose", "--gel", "XYZ", "--t-start", "302", "--t-end", "308",
                 "--fraction", "0.5", "--cache", str(tmp_path / "c.sqlite")]) == 2
    assert "gel" in capsys.readouterr().err
    assert main(["dose", "--gel", "ANB", "--t-start", "302", "--t-end", "308", "--fraction",
                 "0.5", "--interfacial-length", "0.001", "--validation-method", "ladder",
                 "--cache", str(tmp_path / "c.sqlite")]) == 2
    assert "settings.interfacial_length" in capsys.readouterr().err


def test_dose_paper_model_is_selectable(capsys, tmp_path: Path) -> None:
    out = _json(capsys, ["dose", "--gel", "ANB", "--t-start", "302", "--t-end", "308",
                         "--fraction", "0.8", "--interfacial-length", "0", "--json",
                         "--cache", str(tmp_path / "c.sqlite")])
    assert out["model"] == "front" and out["interfacial_length"] == 0.0
    assert out["time"] == pytest.approx(0.0950, abs=1e-4)  # issue 5 (the paper: 0.092)


def test_schedule_hold_only_json(capsys, tmp_path: Path) -> None:
    out = _json(capsys, ["schedule", "--gel", "ANB", "--t-start", "302", "--t-end", "308",
                         "--doses", "0.3", "0.3", "0.3", "--rests", "0.5", "0.5",
                         "--no-check", "--no-correct", "--json",
                         "--cache", str(tmp_path / "c.sqlite")])
    assert out["model"] == "front-sharp" and out["protocol_check"] is None
    ends = [h["end"] for h in out["hold"]]
    assert ends == sorted(ends) and out["hold"][0]["start"] == 0.0


def test_readme_python_example_runs(tmp_path: Path, monkeypatch, capsys) -> None:
    text = README.read_text()
    section = text.split("## Python use", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    monkeypatch.setenv("THERMOGEL_CACHE", str(tmp_path / "readme.sqlite"))
    exec(compile(code, "README.md", "exec"), {})
    out = capsys.readouterr().out
    assert out.startswith("front-sharp t = 0.07") and "tau = eta Omega_p" in out


def test_validation_plot_from_the_answer_alone(tmp_path: Path, capsys) -> None:
    from api.plots.validation import draw_validation

    runs = [{"grid": "lagrangian", "n": n, "interfacial_length": e, "time": t,
             "nucleation_time": d} for n, e, t, d in ((400, 0.01, 0.230, 0.173),
                                                     (800, 0.005, 0.147, 0.082),
                                                     (1600, 0.0025, 0.105, 0.036))]
    answer = {"model": "front-sharp", "time": 0.0724, "dose_fraction": 0.8,
              "error_estimate": 0.135,
              "validation": {"runs": runs, "limit": {"time": 0.0727, "error": 0.0093}}}
    out = draw_validation(answer, tmp_path / "v" / "val.png")
    assert out.stat().st_size > 10_000 and out.read_bytes()[:4] == b"\x89PNG"
    with pytest.raises(ValueError, match="no regularized validation"):
        draw_validation({**answer, "validation": None}, tmp_path / "x.png")
    assert main(["dose", "--gel", "ANB", "--t-start", "302", "--t-end", "308", "--fraction",
                 "0.5", "--plot", str(tmp_path / "y.png"),
                 "--cache", str(tmp_path / "c.sqlite")]) == 2
    assert "plot" in capsys.readouterr().err
    # a drug answer (one bead or a batch) has no validation figure: refused before any run
    for batch in ([], ["--size-cv", "0.2"]):
        assert main(["dose", "--gel", "ANB", "--t-start", "302", "--t-end", "308",
                     "--fraction", "0.5", "--dry-radius-um", "50", "--drug-diffusivity-cm2-s",
                     "1e-6", *batch, "--validate", "--plot", str(tmp_path / "z.png"),
                     "--cache", str(tmp_path / "c.sqlite")]) == 2
        assert "plot" in capsys.readouterr().err and not (tmp_path / "z.png").exists()


def test_direct_validation_plot_from_the_answer_alone(tmp_path: Path) -> None:
    """Issue 12: a direct validation (no ladder, no limit) is drawn too."""
    from api.plots.validation import draw_validation

    unc = {"interfacial_lengths": [4e-5, 1.6e-4], "interfacial_length_times": [0.02046, 0.02047],
           "delayed_transition_time": 0.0345, "delayed_transition_ratio": 1.69}
    answer = {"model": "front-sharp", "time": 0.0201, "dose_fraction": 0.5,
              "error_estimate": 0.018,
              "validation": {"method": "direct", "interfacial_length": 8e-5, "time": 0.02045,
                             "error": 4e-4, "limit": None, "uncertainty": unc, "runs": []}}
    out = draw_validation(answer, tmp_path / "direct.png")
    assert out.stat().st_size > 10_000 and out.read_bytes()[:4] == b"\x89PNG"
    paper = {**answer, "validation": {**answer["validation"], "interfacial_length": 0.0}}
    with pytest.raises(ValueError, match="no regularized validation"):
        draw_validation(paper, tmp_path / "paper.png")


def test_one_printer_for_fluid_and_drug_doses(capsys, tmp_path: Path) -> None:
    """`thermogel dose` prints a drug answer (the fluid carrying it: D0 = 0) with the fluid
    dose's printer: the same model line, the truth, then the drug's payload."""
    jump = ["dose", "--gel", "ANB", "--t-start", "302", "--t-end", "308", "--fraction", "0.5",
            "--dry-radius-um", "50", "--cache", str(tmp_path / "c.sqlite")]
    def point(text: str) -> list[str]:  # the point answer, after the envelope's lead
        lines = text.splitlines()
        return lines[lines.index("the point answer:") + 1:]

    assert main(jump) == 0
    fluid = point(capsys.readouterr().out)
    assert main([*jump, "--drug-diffusivity-cm2-s", "0", "--load-ug", "2"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("50% of the bead's drug after ")  # issue 36: the envelope first
    drug = point(out)
    assert fluid[0].endswith("release 50.0% of the stored fluid (radius 2.292 -> 1.868 dry "
                             "radii)")
    assert drug[0] == "ANB 302 K -> 308 K: release 50.0% of the loaded drug = 1 ug"
    assert drug[1] == fluid[1] + ", after waiting 0 at T_start"  # the same time, one format
    assert drug[2].startswith("  truth of the drug runs: ") and fluid[2].startswith("  truth: ")
    assert any(line.startswith("  mechanism: squeezed out") for line in drug)


@pytest.mark.parametrize(("extra", "needle"), [
    (["--drug-diffusivity-cm2-s", "1e-7", "--wait", "100"], "wait=100.0 is invalid: valid range "
     "is a finite number 0-32 tau"),
    (["--drug-diffusivity-cm2-s", "1e-7", "--wait-seconds", "1e6", "--dry-radius-um", "50"],
     "wait_seconds=1000000.0 is invalid: valid range is a finite number 0-32 tau = 0-705.5 s "
     "(tau = 22.05 s)"),
])
def test_a_wait_out_of_range_exits_2_naming_it(extra, needle, capsys, tmp_path: Path) -> None:
    """The wait's rule (solver.limits, dosing.request.at_start): a drug run's step is at most
    DRUG_STEP_MAX tau (a wait of 100 tau used to fail naming 'saveat')."""
    assert main(["dose", "--t-start", "302", "--t-end", "308", "--fraction", "0.3", *extra,
                 "--cache", str(tmp_path / "c.sqlite")]) == 2
    assert needle in capsys.readouterr().err


@pytest.mark.parametrize(("extra", "needle"), [
    (["--rests", "2000"], "--rests=2000.0 is invalid"),
    (["--rests-seconds", "1e9", "--dry-radius-um", "50"],
     "rests_seconds[0]=1000000000.0 is invalid: valid range is a finite number 0-1000 tau"),
    (["--rests", "100", "--drug-diffusivity-cm2-s", "0"], "rests[0]=100.0 is invalid: valid "
     "range is a finite number 0-32 tau"),
])
def test_a_rest_out_of_range_exits_2_naming_it(extra, needle, capsys, tmp_path: Path) -> None:
    assert main(["schedule", "--t-start", "302", "--t-end", "308", "--doses", "0.3", "0.3",
                 "--no-check", *extra, "--cache", str(tmp_path / "c.sqlite")]) == 2
    assert needle in capsys.readouterr().err
