"""The timescale a kinetics fit pins, carried into every answer (issue 27, items 1-2)."""

from __future__ import annotations

import json

import httpx
import numpy as np
import pytest

from api.cli import main
from api.http import create_app
from dosing import DoseRequest, PhysicalConstants, plan_dose
from dosing.fits.gel import front_radius_model
from dosing.units import timescale, timescale_uncertainty
from solver.gel import HHT

DRY_UM = 40.0
SLOWER = 2.3  # the "measured" bead is 2.3x slower than the default constants say


@pytest.fixture
def env(tmp_path, monkeypatch):
    monkeypatch.setenv("THERMOGEL_GELS", str(tmp_path / "gels"))
    monkeypatch.setenv("THERMOGEL_CACHE", str(tmp_path / "v.sqlite"))
    return tmp_path


def _kinetics_csv(path, tau_s: float):
    curve = front_radius_model(
        __import__("solver.gel", fromlist=["HHT"]).HHT, 300.0, 310.0, "swollen")(None)
    td = np.linspace(0.0, 0.02, 30)
    y = DRY_UM * curve(td) * (1 + 0.005 * np.random.default_rng(1).standard_normal(td.size))
    path.write_text("time_s,radius\n" + "".join(
        f"{t * tau_s:.5f},{v:.5f}\n" for t, v in zip(td, y, strict=True)))
    return path


@pytest.fixture
def calibrated(env, capsys):
    """`fit kinetics --save mygel` on a bead SLOWER times slower than the default tau."""
    tau_true = SLOWER * timescale(DRY_UM, 310.0, omega=HHT.omega).seconds
    csv = _kinetics_csv(env / "k.csv", tau_true)
    assert main(["fit", "kinetics", str(csv), "--gel", "HHT", "--t-start", "300",
                 "--t-end", "310", "--dry-radius-um", str(DRY_UM), "--json",
                 "--save", "mygel"]) == 0
    kin = json.loads(capsys.readouterr().out)
    return kin, tau_true


def test_kinetics_fit_reports_the_diffusivity_it_pins(calibrated) -> None:
    kin, tau_true = calibrated
    d_true = (DRY_UM * 1e-6) ** 2 / tau_true * 1e4
    assert kin["diffusivity_cm2_s"] == pytest.approx(d_true, rel=0.02)
    lo, hi = kin["diffusivity_interval_cm2_s"]
    assert lo < d_true < hi
    assert kin["diffusivity_t_k"] == 310.0


def test_dose_by_name_uses_the_fitted_timescale(calibrated, env, capsys) -> None:
    """CLI, Python and the stored record agree: seconds = time * tau_fit, tau_fit ~ SLOWER x
    the uncalibrated tau, and scaling the bead scales the seconds as R^2 (eq. timescale)."""
    kin, tau_true = calibrated
    tau_fit = kin["tau_s"]
    args = ["dose", "--gel", "mygel", "--t-start", "300", "--t-end", "310", "--fraction", "0.5",
            "--json"]
    assert main([*args, "--dry-radius-um", str(DRY_UM)]) == 0
    dose = json.loads(capsys.readouterr().out)
    assert dose["timescale_seconds"] == pytest.approx(tau_fit, rel=1e-9)
    assert dose["seconds"] == pytest.approx(dose["time"] * tau_fit, rel=1e-9)
    assert dose["timescale_uncertainty"]["calibrated"] is True
    slo, shi = dose["timescale_uncertainty"]["seconds_range"]
    assert slo < dose["seconds"] < shi and shi / slo < 1.2  # the fit's interval, not 100x
    preset = plan_dose(DoseRequest("HHT", 300.0, 310.0, dose_fraction=0.5,
                                   dry_radius_um=DRY_UM))
    assert dose["seconds"] / preset.seconds == pytest.approx(SLOWER, rel=0.03)
    assert main([*args, "--dry-radius-um", str(2 * DRY_UM)]) == 0
    big = json.loads(capsys.readouterr().out)
    assert big["timescale_seconds"] == pytest.approx(4 * tau_fit, rel=1e-9)
    # Python: the same; a request giving D itself keeps it
    ans = plan_dose(DoseRequest("mygel", 300.0, 310.0, dose_fraction=0.5, dry_radius_um=DRY_UM))
    assert ans.seconds == pytest.approx(dose["seconds"], rel=1e-9)
    own = PhysicalConstants(diffusivity_m2_s=1e-11, diffusivity_t_k=310.0)
    ans2 = plan_dose(DoseRequest("mygel", 300.0, 310.0, dose_fraction=0.5,
                                 dry_radius_um=DRY_UM, constants=own))
    assert ans2.timescale_seconds == pytest.approx((DRY_UM * 1e-6) ** 2 / 1e-11)
    # the CLI text says it is calibrated
    assert main(args[:-1] + ["--dry-radius-um", str(DRY_UM)]) == 0
    assert "calibrated seconds" in capsys.readouterr().out


def test_a_calibrated_gel_at_another_temperature_follows_k_B_T_over_eta() -> None:
    c = PhysicalConstants(viscosity_pa_s="water", diffusivity_m2_s=1e-11, diffusivity_t_k=310.0)
    ratio = c.diffusivity(300.0) / c.diffusivity(310.0)
    assert ratio == pytest.approx(300.0 / 310.0 * c.viscosity(310.0) / c.viscosity(300.0))
    assert ratio < 0.8  # water is ~20% more viscous at 300 K than at 310 K


