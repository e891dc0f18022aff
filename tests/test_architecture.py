"""Architecture rules that can be checked by reading the code (issue 16)."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
Fn = ast.FunctionDef | ast.AsyncFunctionDef
MAX_PARAMETERS = 12  # a plain function: more than this wants an options object
MAX_KERNEL_PARAMETERS = 16  # a numba kernel: more wants a bundle (solver/full/rosenbrock.py)
# rodas_run as it was before issue 21: 45 flat arrays and scalars
OLD_RODAS_RUN = """
@njit(cache=True)
def rodas_run(grid, y, f, yold, fold, tt, t_stop, t_seg, par, geo, work, lower, upper,
              jband, jc, jd, je, lu, ipiv, cm, dm, xm, em, spiv, zbuf, u, ytmp, ftmp, ynew,
              fnew, errv, scale, rtol, atol, tableau, acoef, ccoef, mcoef, ecoef, counters,
              ctrl, rec, max_steps, jac_mode, heat):
    pass
"""


def _functions(tree: ast.AST, where: str) -> list[tuple[str, Fn]]:
    return [(f"{where}:{node.lineno} {node.name}", node) for node in ast.walk(tree)
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))]


def _package_functions() -> list[tuple[str, Fn]]:
    out = []
    for package in ("solver", "dosing", "api"):
        for path in sorted((ROOT / package).rglob("*.py")):
            out += _functions(ast.parse(path.read_text()), str(path.relative_to(ROOT)))
    return out


def _count(node: Fn) -> int:
    a = node.args
    names = [*a.posonlyargs, *a.args, *a.kwonlyargs]
    k = len(names) + (a.vararg is not None) + (a.kwarg is not None)
    return k - bool(names and names[0].arg in ("self", "cls"))


def _is_kernel(node: Fn) -> bool:
    """Compiled by numba (@njit, @numba.njit(...), @jit, @numba.jit(...), solver.jit's
    @kernel)."""
    return any("jit" in ast.unparse(d) or ast.unparse(d) == "kernel"
               for d in node.decorator_list)


def _too_long(functions: list[tuple[str, Fn]]) -> list[tuple[str, int, bool]]:
    """(where, parameters, is a kernel) of the functions over their limit:
    MAX_KERNEL_PARAMETERS for numba kernels, else MAX_PARAMETERS."""
    return [(where, _count(node), _is_kernel(node)) for where, node in functions
            if _count(node) > (MAX_KERNEL_PARAMETERS if _is_kernel(node) else MAX_PARAMETERS)]


def test_no_function_takes_more_than_twelve_parameters_outside_numba_kernels() -> None:
    """Options objects instead of long signatures."""
    long = [(where, k) for where, k, kernel in _too_long(_package_functions()) if not kernel]
    assert not long, long


def test_no_numba_kernel_takes_more_than_sixteen_parameters() -> None:
    """Kernels take typed bundles (numba NamedTuples built once per run) instead of flat
    arrays: the integrator's Jacobian, stage buffers, state, method and controller."""
    long = [(where, k) for where, k, kernel in _too_long(_package_functions()) if kernel]
    assert not long, long


def test_the_checker_flags_long_signatures() -> None:
    """The rule can fail: the old 45-parameter rodas_run is flagged (as a kernel), and so
    is a plain function of 13 parameters, while a 16-parameter kernel passes."""
    def params(k: int) -> str:
        return ", ".join(f"p{i}" for i in range(k))

    source = (OLD_RODAS_RUN
              + f"\n@njit(cache=True)\ndef fine_kernel({params(16)}):\n    pass\n"
              + f"\n@numba.njit\ndef long_kernel({params(17)}):\n    pass\n"
              + f"\ndef plain({params(13)}):\n    pass\n"
              + f"\nclass C:\n    def method(self, {params(12)}):\n        pass\n")
    flagged = _too_long(_functions(ast.parse(source), "synthetic"))
    assert [(where.split()[-1], k, kernel) for where, k, kernel in flagged] == [
        ("rodas_run", 45, True), ("long_kernel", 17, True), ("plain", 13, False)]


@pytest.mark.parametrize("package", ["solver", "dosing"])
def test_solver_and_dosing_import_neither_fastapi_nor_matplotlib(package: str) -> None:
    code = (f"import sys, {package}; bad = [m for m in ('fastapi', 'uvicorn', 'matplotlib') "
            "if m in sys.modules]; print(bad); sys.exit(1 if bad else 0)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr
