"""The moving Lagrangian grid (solver/full/moving.py, ale.py, rezone.py).

Tolerances: the uniform grid at 4/ell cells is converged to ~1e-5 in t80 at ell = 0.005
(docs/interfacial.md, sec. 6); benchmarks/moving_mesh.py measures the moving grid with a
quarter of the cells within 0.03-0.06% of it at ell = 0.005-0.00125, so 0.1% (the issue's
acceptance) has a margin of about two.  The fixed non-uniform grid converges at second order
(measured at ell = 0.02, N = 50, 100, 200: orders 3.4, pre-asymptotic, and 2.0);
the test asks for more than 1.5.
"""

from __future__ import annotations

import numpy as np
import pytest
from jacobian_support import dense_jacobian
from moving_support import running_state
from scipy.interpolate import PchipInterpolator

from solver.equilibrium import equilibrium
from solver.errors import ParameterError
from solver.front.result import fraction_radius
from solver.full import FullResult, moving, rezone, simulate
from solver.full.system import JAC_ANALYTIC, MOVING, linearize
from solver.gel import ANB

A80 = fraction_radius(equilibrium(ANB, 302.0).stretch, 0.8)


def _t80(grid: str, n: int, ell: float, until: float = 0.15,
         **kw: object) -> tuple[float, FullResult]:
    res = simulate("ANB", 302.0, 308.0, until=until, grid=grid, n=n, interfacial_length=ell,
                   rtol=1e-5, every=until / 100, **kw)
    return res.time_to_radius(A80), res


def test_equal_widths_at_rest_are_the_uniform_grid() -> None:
    n = 100
    mesh = moving.MeshOptions(rezone=False, nodes=tuple(np.arange(n + 1) / n))
    a = simulate("ANB", 302.0, 308.0, until=0.05, grid="lagrangian", n=n,
                 interfacial_length=0.02, rtol=1e-5)
    b = simulate("ANB", 302.0, 308.0, until=0.05, grid="moving", n=n, interfacial_length=0.02,
                 rtol=1e-5, mesh=mesh)
    np.testing.assert_array_equal(a.step_t, b.step_t)
    np.testing.assert_array_equal(a.step_radius, b.step_radius)
    np.testing.assert_array_equal(a.phi, b.phi)
    assert b.nodes.shape == (a.t.size, n + 1)


def _graded(n: int) -> tuple[float, ...]:
    """A smooth fixed grid, three times finer at the edge than at the centre."""
    u = np.arange(n + 1) / n
    x = u + 0.5 * (u - u**2) * (1.0 - u)  # x'(0) = 1.5, x'(1) = 0.5
    return tuple(x / x[-1])


def test_fixed_non_uniform_grid_converges() -> None:
    ell = 0.02
    ref, _ = _t80("lagrangian", 1600, ell, until=0.2)
    errs = []
    for n in (50, 100, 200):
        t, res = _t80("moving", n, ell, until=0.2,
                      mesh=moving.MeshOptions(rezone=False, nodes=_graded(n)))
        assert res.diagnostics["remaps"] == 0
        errs.append(abs(t - ref))
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(orders > 1.5), (errs, orders)


def test_moving_grid_reproduces_the_uniform_grid_with_a_quarter_of_the_cells() -> None:
    uniform, _ = _t80("lagrangian", 800, 0.005)
    adapted, res = _t80("moving", 200, 0.005)
    assert abs(adapted / uniform - 1.0) < 1e-3
    assert res.diagnostics["remaps"] > 0
    assert np.max(res.solid_error) < 1e-12
    # the result's profiles sit on each output's own cells, without single-cell spikes
    # (outputs land on steps: interpolated moving-node radii gave spikes of 0.8; now 1.5e-4)
    assert np.all(np.diff(res.nodes, axis=1) > 0.0)
    p = res.phi
    spike = np.maximum(np.minimum(p[:, 1:-1] - p[:, :-2], p[:, 1:-1] - p[:, 2:]),
                       np.minimum(p[:, :-2] - p[:, 1:-1], p[:, 2:] - p[:, 1:-1]))
    assert spike.max() < 0.01
    assert np.all(res.cell_radii()[:, -1] < res.radius)


def test_pchip_kernel_is_scipys() -> None:
    rng = np.random.default_rng(3)
    x = np.cumsum(rng.uniform(0.1, 1.0, 40))
    y = np.cumsum(rng.uniform(0.0, 2.0, 40))
    xi = np.linspace(x[0], x[-1], 333)
    out = np.empty(xi.size)
    rezone.pchip(x, y, xi, out)
    np.testing.assert_allclose(out, PchipInterpolator(x, y)(xi), rtol=1e-13, atol=1e-13)


