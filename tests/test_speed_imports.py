"""Lazy imports (issue 23): the CLI, ``solver`` and ``dosing`` load only what a call uses.

Each check runs a fresh interpreter (the modules of this test process are already loaded),
so it fails as soon as a module-level import of scipy.stats, matplotlib, fastapi, pint or
the numba kernels comes back on one of these paths.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

HEAVY = ("scipy.stats", "scipy.optimize", "matplotlib", "fastapi", "pint", "numba",
         "solver.thermo", "solver.full.kernels", "solver.full.run", "pydantic")


def _loaded(code: str) -> list[str]:
    """The HEAVY modules a fresh interpreter holds after running ``code``."""
    probe = (f"import sys\n{code}\nimport json\n"
             f"print(json.dumps([m for m in {HEAVY!r} if m in sys.modules]))")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("code", ["import api.cli", "import solver", "import dosing",
                                  "import solver.errors, solver.gel, solver.full.result"])
def test_import_loads_no_heavy_module(code: str) -> None:
    assert _loaded(code) == []


def test_dose_help_imports_only_its_command() -> None:
    code = ("import contextlib, io\nimport api.cli\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            "    try:\n        api.cli.main(['dose', '--help'])\n"
            "    except SystemExit:\n        pass\n"
            "assert 'api.commands.sweep' not in sys.modules, 'other commands imported'")
    assert _loaded(code) == []


def test_chosen_commands() -> None:
    from api.cli import COMMANDS, chosen_commands

    assert chosen_commands(["phase-map", "--out", "x.png"]) == ["phase_map"]
    assert chosen_commands(["dose", "--help"]) == ["dose"]
    assert chosen_commands(["--help"]) is None and chosen_commands([]) is None
    assert chosen_commands(["nonsense"]) is None  # argparse names the valid commands
    assert "dose" in COMMANDS


def test_grid_names_match_the_solver_registry() -> None:
    """dosing.runs.scenario.GRIDS is written out (no kernels at import): it must stay the
    registry's names, in its order."""
    from dosing.runs.scenario import GRIDS
    from solver.full import GRIDS as REGISTRY

    assert GRIDS == tuple(REGISTRY)


def test_lazy_package_names_resolve() -> None:
    """Every name the lazy packages export resolves, and ``solver.equilibrium`` stays the
    function (as when the package imported it eagerly), also after the submodule loads."""
    import dosing
    import solver
    import solver.equilibrium as eq_module
    import solver.full

    for pkg in (solver, dosing, solver.full):
        for name in pkg.__all__:
            assert getattr(pkg, name) is not None, (pkg.__name__, name)
    assert callable(solver.equilibrium) and eq_module is solver.equilibrium
    assert sys.modules["solver.equilibrium"].equilibrium is solver.equilibrium
    with pytest.raises(AttributeError):
        solver.no_such_name  # noqa: B018
    json.dumps(sorted(dosing.__all__))


def test_a_front_cli_dose_loads_no_kernel(tmp_path) -> None:
    """A front-model ``thermogel dose`` calls the scalar kernels' Python bodies
    (``solver.jit.Kernel``) and Brent's root from ``solver.roots``: it imports neither numba,
    scipy.optimize nor the drug's solute model, once its jump's delayed-law lattice (the
    envelope's front-law part, issue 36: one sub-second run per jump, any size, any dose up
    to the one it ran to) is stored."""
    from api.cli import main

    first = ["dose", "--gel", "ANB", "--t-start", "302", "--t-end", "308", "--fraction", "0.9",
             "--dry-radius-um", "20", "--json", "--cache", str(tmp_path / "c.sqlite")]
    assert main(first) == 0  # stores the lattice run (this process loads the kernels)
    code = ("import contextlib, os\n"
            f"os.environ['THERMOGEL_CACHE'] = {str(tmp_path / 'c.sqlite')!r}\n"
            "import api.cli\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            "    assert api.cli.main(['dose', '--gel', 'ANB', '--t-start', '302', '--t-end',"
            " '308', '--fraction', '0.8', '--dry-radius-um', '50']) == 0\n"
            "assert 'solver.solute' not in sys.modules\n")
    loaded = _loaded("import io\n" + code)
    assert not {"numba", "solver.full.kernels", "scipy.optimize"} & set(loaded), loaded


def test_the_python_bodies_are_the_kernels_bit_for_bit() -> None:
    """What a Kernel runs before it is compiled gives the compiled kernel's own numbers.
    Its body runs with the C library's log1p (``solver.jit.LIBM``), as the compiled kernel
    does: numpy's own log1p (its SIMD code on an AVX-512 machine, AMD EPYC) differs in the
    last bit for 7 % of these phi (the plain ``py_func`` here: 1,474 of 20,000), and a
    Dask sweep's front-model times then moved by 4e-14 from the inline sweep's."""
    import numpy as np

    from solver.front.evolve import _clenshaw, _invert_decreasing
    from solver.front.maxwell import _lower_hull
    from solver.thermo import mixing_energy, osmotic_dp, osmotic_p

    rng = np.random.default_rng(3)
    phi = rng.uniform(1e-6, 1.0 - 1e-9, 20_000)
    chi = (-12.947 + 0.04496 * 305.0, 17.92 - 0.0569 * 305.0)
    for kernel in (osmotic_p, osmotic_dp):
        c, body = kernel.compiled, kernel.python_body
        assert np.array_equal(c(phi, *chi), body(phi, *chi))
        assert all(c(float(x), *chi) == body(float(x), *chi) for x in phi[:2000])
        assert kernel.loaded and kernel(0.3, *chi) == c(0.3, *chi)  # compiled once loaded
    jac = 1.0 / (1.0 - phi)
    assert np.array_equal(mixing_energy.compiled(jac, *chi), mixing_energy.python_body(jac, *chi))
    edges = np.array([0.0, 1.0, 2.0, 1e-300])  # the log's pole and beyond: as C gives them
    with np.errstate(all="ignore"):
        assert np.array_equal(osmotic_p.compiled(edges, *chi), osmotic_p.python_body(edges, *chi),
                              equal_nan=True)
    x = np.sort(rng.uniform(0.1, 5.0, 4001))
    y = np.sin(3.0 * x) + x * x
    assert np.array_equal(_lower_hull.compiled(x, y), _lower_hull.python_body(x, y))
    coef = np.array([1.0, -0.5, 0.1, -0.01, 0.001])  # a decreasing series on [0, 1]
    d = -np.polynomial.chebyshev.chebder(coef) * 2.0
    targets = np.linspace(0.7, 1.5, 9)
    assert np.array_equal(_invert_decreasing.compiled(coef, d, 0.0, 1.0, targets, 1e-14, 60),
                          _invert_decreasing.python_body(coef, d, 0.0, 1.0, targets, 1e-14, 60))
    assert _clenshaw.compiled(coef, 0.0, 1.0, 0.3) == _clenshaw.python_body(coef, 0.0, 1.0, 0.3)


def test_a_kernel_calls_the_kernels_it_names_compiled() -> None:
    """A Kernel's dispatcher is built with the Kernels its body names replaced by their
    dispatchers (numba cannot call a Python object); the module keeps the Kernels."""
    from solver.front import evolve

    compiled = evolve._invert_decreasing.compiled
    assert compiled.py_func.__globals__["_clenshaw"] is evolve._clenshaw.compiled
    assert isinstance(evolve._clenshaw, type(evolve._invert_decreasing))
