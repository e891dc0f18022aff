"""The kinetics fit (tau, hence k0, from a shrinking curve; issue 14)."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

from dosing import Planner
from dosing.fits.gel import fit_shrinking, front_radius_model, kinetics_data, read_kinetics_csv
from dosing.runs.scenario import Scenario, SolverSettings
from dosing.units import PhysicalConstants, timescale
from solver.errors import ParameterError
from solver.gel import ANB

DRY_UM = 50.0
TAU = timescale(DRY_UM, 308.0, omega=ANB.omega).seconds  # default constants: about 22 s


def _curve(radius_of_t, noise: float = 0.01, seed: int = 0, t_max: float = 0.3, n: int = 40):
    td = np.linspace(0.0, t_max, n)
    rng = np.random.default_rng(seed)
    y = DRY_UM * radius_of_t(td) * (1.0 + noise * rng.standard_normal(n))
    return kinetics_data(td * TAU, y)


def test_front_model_data_give_tau_and_k0() -> None:
    curve = front_radius_model(ANB, 302.0, 308.0, "swollen", sharp=True)(None)
    res = fit_shrinking(_curve(curve), "ANB", 302.0, 308.0, dry_radius_um=DRY_UM,
                        model="front-sharp")
    lo, hi = res.intervals["tau"]
    assert lo < TAU < hi
    assert res.parameters["tau"] == pytest.approx(TAU, rel=0.03)
    # k0 through eq. timescale: the constants that made tau come back
    assert res.extra["k0_m2"] == pytest.approx(PhysicalConstants().permeability_m2, rel=0.03)
    assert res.extra["model"] == "front-sharp"


@pytest.mark.slow
def test_full_solver_curve_gives_tau_within_3_percent(tmp_path) -> None:
    """Acceptance: ANB 302 -> 308 K, 50 um bead, 1% noise, data from the full solver at
    ell = 0.0025 (N = 1600, ~15 s); the front model (sharp interface, the default) and the
    full solver at the same settings both give tau within 3% and inside the interval."""
    st = SolverSettings(interfacial_length=0.0025, method="ladder")
    planner = Planner(cache_path=str(tmp_path / "c.sqlite"), executor=ThreadPoolExecutor(1))
    try:
        traj = planner.trajectory(Scenario(ANB, 302.0, 308.0, settings=st), need_radius=1.12,
                                  need_time=0.4)  # the data window: a run stops at its need
        data = _curve(lambda t: np.interp(t, traj.step_t, traj.step_radius))
        for model in ("auto", "full"):
            res = fit_shrinking(data, "ANB", 302.0, 308.0, dry_radius_um=DRY_UM, model=model,
                                settings=st, planner=planner)
            lo, hi = res.intervals["tau"]
            assert lo < TAU < hi, model
            assert res.parameters["tau"] == pytest.approx(TAU, rel=0.03), model
    finally:
        planner.close()
        planner.jobs.executor.shutdown(wait=True)


def test_beta_cannot_be_fitted_with_the_front_model() -> None:
    curve = front_radius_model(ANB, 302.0, 308.0, "swollen")(None)
    with pytest.raises(ParameterError, match="not separately identifiable"):
        fit_shrinking(_curve(curve), "ANB", 302.0, 308.0, fit_beta=True, model="front")


def test_a_flat_curve_is_refused() -> None:
    data = kinetics_data(np.linspace(0, 1000, 20), np.full(20, 100.0))
    with pytest.raises(ParameterError, match="a shrinking curve"):
        fit_shrinking(data, "ANB", 302.0, 308.0, model="front-sharp")


@pytest.mark.parametrize(("text", "words"), [
    ("clock,radius\n0,1\n", "unknown column name(s) 'clock'"),
    ("time_s,radius\n-1,1\n0,1\n", "times >= 0"),
    ("time_s,radius\n0,nan\n1,1\n", "NaN"),
])
def test_bad_kinetics_csv(tmp_path, text, words) -> None:
    p = tmp_path / "k.csv"
    p.write_text(text)
    with pytest.raises(ParameterError) as exc:
        read_kinetics_csv(p)
    assert words in str(exc.value)