def test_remap_keeps_volume_solid_and_porosity_range() -> None:
    n = 60
    old = np.arange(n + 1) / n
    rho = 0.5 * (old[1:] + old[:-1])
    phi = 0.3 + 0.6 / (1.0 + np.exp(-(rho - 0.6) / 0.01))  # a sharp front at rho = 0.6
    y = moving.state_from_profile(1.5, phi, old)
    new = np.sort(np.concatenate([[0.0, 1.0], np.random.default_rng(1).uniform(0, 1, n - 1)]))
    y2 = moving.remap(y, old, new)
    assert y2[-1] == y[-1]
    r3 = np.concatenate([[0.0], y2**3])
    jac = np.diff(r3) / np.diff(new**3)
    assert np.all(jac > 1.0)  # 0 < phi < 1 in every new cell
    assert abs(np.sum(np.diff(r3) / jac) - 1.0) < 1e-13  # the solid


def test_moving_jacobian_matches_central_differences() -> None:
    n, ell = 40, 0.05
    ws, y, par = running_state(ANB, n, ell, 0.03, 1e-7, 1e-10, perm=(1, 1.5))
    assert np.any(ws.geo[moving.ale.R_VEL] != 0.0)  # the nodes move
    central = np.zeros((n + 1, n + 1))
    for j in range(n + 1):
        h = 1e-5 * ((y[j] - (y[j - 1] if j else 0.0)) if j < n else 1e-2)
        yp, ym = y.copy(), y.copy()
        yp[j] += h
        ym[j] -= h
        central[:, j] = (ws.rhs(yp, par) - ws.rhs(ym, par)) / (2 * h)
    f = np.zeros(n + 1)
    assert linearize(MOVING, y, f, par, ws.geo, ws.work, ws.lower, ws.upper, ws.jband, ws.jc,
                     ws.jd, ws.je, ws.ytmp, ws.ftmp, ws.scale, JAC_ANALYTIC) > 0
    np.testing.assert_allclose(f, ws.rhs(y, par), rtol=1e-12, atol=1e-12)
    scale = np.abs(central).max(axis=1, keepdims=True)
    scale[scale == 0.0] = 1.0
    err = np.abs(dense_jacobian(ws) - central) / scale
    assert np.max(err[:, :n]) < 1e-6  # analytic (measured 4e-9)
    # the time column: a central difference moving the fastest node 0.1 of the smallest
    # cell (ale.TIME_STEP), second order: measured 1.3e-6 here
    assert np.max(err[:, n]) < 1e-5


def test_moving_result_round_trip_and_restart(tmp_path: object) -> None:
    t, res = _t80("moving", 100, 0.01, until=0.12)
    path = res.save(tmp_path / "run.npz")  # type: ignore[operator]
    back = FullResult.load(path)
    np.testing.assert_array_equal(back.nodes, res.nodes)
    assert back.grid == "moving"
    cont = simulate("ANB", 302.0, 308.0, until=0.01, grid="lagrangian", n=200,
                    interfacial_length=0.01, initial=res, rtol=1e-5)
    assert abs(cont.radius[0] - res.radius[-1]) < 1e-12
    again = simulate("ANB", 302.0, 308.0, until=0.01, grid="moving", n=100,
                     interfacial_length=0.01, initial=res, rtol=1e-5)
    assert abs(again.radius[0] - res.radius[-1]) < 1e-12
    assert "nodes" not in res.to_json_dict(profiles=False)


@pytest.mark.parametrize("kw", [{"resolution": 0.0}, {"grading": 2.0}, {"check_every": 0},
                                {"nodes": (0.0, 0.5, 1.0)}])
def test_mesh_options_are_validated(kw: dict) -> None:
    with pytest.raises(ParameterError):
        moving.MeshOptions(**kw)


def test_bad_grid_and_mesh_arguments() -> None:
    with pytest.raises(ParameterError, match="moving"):
        simulate("ANB", 302.0, 308.0, until=0.01, grid="adaptive")
    with pytest.raises(ParameterError):
        simulate("ANB", 302.0, 308.0, until=0.01, grid="moving", mesh={"resolution": 0.1})
    with pytest.raises(ParameterError):
        simulate("ANB", 302.0, 308.0, until=0.01, grid="moving", integrator="explicit")


