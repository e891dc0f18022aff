"""Why a thin front takes smaller steps on the moving grid (docs/moving_mesh.md sec. 7.3).

    PYTHONPATH=$PWD .venv/bin/python -m benchmarks.thin_front [--gel ANB]

The planner's direct run (400 cells, rtol 1e-5, outputs every t = 0.002) at ell = 1e-3, 1e-4
and 3e-5, watched from outside (the integrator's ``rodas_run`` and the rezoner's check are
wrapped for the run, then restored; the steps are the same as unwrapped):

- the interface's actual width (|d ln J / d rho| above half its peak) in ell, the cells
  across it and the steepest cell, at t = 0.01 and 0.05;
- the error estimate of one step of fixed size (2.5e-5, 5e-5, 1e-4) from the state the run
  reached at t = 0.005 ... 0.08 (the Jacobian of that state), the front's velocity in the dry
  coordinate and the step the controller chose there;
- where the rejected steps fall: in the first accepted step after a mesh check, or later.
"""

from __future__ import annotations

import argparse
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np

from solver.full import ale, moving, simulate
from solver.full import rosenbrock as ros

CASES = {"ANB": 302.0, "HHT": 304.0}
ELLS = (1e-3, 1e-4, 3e-5)
PROBE_T = (0.005, 0.01, 0.02, 0.05, 0.08)
PROBE_H = (2.5e-5, 5e-5, 1e-4)
WIDTH_T = (0.01, 0.05)


@contextmanager
def watched(probes: dict, widths: dict, rejections: np.ndarray) -> Iterator[None]:
    """Wrap ``ros.rodas_run`` (one accepted step per call, the same steps; probe the error
    estimate at PROBE_T; count the rejections in the first step after a check) and
    ``moving.Rezoner.__call__`` (the state at WIDTH_T)."""
    run, check = ros.rodas_run, moving.Rezoner.__call__
    after_check = [True]

    def rodas_run(grid, state, t_stop, t_seg, budget, par, heat, geo, band, buf, method,
                  control):
        c = control.counters
        while True:
            r0, s0 = c[ros.C_REJECTED], c[ros.C_STEPS]
            st = run(grid, state, t_stop, t_seg, min(budget, s0 + 1), par, heat, geo, band,
                     buf, method, control)
            rejections[0 if after_check[0] else 1] += c[ros.C_REJECTED] - r0
            if c[ros.C_STEPS] > s0:
                after_check[0] = False
            t = float(state.tt[0])
            for when in PROBE_T:
                if when not in probes and t >= when and control.ctrl[3] == 1.0:
                    errs = [ros.rodas_try(grid, state.y, state.f, t, h, par, heat, geo, band,
                                          buf, method, control)[1] for h in PROBE_H]
                    ale.refresh(geo, t)
                    k = _steepest(state.y[:-1], geo[0])
                    probes[when] = (t, errs, float(geo[ale.R_VNOW, k + 1]),
                                    float(control.ctrl[0]))
            if st != ros.RUN_BUDGET or c[ros.C_STEPS] >= budget or state.tt[0] >= t_stop:
                return st

    def rezoner_call(self, y, geo):
        out = check(self, y, geo)
        after_check[0] = True
        n = geo.shape[1] - 1
        for when in WIDTH_T:
            if when not in widths and y[n] >= when:
                widths[when] = (y[:n].copy(), geo[0].copy())
        return out

    ros.rodas_run, moving.Rezoner.__call__ = rodas_run, rezoner_call
    try:
        yield
    finally:
        ros.rodas_run, moving.Rezoner.__call__ = run, check


def _gradient(radii: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(|d ln J / d rho| between cell centres, the centres)."""
    lj = np.log(np.diff(np.concatenate([[0.0], radii**3])) / np.diff(nodes**3))
    centre = 0.5 * (nodes[1:] + nodes[:-1])
    return np.abs(np.diff(lj) / np.diff(centre)), centre


def _steepest(radii: np.ndarray, nodes: np.ndarray) -> int:
    """The cell left of the steepest pair."""
    return int(np.argmax(_gradient(radii, nodes)[0]))


def width(radii: np.ndarray, nodes: np.ndarray, ell: float) -> str:
    """The interface's width at half its peak gradient (in ell), cells across, steepest cell."""
    g, centre = _gradient(radii, nodes)
    k = int(np.argmax(g))
    a, b = k, k
    while a > 0 and g[a - 1] >= 0.5 * g[k]:
        a -= 1
    while b < g.size - 1 and g[b + 1] >= 0.5 * g[k]:
        b += 1
    return (f"width {(centre[b + 1] - centre[a]) / ell:.2f} ell, {b - a + 1} cells across, "
            f"steepest cell {(nodes[k + 1] - nodes[k]) / ell:.3f} ell")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--gel", choices=tuple(CASES), action="append")
    args = parser.parse_args()
    simulate("ANB", 302.0, 308.0, until=1e-3, grid="moving", n=20, interfacial_length=0.05)
    for gel in args.gel or list(CASES):
        for ell in ELLS:
            probes: dict = {}
            widths: dict = {}
            rejections = np.zeros(2, dtype=np.int64)
            with watched(probes, widths, rejections):
                res = simulate(gel, CASES[gel], 308.0, until=0.1, grid="moving", n=400,
                               interfacial_length=ell, rtol=1e-5, every=0.1 / 50)
            d = res.diagnostics
            print(f"{gel} ell = {ell:g}: {d['steps']} accepted, {d['rejected']} rejected "
                  f"({rejections[0]} in the first step after a check, {rejections[1]} later)",
                  flush=True)
            for when, (radii, nodes) in sorted(widths.items()):
                print(f"   t = {when}: {width(radii, nodes, ell)}", flush=True)
            for _when, (t, errs, v, h) in sorted(probes.items()):
                order = np.log(errs[-1] / errs[0]) / np.log(PROBE_H[-1] / PROBE_H[0])
                print(f"   t = {t:.4f}: front velocity {v:+.3f}, step {h:.2e}; error estimate "
                      f"at h = {', '.join(f'{x:g}' for x in PROBE_H)}: "
                      f"{', '.join(f'{e:.2e}' for e in errs)} (slope {order:.2f})", flush=True)


if __name__ == "__main__":
    main()
