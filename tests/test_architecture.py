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


# ------------------------------------------- the planner holds no physics kernels (issue 35)
NUMBA_DECORATORS = {"njit", "jit", "generated_jit", "vectorize", "guvectorize", "cfunc",
                    "stencil", "jitclass"}
# dosing/batch_medium.py as it was before issue 35 (the coupled march in the planner)
OLD_BATCH_MEDIUM = """
import numpy as np
from numba import njit

from solver.errors import ParameterError, SolverError
from solver.solute import Solute
from solver.solute.kernels import A_N, A_U, D_COEF, GAMMA, _solve, conductances, operator


@njit(cache=True)
def _march(grid, m):
    _solve(grid, m)
"""


def _is_solver(module: str) -> bool:
    return module == "solver" or module.startswith("solver.")


def _private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def _numba_uses(tree: ast.AST, where: str) -> list[str]:
    """numba in a module: ``import numba[.x]``, ``from numba[.x] import ...``, the solver's
    numba gate ``solver.jit`` imported, and functions or classes under a numba decorator
    (``@njit``, ``@numba.jit(...)``, ``@vectorize``, ...)."""
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [f"{where}:{node.lineno} import {a.name}" for a in node.names
                    if a.name.split(".")[0] == "numba" or a.name == "solver.jit"]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and (
                (node.module or "").split(".")[0] == "numba" or node.module == "solver.jit"
                or node.module == "solver" and any(a.name == "jit" for a in node.names)):
            out.append(f"{where}:{node.lineno} from {node.module} import")
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            for d in node.decorator_list:
                target = d.func if isinstance(d, ast.Call) else d
                name = target.attr if isinstance(target, ast.Attribute) else \
                    getattr(target, "id", "")
                if name in NUMBA_DECORATORS:
                    out.append(f"{where}:{node.lineno} @{ast.unparse(d)} {node.name}")
    return out


def _private_solver_names(tree: ast.AST, where: str) -> list[str]:
    """Private solver names a module reaches: ``from solver.x import _name``, a private
    module (``solver._x``, ``from solver import _x``), or ``_name`` read off anything it
    imported from ``solver`` (``kernels._solve`` after ``import solver.solute.kernels as
    kernels``).  Its own private names and a public solver name bound to a private alias
    (``import register as _register``) are its business."""
    out = []
    bound: set[str] = set()  # names this module bound to something of the solver's
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                if _is_solver(a.name):
                    bound.add(a.asname or "solver")
                    if any(_private(p) for p in a.name.split(".")):
                        out.append(f"{where}:{node.lineno} import {a.name}")
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and \
                _is_solver(node.module or ""):
            bound.update(a.asname or a.name for a in node.names)
            bad = [a.name for a in node.names if _private(a.name)]
            if bad or any(_private(p) for p in node.module.split(".")):
                out.append(f"{where}:{node.lineno} from {node.module} import "
                           f"{', '.join(bad) or '...'}")
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and _private(node.attr):
            root = node.value
            while isinstance(root, ast.Attribute):
                root = root.value
            if isinstance(root, ast.Name) and root.id in bound:
                out.append(f"{where}:{node.lineno} {ast.unparse(node)}")
    return out


def _dosing_modules() -> list[tuple[str, ast.AST]]:
    return [(str(p.relative_to(ROOT)), ast.parse(p.read_text()))
            for p in sorted((ROOT / "dosing").rglob("*.py"))]


def test_dosing_holds_no_numba() -> None:
    """The planner holds no compiled physics: kernels live in solver/ (issue 35; the batch's
    coupled march moved to solver/solute/medium.py)."""
    found = [x for where, tree in _dosing_modules() for x in _numba_uses(tree, where)]
    assert not found, found


def test_dosing_imports_no_private_solver_names() -> None:
    """The planner reaches the solver through its public names only."""
    found = [x for where, tree in _dosing_modules() for x in _private_solver_names(tree, where)]
    assert not found, found


def test_the_checkers_flag_numba_and_private_solver_names() -> None:
    """The rules can fail: the old dosing/batch_medium.py is flagged on both (its numba
    import and kernel, its import of kernels._solve), and so are the other forms, while
    public names, a module's own private names and private aliases pass."""
    old = ast.parse(OLD_BATCH_MEDIUM)
    assert [x.split(" ", 1)[1] for x in _numba_uses(old, "old")] == [
        "from numba import", "@njit(cache=True) _march"]
    assert [x.split(" ", 1)[1] for x in _private_solver_names(old, "old")] == [
        "from solver.solute.kernels import _solve"]
    flagged = """
import numba
import numba.typed
from solver.jit import kernel
import solver.solute.kernels as kern
import solver._hidden
from solver import _secret

@numba.jit(nopython=True)
def a(x):
    return kern._solve(x) + solver.solute.kernels._apply(x)

@vectorize
def b(x):
    return x
"""
    tree = ast.parse(flagged)
    assert len(_numba_uses(tree, "s")) == 5, _numba_uses(tree, "s")
    assert [x.split(" ", 1)[1] for x in _private_solver_names(tree, "s")] == [
        "import solver._hidden", "from solver import _secret", "kern._solve",
        "solver.solute.kernels._apply"]
    clean = ast.parse("""
import numpy as np
from solver.presenters import register as _register
from solver.solute import MediumRelease, coupled_release
from .batch_truth import _private_helper

def njit_like(x):
    return np.asarray(x).__class__, _private_helper(x)._y
""")
    assert _numba_uses(clean, "c") == [] and _private_solver_names(clean, "c") == []


# ----------------------------------------------------------- one request (issue 35)
AXIS_ATTRS = {"heating", "protocol", "size_distribution", "drug", "sizes", "key"}
AXIS_TYPES = {"Fluid", "Drug", "OneBead", "Batch", "Jump", "Heating", "Dose", "Schedule",
              "DoseRequest", "ScheduleRequest", "DrugDoseRequest", "DrugScheduleRequest",
              "Protocol", "SizeDistribution", "DrySizes", "DrugModel"}
# the planner's question code and the HTTP adapter: they look cells up, never branch on an
# axis (api/requests.py and dosing/question/legacy.py are where a body or an old request
# picks its axes' values: exempt)
NO_AXIS_BRANCH = ("dosing/question/__init__.py", "dosing/question/request.py",
                  "dosing/question/cells.py", "dosing/question/result.py", "api/service.py",
                  "dosing/planner.py")


def axis_branches(source: str, where: str) -> list[str]:
    """Branches on an axis: isinstance against an axis's type, getattr of an axis field, a
    comparison of an axis field (``req.heating is None``, ``payload.key == "drug"``)."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
            args = node.args
            if node.func.id == "isinstance" and len(args) == 2:
                names = {n.id for n in ast.walk(args[1]) if isinstance(n, ast.Name)}
                if names & AXIS_TYPES:
                    out.append(f"{where}:{node.lineno} isinstance {sorted(names)}")
            if (node.func.id == "getattr" and len(args) >= 2
                    and isinstance(args[1], ast.Constant) and args[1].value in AXIS_ATTRS):
                out.append(f"{where}:{node.lineno} getattr {args[1].value}")
        if isinstance(node, ast.Compare):
            sides = [node.left, *node.comparators]
            for side in sides:
                if isinstance(side, ast.Attribute) and side.attr in AXIS_ATTRS:
                    out.append(f"{where}:{node.lineno} compares .{side.attr}")
    return out


def test_the_question_code_and_the_http_adapter_do_not_branch_on_an_axis() -> None:
    found = [hit for rel in NO_AXIS_BRANCH
             for hit in axis_branches((ROOT / rel).read_text(), rel)]
    assert not found, found


def test_the_axis_branch_checker_can_fail() -> None:
    source = ("def f(req, body):\n"
              "    if req.heating is not None: pass\n"
              "    if isinstance(req.payload, Drug): pass\n"
              "    if getattr(body, 'size_distribution', None): pass\n"
              "    if req.payload.key == 'drug': pass\n"
              "    return req.cell.run(req)\n")
    hits = axis_branches(source, "x.py")
    assert len(hits) == 4, hits
    assert not axis_branches("def f(r):\n    return r.cell.now(r)\n", "y.py")


def test_every_combination_of_the_axes_has_a_cell() -> None:
    """The registry is the product of the axes' values (a new value needs its cells)."""
    import itertools

    from dosing.question.axes import HEATINGS, PAYLOADS, POPULATIONS, QUESTIONS
    from dosing.question.cells import CELLS

    product = {tuple(c.key for c in cell) for cell in
               itertools.product(PAYLOADS, POPULATIONS, HEATINGS, QUESTIONS)}
    assert set(CELLS) == product


# ----------------------------------------------------------- one run store (issue 35)
def full_solver_imports(tree: ast.AST, where: str) -> list[str]:
    """Imports of the full solver's entry point: ``from solver.full[.run] import simulate``,
    ``import solver.full[.run]`` and ``solver.full.simulate`` spelled out."""
    out = []
    for node in ast.walk(tree):
        if (isinstance(node, ast.ImportFrom) and node.module in ("solver.full", "solver.full.run")
                and any(a.name == "simulate" for a in node.names)):
            out.append(f"{where}:{node.lineno} from {node.module} import simulate")
        elif isinstance(node, ast.Import) and any(
                a.name in ("solver.full", "solver.full.run") for a in node.names):
            out.append(f"{where}:{node.lineno} import solver.full")
        elif isinstance(node, ast.Attribute) and ast.unparse(node) in (
                "solver.full.simulate", "solver.full.run.simulate"):
            out.append(f"{where}:{node.lineno} solver.full.simulate")
    return out


