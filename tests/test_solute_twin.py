"""The D0 = 0 twin of a drug run (``squeezed_fraction``): taken as the expelled fraction
where that is its release exactly (``twin="exact"``, the default), run where it is not."""

import numpy as np
import pytest

from solver.full import simulate
from solver.solute import Hindrance, Solute, release


@pytest.fixture(scope="module")
def mechanics():
    """A thin running front on the moving grid (what the planner's drug runs sample)."""
    return simulate("ANB", 302, 308, until=0.06, grid="moving", n=100,
                    interfacial_length=1e-3, rtol=1e-5, every=0.06 / 300)


def test_the_exact_twin_is_the_run_twin_to_round_off(mechanics) -> None:
    """No sieving, a perfect sink: the conservative upwind scheme keeps a uniform pore
    concentration uniform, so the run twin releases the expelled fraction; taking that
    fraction instead changes nothing but the cost (the release itself is the same run)."""
    sol = Solute(diffusivity=0.05)
    run = release(mechanics, sol, twin="run")
    exact = release(mechanics, sol)
    assert exact.squeezed_fraction.size == run.squeezed_fraction.size == mechanics.t.size
    assert run.squeezed_fraction[-1] > 0.3  # the front has expelled fluid
    assert np.max(np.abs(exact.squeezed_fraction - run.squeezed_fraction)) < 1e-12
    assert np.array_equal(exact.released_fraction, run.released_fraction)
    assert np.array_equal(exact.squeezed_fraction, exact.expelled_fraction.clip(min=0.0))


@pytest.mark.parametrize("case", ["sieved", "finite medium"])
def test_the_twin_runs_where_the_expelled_fraction_is_not_its_release(mechanics,
                                                                      case) -> None:
    """A sieving mesh holds solute back from the expelled fluid: there the twin is run,
    whatever ``twin`` asks; so it is with a finite medium (its twin releases the expelled
    fraction too, to round-off, but the exact form is not assumed there)."""
    if case == "sieved":
        sol = Solute(diffusivity=0.05, hindrance=Hindrance(mesh=0.3))
    else:
        sol = Solute(diffusivity=0.05, release_volume=20.0)
    exact, run = release(mechanics, sol), release(mechanics, sol, twin="run")
    assert np.array_equal(exact.squeezed_fraction, run.squeezed_fraction)
    gap = np.max(np.abs(run.squeezed_fraction - run.expelled_fraction))
    if case == "sieved":
        assert gap > 1e-4  # the expelled fraction would have been wrong here
    else:
        assert 0.0 < gap < 1e-10  # run (bit for bit the run twin), not taken