@pytest.mark.slow
def test_direct_run_at_a_small_interfacial_length() -> None:
    """HHT 304 -> 308 K at ell = 3.125e-4 directly (issue 12's window for t80, which holds the
    ell -> 0 limit 0.0746 +/- 4%, docs/interfacial.md sec. 7); benchmarked 0.07511."""
    from solver.gel import HHT

    a80 = fraction_radius(equilibrium(HHT, 304.0).stretch, 0.8)
    res = simulate("HHT", 304.0, 308.0, until=0.08, grid="moving", n=400,
                   interfacial_length=3.125e-4, rtol=1e-5)
    assert 0.0735 < res.time_to_radius(a80) < 0.0779
    assert np.max(res.solid_error) < 1e-12


@pytest.mark.slow
def test_stiff_gel_burst_is_integrated_and_converged() -> None:
    """Omega = 1e4 (ANB otherwise), ell = 1e-3: the swollen edge goes through the spinodal in
    a burst at t = 0.1429; the moving grid integrates it, and its 50% dose at 400 cells is
    within 0.5% (the issue's criterion) of the 800-cell value 0.145645 (benchmarked:
    0.145625, 0.014% apart)."""
    from dataclasses import replace

    gel = replace(ANB, omega=1e4, name="stiff")
    a50 = fraction_radius(equilibrium(gel, 302.0).stretch, 0.5)
    res = simulate(gel, 302.0, 308.0, until=0.15, grid="moving", n=400,
                   interfacial_length=1e-3, rtol=1e-5)
    assert abs(res.time_to_radius(a50) / 0.145645 - 1.0) < 5e-3


def test_protocol_steps_restart_the_mesh_motion() -> None:
    """Heat, cool, heat (a schedule's shape): a(t) on the moving grid (200 cells) against the
    uniform grid (800), measured 8e-5 apart at most; 3e-4 allowed."""
    kw = dict(protocol=[(0.02, 308.0), (0.05, 302.0), (0.03, 308.0)], interfacial_length=0.005,
              rtol=1e-5, every=0.001)
    uniform = simulate("ANB", 302.0, grid="lagrangian", n=800, **kw)  # type: ignore[arg-type]
    adapted = simulate("ANB", 302.0, grid="moving", n=200, **kw)  # type: ignore[arg-type]
    assert np.max(np.abs(adapted.radius / uniform.radius - 1.0)) < 3e-4
    assert np.max(adapted.solid_error) < 1e-12


def test_the_truths_dose_times_with_their_numerical_bound(tmp_path) -> None:
    """The planner's direct truth at ANB ell = 0.005 (dosing.truth: the moving grid on
    N = 400, checked on N / 2), 50% and 80%: the uniform grid's converged values (N = 800;
    docs/interfacial.md sec. 6, converged to 1e-5) lie within 0.1% and within the stated
    numerical bound (the 400- vs 200-cell gap, a threefold safety for a second-order
    scheme); the front nucleates at the edge before the first dose; ell = 0 is no direct
    truth (the paper's model)."""
    from concurrent.futures import ThreadPoolExecutor

    from dosing import Planner, Scenario, SolverSettings
    from solver.phase import nucleation_level

    truth = SolverSettings(interfacial_length=0.005)
    assert (truth.direct, truth.grid, truth.n, truth.check().n) == (True, "moving", 400, 200)
    radii = fraction_radius(equilibrium(ANB, 302.0).stretch, np.array([0.5, 0.8]))
    planner = Planner(cache_path=tmp_path / "c.sqlite", executor=ThreadPoolExecutor(1))
    try:
        fine, coarse = (planner.trajectory(Scenario(ANB, 302.0, 308.0, settings=s),
                                           need_radius=float(radii[-1]))
                        for s in (truth, truth.check()))
    finally:
        planner.close()
    for a, ref in zip(radii, (0.024513, 0.081977), strict=True):
        t, t_check = fine.time_to_radius(a), coarse.time_to_radius(a)
        bound = abs(t - t_check) / t
        assert abs(t / ref - 1.0) < 1e-3
        assert abs(t / ref - 1.0) <= bound + 2e-5  # + the reference's own rounding
    nuc = fine.nucleation_time(nucleation_level(ANB, 302.0, 308.0))
    assert 0.0 < nuc < fine.time_to_radius(radii[0])
    assert not SolverSettings(interfacial_length=0.0).direct