def test_one_dosing_module_reaches_the_full_solver() -> None:
    """Every full-solver run of the planner goes through dosing/runs/ (the store, and the
    run functions its executor calls), which take the solver from dosing/runs/full.py."""
    found = {hit.split(":")[0] for where, tree in _dosing_modules()
             for hit in full_solver_imports(tree, where)}
    assert found == {"dosing/runs/full.py"}, found


def test_the_full_solver_import_checker_can_fail() -> None:
    source = ("from solver.full import simulate\nimport solver.full\n"
              "def f():\n    from solver.full.run import simulate\n"
              "    return solver.full.simulate\n")
    assert len(full_solver_imports(ast.parse(source), "x.py")) == 4
    assert not full_solver_imports(ast.parse("from solver.full import FullResult\n"), "y.py")


# ----------------------------------------------------------- the axes' modules (issue 35)
AXIS_WORDS = {
    "payload": {"fluid", "drug", "solute"},
    "population": {"bead", "batch", "size", "sizes"},
    "heating": {"jump", "protocol", "heating", "ramp", "bath"},
    "question": {"dose", "schedule"},
}
OLD_WINGS = ("batch_drug", "batch_drug_protocol", "batch_protocol", "batch_schedule",
             "drug_dose", "drug_protocol", "drug_schedule", "protocol_dose")


def axes_named(relpath: str) -> set[str]:
    """The axes a module's path inside dosing/ names (its folders and file name, split at
    '/' and '_'): ``batch_drug.py`` names population and payload."""
    words = set(relpath.removesuffix(".py").replace("/", "_").split("_"))
    return {axis for axis, values in AXIS_WORDS.items() if words & values}


def test_no_dosing_module_is_named_after_two_axes() -> None:
    """A value of an axis is a class behind that axis's seam (dosing/question/axes.py), a
    model or population is a module in its own package: no module per combination."""
    two = {rel: sorted(axes_named(rel)) for rel in
           (str(p.relative_to(ROOT / "dosing")) for p in (ROOT / "dosing").rglob("*.py"))
           if len(axes_named(rel)) > 1}
    assert not two, two


def test_the_two_axes_rule_can_fail() -> None:
    assert all(len(axes_named(f"{name}.py")) >= 2 for name in OLD_WINGS)
    assert axes_named("population/medium.py") == set()
    assert axes_named("heating/response.py") == {"heating"}


# ----------------------------------------------------------- typed uncertainty parts
PART_KEYS = {"relative", "text"}


def dict_parts(tree: ast.AST, where: str) -> list[str]:
    """Uncertainty parts built by hand: dict literals (and ``dict(...)`` calls) holding both
    "relative" and "text" (``dosing.truth.Part`` is their type), outside a ``to_dict`` (a
    record's own plain-data form, as ``dosing.question.envelope.Part.to_dict``)."""
    exempt = {id(n) for fn in ast.walk(tree)
              if isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)) and fn.name == "to_dict"
              for n in ast.walk(fn)}
    out = []
    for node in ast.walk(tree):
        if id(node) in exempt:
            continue
        if isinstance(node, ast.Dict):
            keys = {k.value for k in node.keys if isinstance(k, ast.Constant)}
        elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
              and node.func.id == "dict"):
            keys = {k.arg for k in node.keywords}
        else:
            continue
        if PART_KEYS <= keys:
            out.append(f"{where}:{node.lineno} {ast.unparse(node)[:60]}")
    return out


def test_no_dosing_module_builds_an_uncertainty_part_as_a_dict() -> None:
    """An answer's uncertainty parts are ``dosing.truth.Part`` (their JSON the same
    {"relative": ..., "text": ...}), never a dict built by hand."""
    found = [x for where, tree in _dosing_modules() for x in dict_parts(tree, where)]
    assert not found, found


def test_the_dict_part_checker_can_fail() -> None:
    source = '''
def parts(num, why):
    out = {"numerical": {"relative": num, "text": f"numerical: {num:.2%}"}}
    out["nodes"] = {"relative": None, "full_um": [], "text": why, **out}
    return out, dict(relative=None, text=why)

class Part:
    def to_dict(self):
        return {"name": "x", "relative": self.relative, "text": self.text}
'''
    hits = dict_parts(ast.parse(source), "x.py")
    assert sorted(h.split(" ")[0] for h in hits) == ["x.py:3", "x.py:4", "x.py:5"], hits
    assert not dict_parts(ast.parse("p = Part(0.1, 'numerical')\nq = {'relative': 1.0}\n"
                                    "r = dict(text='t')\n"), "y.py")
