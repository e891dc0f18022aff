"""A batch's dose through every way in (issue 26): Python, `thermogel dose --size-cv` /
`--sizes`, and POST /v1/dose-time with a size_distribution give the same numbers."""

from __future__ import annotations

import json
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
from api_support import asgi

from api.cli import main
from api.http import create_app
from dosing import DoseRequest, Planner
from dosing.population.front import batch_answer

JUMP = {"gel": "ANB", "t_start": 302.0, "t_end": 308.0}
ARGS = ["dose", "--gel", "ANB", "--t-start", "302", "--t-end", "308", "--fraction", "0.8"]
SIZES = "diameter (um),count\n80,1\n100,3\n120,2\n"


def _python(**dist) -> dict:
    size = {} if dist.get("kind") == "table" else {"dry_radius_um": 50.0}
    req = DoseRequest(**JUMP, dose_fraction=0.8, size_distribution=dist, **size)
    return batch_answer(req).to_dict()


def _cli(capsys, argv: list[str]) -> dict:
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def test_cli_size_cv_and_sizes_match_python(capsys, tmp_path: Path) -> None:
    cache = ["--cache", str(tmp_path / "c.sqlite"), "--json"]
    out = _cli(capsys, [*ARGS, "--dry-radius-um", "50", "--size-cv", "0.2", *cache])
    ref = _python(cv=0.2)
    assert out["batch"]["time"] == ref["time"] and out["batch"]["seconds"] == ref["seconds"]
    assert out["batch"]["quadrature"]["nodes"] == ref["quadrature"]["nodes"]
    assert out["bead_dry_radius_um"] == 50.0  # the single-bead fields: the mean bead
    csv = tmp_path / "sizes.csv"
    csv.write_text(SIZES)
    out = _cli(capsys, [*ARGS, "--sizes", str(csv), *cache])
    tab = _python(kind="table", sizes_um=[80.0, 100.0, 120.0], counts=[1, 3, 2],
                  measure="diameter")
    assert out["batch"]["time"] == tab["time"]
    assert out["batch"]["reference_dry_radius_um"] == pytest.approx(310 / 6, rel=1e-14)
    # the text form
    assert main([*ARGS, "--dry-radius-um", "50", "--size-cv", "0.3", "--cache",
                 str(tmp_path / "c.sqlite")]) == 0
    text = capsys.readouterr().out
    assert "batch (a number-weighted lognormal of dry radii, mean 50 um, CV 0.3)" in text
    assert "quadrature:" in text and "of the beads have delivered" in text


@pytest.mark.parametrize("extra,flag", [
    (["--size-cv", "-0.1", "--dry-radius-um", "50"], "--size-cv"),
    (["--size-cv", "2.5", "--dry-radius-um", "50"], "--size-cv"),
    (["--size-cv", "0.2"], "size_distribution.mean_um"),  # no size for the mean
])
def test_cli_refusals_name_the_option(capsys, tmp_path, extra, flag) -> None:
    assert main([*ARGS, *extra, "--cache", str(tmp_path / "c.sqlite")]) == 2
    assert flag in capsys.readouterr().err


def test_cli_refuses_an_empty_or_negative_table(capsys, tmp_path) -> None:
    for i, text in enumerate(["radius_um\n", "radius_um\n50\n-3\n"]):
        p = tmp_path / f"s{i}.csv"
        p.write_text(text)
        assert main([*ARGS, "--sizes", str(p), "--cache", str(tmp_path / "c.sqlite")]) == 2
        assert "--sizes" in capsys.readouterr().err


def test_cli_refuses_a_drug_batch_with_a_per_bead_medium(capsys, tmp_path) -> None:
    # a batch's drug dose shares one medium (tests/test_batch_drug.py): a per-bead release
    # volume is refused, naming it, before any run
    assert main([*ARGS, "--dry-radius-um", "50", "--size-cv", "0.2",
                 "--drug-diffusivity-cm2-s", "1e-7", "--release-volume-ul", "1", "--cache",
                 str(tmp_path / "c.sqlite")]) == 2
    assert "release_volume_ul" in capsys.readouterr().err



@pytest.mark.anyio
async def test_http_size_distribution_matches_python(tmp_path) -> None:
    planner = Planner(cache_path=tmp_path / "c.sqlite", executor=ThreadPoolExecutor(1))
    try:
        async with asgi(create_app(planner=planner, warm=False)) as (_, raw):
            body = {**JUMP, "dose_fraction": 0.8, "dry_radius_um": 50.0,
                    "size_distribution": {"cv": 0.2}}
            r = await raw.post("/v1/dose-time", json=body)
            assert r.status_code == 200, r.text
            got = r.json()["batch"]
            ref = _python(cv=0.2)
            assert got["time"] == ref["time"] and got["delay"] == ref["delay"]
            assert got["fraction_delivered"] == ref["fraction_delivered"]
            assert got["quadrature"]["nodes"] == ref["quadrature"]["nodes"]
            tab = {"kind": "table", "sizes_um": [80.0, 100.0, 120.0], "counts": [1, 3, 2],
                   "measure": "diameter"}
            r = await raw.post("/v1/dose-time", json={**JUMP, "dose_fraction": 0.8,
                                                      "size_distribution": tab})
            assert r.status_code == 200, r.text
            assert r.json()["batch"]["time"] == _python(**tab)["time"]
            for bad, loc in [({"cv": 2.5}, "cv"), ({"cv": -1.0}, "cv"),
                             ({"kind": "table", "sizes_um": []}, "sizes_um")]:
                r = await raw.post("/v1/dose-time", json={**body, "size_distribution": bad})
                assert r.status_code == 422 and loc in r.text, r.text
            r = await raw.post("/v1/dose-time", json={**body, "size_distribution": {
                "kind": "table", "sizes_um": [50.0, -1.0]}})
            assert r.status_code == 422 and "sizes_um" in r.text
            r = await raw.post("/v1/dose-time", json={**body, "drug": {
                "diffusivity_cm2_s": 1e-7, "release_volume_ul": 1.0}})
            assert r.status_code == 422 and "release_volume_ul" in r.text
    finally:
        planner.close()
        planner.jobs.executor.shutdown(wait=True)
