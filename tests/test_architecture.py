"""Architecture rules that can be checked by reading the code (issue 16)."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
MAX_PARAMETERS = 12


def _functions() -> list[tuple[str, ast.FunctionDef | ast.AsyncFunctionDef]]:
    out = []
    for package in ("solver", "dosing", "api"):
        for path in sorted((ROOT / package).rglob("*.py")):
            tree = ast.parse(path.read_text())
            out += [(f"{path.relative_to(ROOT)}:{node.lineno} {node.name}", node)
                    for node in ast.walk(tree)
                    if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))]
    return out


def _count(node: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    a = node.args
    names = [*a.posonlyargs, *a.args, *a.kwonlyargs]
    k = len(names) + (a.vararg is not None) + (a.kwarg is not None)
    return k - bool(names and names[0].arg in ("self", "cls"))


def test_no_function_takes_more_than_twelve_parameters_outside_numba_kernels() -> None:
    """Options objects instead of long signatures (numba kernels take flat arrays)."""
    long = [(where, _count(node)) for where, node in _functions()
            if _count(node) > MAX_PARAMETERS
            and not any("njit" in ast.unparse(d) for d in node.decorator_list)]
    assert not long, long


@pytest.mark.parametrize("package", ["solver", "dosing"])
def test_solver_and_dosing_import_neither_fastapi_nor_matplotlib(package: str) -> None:
    code = (f"import sys, {package}; bad = [m for m in ('fastapi', 'uvicorn', 'matplotlib') "
            "if m in sys.modules]; print(bad); sys.exit(1 if bad else 0)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr
