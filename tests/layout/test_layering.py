"""Data flows one way: nothing below imports from above, and solvers never see robots."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[2] / "dualarm_qp"

#: Layer of each top-level module or subpackage, lowest first.
LAYERS = {
    "errors": 0, "_validate": 0, "se3": 0, "poses": 0, "_io": 0, "_signals": 0,
    "_compiled": 0, "_kernel": 0,  # the compiled kernel and its loader (numbers only)
    "_remade": 0,  # holders of what a pickle cannot hold, made again when unpickled
    "_lazy": 0,  # a package's names imported on first access
    "kinematics": 1,
    "task": 2, "geometry": 2,  # shapes, distances, capsules fitted to arms (kinematics)
    "collision": 2,  # the bodies and pairs of a task, their clearance (geometry)
    "step": 3,
    "solvers": 4,
    "control": 5, "viz": 5,  # draws tasks and recorded runs; knows no experiment files
    "experiments": 6, "bench": 6,
    "physics": 6,  # the task in MuJoCo: checks a run's folder, adds to its report
    "sweep": 7,  # runs experiments (6) and reuses the bench store (6)
    "bag": 6,  # a run folder as ROS 2 messages: a bag, a live view (experiments' files)
    "cell": 7,  # drives an experiment's controller (6) on two arms, MuJoCo's too (6)
    "cli": 7, "cli_commands": 7, "__main__": 7, "__init__": 7,
}


def _modules():
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE).with_suffix("")
        yield rel.parts, path


def _imports(parts: tuple[str, ...], path: Path):
    """Absolute dotted names of the package modules that ``path`` imports."""
    tree = ast.parse(path.read_text())
    here = ["dualarm_qp", *parts[:-1]]  # the package the module lives in
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = here[: len(here) - node.level + 1]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            names = [f"{mod}.{a.name}" for a in node.names]
            yield from [mod, *names]
        elif isinstance(node, ast.Import):
            yield from (a.name for a in node.names)


def _layer(dotted: str) -> tuple[str, int] | None:
    parts = dotted.split(".")
    if parts[0] != "dualarm_qp" or len(parts) < 2 or parts[1] not in LAYERS:
        return None
    return parts[1], LAYERS[parts[1]]


@pytest.mark.parametrize(("parts", "path"), list(_modules()),
                         ids=lambda v: "/".join(v) if isinstance(v, tuple) else "")
def test_no_module_imports_from_a_higher_layer(parts, path):
    top = parts[0]
    own = LAYERS[top]
    for dotted in _imports(parts, path):
        found = _layer(dotted)
        if found is None:
            continue
        name, layer = found
        assert layer <= own, f"{'/'.join(parts)} (layer {own}) imports {dotted} (layer {layer})"
        if top == "solvers":
            assert name not in ("kinematics", "task"), f"a solver imports {dotted}"
            if name == "step":
                assert dotted.startswith("dualarm_qp.step.problem"), (
                    f"solvers may only use the step problem, not {dotted}")


#: The one module that builds a DualArmController (Experiment.controller).
CONTROLLER_BUILDER = ("experiments", "experiment.py")


def _sources():
    root = PACKAGE.parent
    for path in sorted([*PACKAGE.rglob("*.py"), *(root / "benchmarks").rglob("*.py")]):
        yield path.relative_to(root), path


def _named(node: ast.expr) -> str | None:
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        return node.attr
    return None


@pytest.mark.parametrize(("rel", "path"), list(_sources()), ids=lambda v: str(v))
def test_only_experiment_controller_builds_a_controller(rel, path):
    """The package and the benchmark scripts get their controller from Experiment.controller
    (no direct DualArmController(...) call, no subclass of it), so runs, the bench and the
    suite generator step the same controller."""
    tree = ast.parse(path.read_text())
    calls = [n.lineno for n in ast.walk(tree)
             if isinstance(n, ast.Call) and _named(n.func) == "DualArmController"]
    subclasses = [n.name for n in ast.walk(tree) if isinstance(n, ast.ClassDef)
                  and any(_named(b) == "DualArmController" for b in n.bases)]
    assert not subclasses, f"{rel} subclasses DualArmController: {subclasses}"
    if rel.parts[-2:] == CONTROLLER_BUILDER and rel.parts[0] == "dualarm_qp":
        assert len(calls) == 1, f"{rel} should build the controller once, in controller()"
    else:
        assert not calls, f"{rel} builds a DualArmController (lines {calls}); use " \
                          "Experiment.controller"


def _module_name(path: Path) -> str:
    """Dotted name of a package file (a package's ``__init__.py`` is the package)."""
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _import_graph() -> dict[str, set[str]]:
    """Each package module and the package modules it imports (every import statement,
    ``TYPE_CHECKING`` blocks and function bodies included).

    ``from .a import b`` is an edge to the module ``a.b`` when there is one, else to
    ``a``; a stub's name (the compiled kernel's ``.pyi``) is no module here.
    """
    files = {_module_name(p): p for p in PACKAGE.rglob("*.py")}
    stubs = {_module_name(p) for p in PACKAGE.rglob("*.pyi")}
    graph: dict[str, set[str]] = {}
    for name, path in files.items():
        package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
        edges: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                base = (package[: len(package) - node.level + 1] if node.level else [])
                mod = ".".join(base + ([node.module] if node.module else []))
                for alias in node.names:
                    full = f"{mod}.{alias.name}"
                    if full in files:
                        edges.add(full)
                    elif full not in stubs and mod in files:
                        edges.add(mod)
            elif isinstance(node, ast.Import):
                edges.update(a.name for a in node.names if a.name in files)
        graph[name] = edges - {name}
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The import circles: each strongly connected group of two or more modules."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found: list[list[str]] = []

    def visit(v: str) -> None:  # Tarjan's algorithm
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                found.append(sorted(group))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


@pytest.mark.slow
def test_no_import_cycle():
    """No module imports a module that (through the package) imports it back, not even
    for type annotations only: each module's place in the layers is then well defined."""
    assert _cycles(_import_graph()) == []


def test_the_cycle_check_finds_a_circle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []
