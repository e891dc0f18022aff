"""No import circle among the project's modules (module-level and deferred imports alike;
imports under ``if TYPE_CHECKING`` are for annotations only and not counted)."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("solver", "dosing", "api", "thermogel")


def _module_name(path: Path, root: Path = ROOT) -> str:
    parts = list(path.relative_to(root).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path, name: str, modules: set[str], annotations: bool = False) -> set[str]:
    tree = ast.parse(path.read_text())
    skip: set[int] = set()
    for node in ast.walk(tree):  # ``if TYPE_CHECKING:`` blocks (unless ``annotations``)
        if (not annotations and isinstance(node, ast.If)
                and "TYPE_CHECKING" in ast.unparse(node.test)):
            skip.update(id(n) for b in node.body for n in ast.walk(b))
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out: set[str] = set()
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                up = package.split(".")
                up = up[:len(up) - (node.level - 1)]
                base = ".".join([*up, base] if base else up)
            # ``from pkg import sub``: an edge to the submodule (the package's __init__ runs
            # first, but that edge is the package's own); ``from pkg import name``: to pkg
            targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base
                       for a in node.names]
        else:
            continue
        out.update(t for t in targets if t in modules and t != name)
    return out


def import_graph(packages: tuple[str, ...] = PACKAGES, annotations: bool = False,
                 root: Path = ROOT) -> dict[str, set[str]]:
    files = {_module_name(p, root): p for pkg in packages for p in (root / pkg).rglob("*.py")}
    mods = set(files)
    return {m: _imports(p, m, mods, annotations) for m, p in files.items()}


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_import_circle() -> None:
    graph = import_graph()
    # a package's __init__ re-exporting its modules is not a circle of the design: leave
    # out the edges from a module to its own package's __init__
    pruned = {m: {t for t in ts if not m.startswith(t + ".")} for m, ts in graph.items()}
    found = cycles(pruned)
    assert not found, found


def test_the_checker_finds_a_circle() -> None:
    assert cycles({"a": {"b"}, "b": {"a"}, "c": set()}) == [["a", "b"]]


def test_the_planner_has_no_circle_even_in_its_annotations() -> None:
    """dosing/ (issue 35): acyclic counting deferred and ``TYPE_CHECKING`` imports too (the
    answers reach their tables through the presenters registry, not by importing them)."""
    graph = import_graph(("dosing",), annotations=True)
    pruned = {m: {t for t in ts if not m.startswith(t + ".")} for m, ts in graph.items()}
    found = cycles(pruned)
    assert not found, found


def test_the_planner_has_no_circle_through_its_own_package() -> None:
    """dosing/ (issue 35) without the pruning above: no module reaches back into
    ``dosing/__init__`` (the one-shot planner was there, imported by ``question/`` and
    ``batch_schedule``, an 8-module circle; it is ``dosing.planner.one_shot`` now)."""
    found = cycles(import_graph(("dosing",), annotations=True))
    assert not found, found


def test_the_edges_tell_a_submodule_from_a_name() -> None:
    """``from . import sub`` is an edge to the submodule, ``from . import name`` to the
    package: a circle through a package's __init__ is seen, one through a sibling is not
    invented."""
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        pkg = Path(tmp) / "pk"
        pkg.mkdir()
        (pkg / "__init__.py").write_text("from .a import f\n")
        (pkg / "a.py").write_text("def f():\n    from . import b\n")
        (pkg / "b.py").write_text("def g():\n    from . import name\n")
        graph = import_graph(("pk",), annotations=True, root=Path(tmp))
    assert graph == {"pk": {"pk.a"}, "pk.a": {"pk.b"}, "pk.b": {"pk"}}
    assert cycles(graph) == [["pk", "pk.a", "pk.b"]]