def test_uncalibrated_answers_state_the_constants_range(capsys) -> None:
    """ANB (Omega = 100): the default Omega_p = Omega Omega_f = 3e-27 m^3 against the paper's
    3e-25 m^3 is a factor 100 in tau, the default at its fast end; HHT (Omega = 720) 13.9x,
    widened to 26x by Tanaka's D."""
    ans = plan_dose(DoseRequest("ANB", 302.0, 308.0, dose_fraction=0.8, dry_radius_um=50.0))
    tu = ans.timescale_uncertainty
    assert tu["calibrated"] is False and "UNCALIBRATED" in tu["note"]
    assert tu["factor"] == pytest.approx(100.0, rel=1e-6)
    assert tu["seconds_range"][0] == pytest.approx(ans.seconds)
    assert tu["source"].startswith("default constants consistent with the gel")
    assert "fit kinetics" in tu["how_to_pin"]
    hht = timescale_uncertainty(720.0, 308.0, PhysicalConstants())
    d_paper = PhysicalConstants.paper().diffusivity(308.0) * 1e4
    assert hht["diffusivity_cm2_s"] == pytest.approx(d_paper * 3e-25 / (720 * 3e-29))
    assert hht["factor"] == pytest.approx(3e-7 / d_paper, rel=1e-6)
    assert 10 < hht["factor"] < 100  # one to two orders of magnitude
    paper = timescale_uncertainty(720.0, 308.0, PhysicalConstants.paper())
    assert paper["source"].startswith("the paper's constants")
    assert paper["factor"] == pytest.approx(hht["factor"], rel=1e-9)  # the same three readings
    assert main(["dose", "--gel", "ANB", "--t-start", "302", "--t-end", "308",
                 "--fraction", "0.8", "--dry-radius-um", "50"]) == 0
    assert "UNCALIBRATED seconds" in capsys.readouterr().out



@pytest.mark.anyio
async def test_http_lists_fitted_gels_and_doses_with_their_timescale(calibrated, env) -> None:
    kin, _ = calibrated
    app = create_app(warm=False, cache_path=str(env / "v.sqlite"))
    async with app.router.lifespan_context(app):
        transport = httpx.ASGITransport(app=app)
        async with httpx.AsyncClient(base_url="http://t", transport=transport) as c:
            gels = (await c.get("/v1/gels")).json()
            assert [g["gel"]["name"] for g in gels["gels"]] == ["ANB", "HHT"]
            (mine,) = gels["fitted"]
            assert mine["name"] == "mygel" and mine["fitted"]["kinetics"]
            assert mine["timescale"]["diffusivity_cm2_s"] == pytest.approx(
                kin["diffusivity_cm2_s"])
            assert "kinetics.tau" in mine["parameters"] and mine["folds"]
            r = await c.post("/v1/dose-time", json={
                "gel": "mygel", "t_start": 300.0, "t_end": 310.0, "dose_fraction": 0.5,
                "dry_radius_um": DRY_UM})
            assert r.status_code == 200, r.text
            ans = r.json()
            assert ans["timescale_seconds"] == pytest.approx(kin["tau_s"], rel=1e-9)
            assert ans["timescale_uncertainty"]["calibrated"] is True


def test_joint_interval_of_a_gel_fitted_to_swelling_and_kinetics(env, capsys) -> None:
    """A gel with both fits: the seconds' interval comes from both jointly (tau refitted as
    the swelling parameters move), and is narrower than the two added as if independent,
    since the dose time and the kinetics half-time move together with the dry size."""
    from solver.fit.synthetic import synthetic_swelling
    from solver.gel import HHT

    d = synthetic_swelling(HHT, scale=41.27, seed=3)
    sw = env / "s.csv"
    sw.write_text("temperature_K,radius\n" + "".join(
        f"{t:.4f},{y:.5f}\n" for t, y in zip(d.temperature, d.size, strict=True)))
    assert main(["fit", "swelling", str(sw), "--save", "both", "--json"]) == 0
    capsys.readouterr()
    csv = _kinetics_csv(env / "k.csv", SLOWER * timescale(DRY_UM, 310.0, omega=HHT.omega).seconds)
    assert main(["fit", "kinetics", str(csv), "--gel", "both", "--t-start", "300", "--t-end",
                 "310", "--dry-radius-um", str(DRY_UM), "--save", "both", "--json"]) == 0
    capsys.readouterr()
    ans = plan_dose(DoseRequest("both", 300.0, 310.0, dose_fraction=0.5, dry_radius_um=DRY_UM))
    iv = ans.parameter_interval
    assert iv["method"] == "delta, joint" and "jointly" in iv["note"]
    lo, hi = iv["seconds"]
    assert lo < ans.seconds < hi
    rec_kin = json.loads((env / "gels" / "both.json").read_text())["kinetics"]["fit"]
    d_lo, d_hi = rec_kin["diffusivity_interval_cm2_s"]
    added = np.hypot(iv["relative_half_width"], 0.5 * np.log(d_hi / d_lo))
    assert iv["seconds_relative_half_width"] < added
