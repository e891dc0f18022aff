"""Global sensitivity of the dose time (issue 25): Sobol indices against an analytic answer,
the model is the planner's own front answer, Morris screening, errors, CLI and HTTP.

The analytic case: with the gel, the jump and the dose fixed, the front model's dose time
in seconds is t* tau with tau = eta Omega_p R^2 / (k0 k_B T_end) (eq. timescale), i.e.
c R^2 / k0.  For independent log-uniform R and k0 the Sobol indices of a product of powers
are exact (``analytic_power_law_indices``, derived in its docstring); the estimates must
match them within SALib's stated 95% intervals."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("SALib")

from api.cli import main
from dosing import DoseRequest
from dosing.model_choice import front_answer
from dosing.studies.sensitivity import (
    Base,
    DoseTimeModel,
    Vary,
    analytic_power_law_indices,
    sensitivity,
)
from dosing.units import PhysicalConstants
from solver.errors import ParameterError
from solver.gel import ANB

R, K = (10.0, 100.0), (1e-20, 1e-19)
VARY = [f"dry_radius_um={R[0]}:{R[1]}:log", f"permeability_m2={K[0]}:{K[1]}:log"]


def test_analytic_indices_of_a_pure_power_are_one() -> None:
    # one input alone explains everything; a sanity check of the formula
    one = analytic_power_law_indices({"r": R}, {"r": 2.0})
    assert one["r"]["S1"] == pytest.approx(1.0) and one["r"]["ST"] == pytest.approx(1.0)
    # the check by direct quadrature of the moments (Y = R^2 / k, log-uniform each)
    u = np.linspace(0, 1, 200_001)
    r = R[0] * (R[1] / R[0]) ** u
    k = K[0] * (K[1] / K[0]) ** u
    x1, x2 = r**2, 1 / k
    m1, m2, s1, s2 = x1.mean(), x2.mean(), (x1**2).mean(), (x2**2).mean()
    var = s1 * s2 - (m1 * m2) ** 2
    exact = analytic_power_law_indices({"R": R, "k": K}, {"R": 2.0, "k": -1.0})
    assert exact["R"]["S1"] == pytest.approx((s1 - m1**2) * m2**2 / var, rel=1e-4)
    assert exact["k"]["ST"] == pytest.approx((s2 - m2**2) * s1 / var, rel=1e-4)


@pytest.mark.parametrize("seed", [0, 1])
def test_sobol_matches_the_analytic_indices_within_their_intervals(seed: int) -> None:
    res = sensitivity("ANB", 302.0, 308.0, 0.8, VARY, samples=1024, seed=seed)
    exact = analytic_power_law_indices({"dry_radius_um": R, "permeability_m2": K},
                                       {"dry_radius_um": 2.0, "permeability_m2": -1.0})
    # R^2 over a decade varies 100-fold, k0 10-fold: R dominates, and interaction matters
    assert exact["dry_radius_um"]["S1"] > 0.5 > exact["permeability_m2"]["S1"]
    for name in res.names:
        for key in ("S1", "ST"):
            got, conf = res.indices[name][key], res.indices[name][key + "_conf"]
            assert 0 < conf < 0.15, (name, key, conf)  # an interval that can fail
            assert abs(got - exact[name][key]) <= conf, (name, key, got, exact[name][key])
    assert res.evaluations == 1024 * 4


def test_the_model_is_the_planners_front_answer() -> None:
    c = PhysicalConstants()
    base = Base(ANB, 302.0, 308.0, 0.8, 50.0, c)  # Omega_p follows a varied omega
    model = DoseTimeModel(base, ["dry_radius_um", "dose_fraction", "t_end", "omega"])
    x = np.array([[20.0, 0.5, 308.0, 100.0], [70.0, 0.3, 309.0, 100.0],
                  [35.0, 0.7, 308.0, 110.0], [35.0, 0.6, 308.0, 110.0]])
    y = model(x)
    for row, got in zip(x, y, strict=True):
        gel = ANB if row[3] == 100.0 else ANB.__class__(**{**ANB.to_dict(), "omega": row[3]})
        ans = front_answer(DoseRequest(gel, 302.0, row[2], dose_fraction=row[1],
                                       dry_radius_um=row[0]))
        assert got == pytest.approx(ans.seconds, rel=1e-12)


def test_morris_ranks_the_bead_size_above_a_narrow_viscosity() -> None:
    res = sensitivity("ANB", 302.0, 308.0, 0.8,
                      [*VARY, "viscosity_pa_s=0.00095:0.00105"], method="morris",
                      samples=40)
    mu = {n: res.indices[n]["mu_star"] for n in res.names}
    assert mu["dry_radius_um"] > mu["permeability_m2"] > 10 * mu["viscosity_pa_s"] > 0


def test_bad_inputs_name_their_field() -> None:
    with pytest.raises(ParameterError) as e:
        sensitivity("ANB", 302.0, 308.0, 0.8, ["radius=1:2"])
    assert e.value.field == "vary"
    with pytest.raises(ParameterError) as e:
        Vary("permeability_m2", -1.0, 1.0, log=True)
    assert e.value.field == "vary.permeability_m2"
    with pytest.raises(ParameterError) as e:  # beyond a fraction's range: refused at once
        sensitivity("ANB", 302.0, 308.0, 0.8, ["dose_fraction=0.5:1.5"], samples=8)
    assert e.value.field == "vary.dose_fraction" and "< 1" in e.value.valid
    with pytest.raises(ParameterError) as e:  # doses above what the gel can expel
        sensitivity("ANB", 302.0, 308.0, 0.8, ["dose_fraction=0.97:0.99"], samples=8)
    assert e.value.field == "vary" and "samples failed" in str(e.value)
    for bad in ("dry_radius_um=1e-300:1e300:log", "t_end=0:1e308", "omega=-1e308:1e308"):
        with pytest.raises(ParameterError) as e:  # unbounded ranges (issue 40, R6)
            sensitivity("ANB", 302.0, 308.0, 0.8, [bad], samples=8)
        assert e.value.field == f"vary.{bad.split('=')[0]}", bad
    with pytest.raises(ParameterError) as e:
        sensitivity("ANB", 302.0, 308.0, 0.8, ["t_end=308:309"], samples=512,
                    max_trajectories=100)
    assert e.value.field == "samples"


def test_cli_json_and_plot(tmp_path: Path, capsys) -> None:
    plot = tmp_path / "s.svg"
    assert main(["sensitivity", "--gel", "ANB", "--t-start", "29 degC", "--t-end", "308",
                 "--fraction", "0.8", "--vary", VARY[0], "--vary", VARY[1], "--samples",
                 "256", "--json", "--plot", str(plot)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["base"]["t_start"] == pytest.approx(302.15)
    assert set(out["indices"]) == {"dry_radius_um", "permeability_m2"}
    assert plot.read_text().lstrip().startswith("<?xml")
    assert main(["sensitivity", "--t-start", "302", "--t-end", "308", "--fraction", "0.8",
                 "--vary", "bogus=1:2"]) == 2



@pytest.mark.anyio
async def test_http_answers_at_once_and_refuses_a_bad_name(tmp_path: Path) -> None:
    from api_support import asgi, fake_full_solver, fake_planner

    from api.http import create_app

    body = {"gel": "ANB", "t_start": "29 degC", "t_end": 308.0, "dose_fraction": 0.8,
            "vary": [{"name": "dry_radius_um", "low": 10, "high": 100, "log": True},
                     {"name": "permeability_m2", "low": 1e-20, "high": 1e-19, "log": True}],
            "samples": 256}
    with fake_full_solver() as fake, fake_planner(tmp_path / "c.sqlite", fake) as planner:
        app = create_app(planner=planner, warm=False)
        async with asgi(app) as (_, client):
            r = await client.post("/v1/sensitivity", json=body)
            assert r.status_code == 200, r.text
            got = r.json()
            assert got["output"] == "dose time [s]" and got["evaluations"] == 256 * 4
            s1 = got["indices"]["dry_radius_um"]["S1"]
            assert math.isfinite(s1) and s1 > got["indices"]["permeability_m2"]["S1"]
            bad = await client.post("/v1/sensitivity", json={**body, "vary": [
                {"name": "radius", "low": 1, "high": 2}]})
            assert bad.status_code == 422 and "radius" in bad.text
            unit = await client.post("/v1/sensitivity", json={**body, "t_start": "50 um"})
            assert unit.status_code == 422 and "t_start" in unit.text
