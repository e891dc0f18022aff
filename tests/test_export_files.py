"""Exports that leave cleanly (issue 37): ``--out`` on simulate and release writes every
format at the commands' defaults; a CSV is a set of bounded tidy tables (the series at the
output times; the profiles long form beside it), read back by pandas; every file carries
``request`` (resolved, with units) and ``version``.  One round trip per result type: runs,
release runs, schedules, sweeps and fits, each file read back and its size checked."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

xr = pytest.importorskip("xarray")
pd = pytest.importorskip("pandas")

from api.cli import main  # noqa: E402
from dosing import Planner, ScheduleRequest  # noqa: E402
from dosing.present import export  # noqa: E402
from dosing.studies.sweep import SweepGrid, run_sweep  # noqa: E402
from solver.fit import fit_equilibrium  # noqa: E402
from solver.fit.synthetic import synthetic_swelling  # noqa: E402
from solver.gel import HHT  # noqa: E402

MB = 2**20
SMALL_RUN = ["--gel", "ANB", "--t-start", "302", "--t-end", "308", "--until", "0.01",
             "--n", "100", "--every", "0.001"]
RELEASE = ["release", "--gel", "ANB", "--t-start", "302", "--protocol", "0.01:308",
           "--dry-radius-um", "50", "--drug-diffusivity-cm2-s", "1e-7", "--mesh-size-nm", "23",
           "--n", "60", "--samples", "100"]


def _provenance(attrs: dict) -> dict:
    """The request an export carries, checked for its units and the version beside it."""
    version = json.loads(attrs["version"])
    assert {"package", "code", "solver"} <= set(version)
    request = json.loads(attrs["request"])
    assert "units" in request
    return request


def _read_csv(path: Path) -> tuple[pd.DataFrame, dict]:
    attrs = {}
    for line in path.read_text().splitlines():
        if not line.startswith("# "):
            break
        key, _, value = line[2:].partition(": ")
        attrs[key] = value
    return pd.read_csv(path, comment="#"), attrs


def test_simulate_csv_is_the_series_and_profiles_long_form(tmp_path: Path, capsys) -> None:
    out = tmp_path / "run.csv"
    assert main(["simulate", *SMALL_RUN, "--out", str(out), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["file"] == str(out)
    assert set(report["files"]) == {str(out), str(tmp_path / "run.profiles.csv"),
                                    str(tmp_path / "run.steps.csv")}
    series, attrs = _read_csv(out)
    assert len(series) == len(report["t"]) == 11
    np.testing.assert_array_equal(series["time [1]"], report["t"])
    np.testing.assert_array_equal(series["radius [1]"], report["radius"])
    assert {"temperature [K]", "front [1]"} <= set(series.columns)
    req = _provenance(attrs)
    assert req["t_start"] == 302.0 and req["units"]["t_start"] == "K"
    prof, _ = _read_csv(tmp_path / "run.profiles.csv")
    assert len(prof) == 11 * 100  # one row per output time and cell
    assert {"time [1]", "phi [1]", "cell_radius [1]"} <= set(prof.columns)
    for f in report["files"]:
        assert Path(f).stat().st_size < 5 * MB


def test_release_out_works_at_every_default_and_in_every_format(tmp_path: Path,
                                                                 capsys) -> None:
    # the interfacial length, the grid and the cells left to their defaults (once a TypeError)
    for name in ("rel.nc", "rel.csv", "rel.npz"):
        assert main([*RELEASE, "--out", str(tmp_path / name)]) == 0
    text = capsys.readouterr().out
    assert f"wrote {tmp_path / 'rel.csv'}" in text and "rel.profiles.csv" in text
    ds = export.open_netcdf(tmp_path / "rel.nc")
    req = _provenance(ds.attrs)
    assert req["dry_radius_um"] == 50.0 and req["units"]["dry_radius_um"] == "um"
    assert "moving grid, N = 60" in ds.attrs["truth"] and "interfacial length" in ds.attrs["truth"]
    series, attrs = _read_csv(tmp_path / "rel.csv")
    np.testing.assert_array_equal(series["released_fraction [1]"],
                                  ds["released_fraction"].values)
    assert len(series) == ds.sizes["time"] and "seconds [s]" in series.columns
    _provenance(attrs)
    prof, _ = _read_csv(tmp_path / "rel.profiles.csv")
    assert len(prof) == ds.sizes["profile_time"] * ds.sizes["cell"]
    for f in tmp_path.iterdir():
        assert f.stat().st_size < 5 * MB


def test_a_table_too_large_for_csv_is_refused_naming_nc(tmp_path: Path) -> None:
    from solver.full import simulate
    from solver.gel import ANB

    ds = simulate(ANB, 302.0, 308.0, until=0.005, n=40, every=0.001).to_xarray(request={})
    files, notes = export.write_csv(ds, tmp_path / "r.csv", max_bytes=20_000)
    assert [f.name for f in files] == ["r.csv", "r.steps.csv"]  # the profiles left out
    assert any("profiles not written" in n and ".nc" in n for n in notes)
    assert "profiles not written" in (tmp_path / "r.csv").read_text()
    with pytest.raises(export.CsvTooLarge, match=r"\.nc"):
        export.write_csv(ds, tmp_path / "r2.csv", max_bytes=100)


def test_schedule_sweep_and_fit_files_round_trip(tmp_path: Path) -> None:
    with Planner(cache_path=tmp_path / "c.sqlite") as p:
        req = ScheduleRequest("ANB", 302.0, 308.0, doses=[0.3, 0.3], rests=[0.5],
                              dry_radius_um=50.0, check_protocol=False, correct=False)
        sched = p.schedule_now(req)
    sweep = run_sweep(SweepGrid(t_ends=[308.0, 310.0], dry_radii_um=[20.0, 50.0],
                                doses=[0.3, 0.8], gels=["ANB"]))
    fit = fit_equilibrium(synthetic_swelling(HHT, scale=0.4127, seed=3))
    cases = {"schedule": (sched.to_xarray(request=req), 2),
             "sweep": (sweep.to_xarray(), 8),
             "fit": (fit.to_xarray(request={"file": "x.csv"}), len(fit.names))}
    for name, (ds, rows) in cases.items():
        nc = export.save(ds, tmp_path / f"{name}.nc")
        back = export.open_netcdf(nc)
        _provenance(back.attrs)
        assert set(back.data_vars) == set(ds.data_vars), name
        csv = export.save(ds, tmp_path / f"{name}.csv")
        df, attrs = _read_csv(csv)
        assert len(df) == rows, name
        _provenance(attrs)
        assert nc.stat().st_size < MB and csv.stat().st_size < MB
    cov, _ = _read_csv(tmp_path / "fit.covariance.csv")
    assert len(cov) == len(fit.names) ** 2


@pytest.mark.slow
def test_the_commands_defaults_write_bounded_csv(tmp_path: Path) -> None:
    """The acceptance: the README's simulate and release commands with --out .csv."""
    run = tmp_path / "run.csv"
    assert main(["simulate", "--gel", "ANB", "--t-start", "302", "--t-end", "308",
                 "--until", "0.3", "--out", str(run)]) == 0
    rel = tmp_path / "rel.csv"
    assert main(["release", "--gel", "ANB", "--t-start", "302", "--protocol",
                 "0.05:308,0.5:302,0.1:308", "--dry-radius-um", "50",
                 "--drug-diffusivity-cm2-s", "1e-7", "--mesh-size-nm", "23",
                 "--out", str(rel)]) == 0
    for f in tmp_path.glob("*.csv"):
        assert f.stat().st_size <= 50 * MB, f
        assert len(pd.read_csv(f, comment="#")) > 0
