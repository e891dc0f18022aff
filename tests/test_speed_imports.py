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
    """dosing.scenario.GRIDS is written out (no kernels at import): it must stay the
    registry's names, in its order."""
    from dosing.scenario import GRIDS
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


def test_front_model_path_needs_no_scipy_optimize() -> None:
    """The equilibria, the jump's class and the shrunken level (the front model's inputs)
    load no scipy.optimize (0.7 s of a CLI call): solver.roots finds their roots."""
    code = ("from solver.equilibrium import equilibrium, folds\n"
            "from solver.phase import classify_jump, shrunken_level\n"
            "equilibrium('ANB', 302.0); folds('ANB')\n"
            "classify_jump('ANB', 302.0, 308.0); shrunken_level('ANB', 308.0)\n"
            "import solver.solute")
    assert "scipy.optimize" not in _loaded(code)
