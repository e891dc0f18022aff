"""The coupled release of a batch into one medium, at its home in the solver (issue 35):
``solver.solute.medium.coupled_release`` gives bit for bit what the kernel gave when it
lived in ``dosing/batch_medium.py`` (commit 70c49c7), and the planner's names reach it.

The mechanics are synthetic (a uniform sphere on 8 dry cells whose volume falls as sqrt(s),
two bands), so the reference depends on the coupled solve alone: three classes, one of them
resting past its band's end, in a finite medium, two steps per interval."""

from __future__ import annotations

import numpy as np
import pytest

from solver.errors import ParameterError
from solver.solute import MediumRelease, Solute, coupled_release

TIMES = np.array([0.0, 0.01, 0.05, 0.1, 0.2, 0.4])
# written by dosing.batch_medium.coupled_release at 70c49c7 (before the move)
OLD_RELEASED = ["0x0.0p+0", "0x1.39c2fb3ecfeaep-2", "0x1.14f460faefedbp-1",
                "0x1.43a97bfcbd394p-1", "0x1.6bd5973fd77d8p-1", "0x1.8d106362c17e0p-1"]
OLD_CONCENTRATION = ["0x0.0p+0", "0x1.2d9315597a59bp-4", "0x1.e71ecc1307dacp-4",
                     "0x1.0f188d859f9e4p-3", "0x1.2240b419af8d8p-3", "0x1.2eeed8ee0ce3ep-3"]
OLD_CLASSES = [
    ["0x0.0p+0", "0x1.c5be8f857a270p-2", "0x1.5142eaf107f9ap-1", "0x1.790426eae0202p-1",
     "0x1.7101a209d3957p-1", "0x1.68f9330f870d8p-1"],
    ["0x0.0p+0", "0x1.406676eac7958p-2", "0x1.1d8eb2b5890a4p-1", "0x1.4e43626b86f35p-1",
     "0x1.8284674b81830p-1", "0x1.a5e9dc38e17f3p-1"],
    ["0x0.0p+0", "0x1.a2c03f3784500p-3", "0x1.bcd2f99517512p-2", "0x1.0e6c89faab5d6p-1",
     "0x1.4294dffb145a6p-1", "0x1.7bb564e008c1ap-1"]]
OLD_STEPS, OLD_BALANCE = 252, "0x1.8000000000000p-45"


def _hex(values) -> np.ndarray:
    return np.array([[float.fromhex(x) for x in row] for row in values]) \
        if isinstance(values[0], list) else np.array([float.fromhex(x) for x in values])


def _mechanics(a3_end: float, samples: int, span: float) -> tuple[np.ndarray, np.ndarray]:
    """A uniform sphere (8 dry cells, uniform in rho) shrinking from a0^3 = 3 to ``a3_end``
    as sqrt(s / span): node volumes r_k^3 = (k / 8)^3 a^3."""
    n = 8
    s = np.linspace(0.0, span, samples)
    a3 = 3.0 + (a3_end - 3.0) * np.sqrt(s / span)
    return s, ((np.arange(n + 1) / n) ** 3)[None, :] * a3[:, None]


def _case() -> MediumRelease:
    (sa, s3a), (sb, s3b) = _mechanics(2.0, 9, 0.2), _mechanics(1.6, 13, 0.3)
    return coupled_release([sa, sb], [s3a, s3b], Solute(diffusivity=5.0, partition=2.0),
                           [0.5, 1.0, 2.0], [0.2, 0.5, 0.3], 4.0, TIMES, sub=2,
                           band=[0, 1, 1])


def test_the_solver_entry_point_reproduces_the_old_kernel_bit_for_bit() -> None:
    mr = _case()
    assert isinstance(mr, MediumRelease)
    assert np.array_equal(mr.t, TIMES)
    assert np.array_equal(mr.released, _hex(OLD_RELEASED))
    assert np.array_equal(mr.concentration, _hex(OLD_CONCENTRATION))
    assert np.array_equal(mr.class_released, _hex(OLD_CLASSES))
    assert mr.steps == OLD_STEPS and mr.mass_balance_error == float.fromhex(OLD_BALANCE)
    assert mr.diagnostics == {"grid_points": 253, "sub": 2, "n": 8}
    assert mr.medium_volume == 4.0 and np.array_equal(mr.nu, [0.2, 0.5, 0.3])


def test_the_planner_names_are_the_solvers() -> None:
    """The planner's drug batch (dosing.population.medium, the one user of the coupled solve)
    calls the solver's own names, with no physics of its own."""
    import dosing.population.medium as planner
    import solver.solute.medium as medium

    assert planner.coupled_release is medium.coupled_release is coupled_release
    assert planner.MediumRelease is MediumRelease


def test_bad_input_names_the_field() -> None:
    s, s3 = _mechanics(2.0, 9, 0.2)
    with pytest.raises(ParameterError) as exc:
        coupled_release(s, s3, Solute(diffusivity=1.0), [1.0], [1.0], 0.0, TIMES)
    assert exc.value.field == "medium_volume"
    with pytest.raises(ParameterError) as exc:
        coupled_release(s, s3, Solute(diffusivity=1.0), [1.0], [1.0], None, TIMES, sub=0)
    assert exc.value.field == "sub"
