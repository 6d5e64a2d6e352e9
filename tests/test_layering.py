"""The architecture as the imports show it: each layer uses only the ones below it.

kernels/ (Warp code) imports only Warp, the standard library and warpcloth.errors (itself
standard library alone); each package of warpcloth
imports only the packages below it (:data:`ORDER`); no module and no package imports
itself back through a cycle. Imports are
read from the source (including ones inside functions, excluding type-checking-only ones).
"""

import ast
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = {"warpcloth": ROOT / "warpcloth", "warpcloth.kernels": ROOT / "kernels"}

# The layers, lowest first: kernels < core < strip < sim (the strip's former name) < sheet < scene < io
# < viz < runs < track < calibrate < sweeps < cli
# (errors, units and metrics, the one ruler, sit beside all of them). track sits above runs:
# its synthetic camera films a simulation; nothing of the simulation imports it.
ORDER = (
    "warpcloth.kernels",
    "warpcloth.core",
    "warpcloth.strip",
    "warpcloth.sim",
    "warpcloth.sheet",
    "warpcloth.scene",
    "warpcloth.io",
    "warpcloth.viz",
    "warpcloth.runs",
    "warpcloth.track",
    "warpcloth.calibrate",
    "warpcloth.sweeps",
    "warpcloth.cli",
)
FORBIDDEN = {layer: ORDER[i + 1 :] for i, layer in enumerate(ORDER) if layer != "warpcloth.kernels"}


def modules() -> dict[str, Path]:
    found = {}
    for package, folder in PACKAGES.items():
        for path in folder.rglob("*.py"):
            parts = list(path.relative_to(folder).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            name = ".".join([package, *parts])
            if package == "warpcloth" and name.startswith("warpcloth.kernels"):
                continue
            found[name] = path
    return found


def _type_checking_only(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def imports_of(name: str, path: Path, known: set[str]) -> set[str]:
    """Absolute names of what module ``name`` imports (a submodule where one is named)."""
    is_package = path.name == "__init__.py"
    out = set()

    def visit(node: ast.AST) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and _type_checking_only(child):
                continue
            if isinstance(child, ast.Import):
                out.update(alias.name for alias in child.names)
            elif isinstance(child, ast.ImportFrom):
                if child.level:
                    base = name.split(".") if is_package else name.split(".")[:-1]
                    base = base[: len(base) - (child.level - 1)]
                    target = ".".join(base + ([child.module] if child.module else []))
                else:
                    target = child.module
                for alias in child.names:
                    sub = f"{target}.{alias.name}"
                    out.add(sub if sub in known else target)
            visit(child)

    visit(ast.parse(path.read_text()))
    return out


@pytest.fixture(scope="module")
def graph() -> dict[str, set[str]]:
    found = modules()
    known = set(found)
    return {name: imports_of(name, path, known) for name, path in found.items()}


def test_kernels_import_only_warp_and_the_standard_library(graph):
    # and warpcloth.errors, a leaf of the standard library alone: a refused name is the
    # library's own error, naming the argument, wherever it is refused
    for name, deps in graph.items():
        if not name.startswith("warpcloth.kernels"):
            continue
        for dep in deps:
            top = dep.split(".")[0]
            allowed = dep.startswith("warpcloth.kernels") or dep == "warpcloth.errors"
            assert allowed or top == "warp" or top in sys.stdlib_module_names, f"{name} imports {dep}"
    assert graph["warpcloth.errors"] <= set(sys.stdlib_module_names), "warpcloth.errors is a leaf"


@pytest.mark.parametrize("layer", sorted(FORBIDDEN))
def test_layer_imports_nothing_above_it(graph, layer):
    for name, deps in graph.items():
        if name != layer and not name.startswith(layer + "."):
            continue
        for dep in deps:
            bad = [f for f in FORBIDDEN[layer] if dep == f or dep.startswith(f + ".")]
            assert not bad, f"{name} imports {dep}"


def test_no_import_cycles(graph):
    internal = {n: {d for d in deps if d in graph} for n, deps in graph.items()}
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> None:
        state[node] = 1
        stack.append(node)
        for dep in sorted(internal[node]):
            if state.get(dep) == 1:
                cycle = stack[stack.index(dep) :] + [dep]
                pytest.fail("import cycle: " + " → ".join(cycle))
            if dep not in state:
                visit(dep)
        stack.pop()
        state[node] = 2

    for node in sorted(internal):
        if node not in state:
            visit(node)


def package_of(module: str) -> str:
    return ".".join(module.split(".")[:2])


def test_no_cycles_between_packages(graph):
    # coarser than modules: io importing viz while viz imports io is a cycle even when
    # no single module imports itself back
    edges: dict[str, set[str]] = {}
    for name, deps in graph.items():
        if name == "warpcloth":
            continue  # the curated API imports every package by design
        for dep in deps:
            if dep in graph and dep != "warpcloth" and package_of(dep) != package_of(name):
                edges.setdefault(package_of(name), set()).add(package_of(dep))
    for package, deps in edges.items():
        for dep in deps:
            assert package not in reachable(edges, dep), f"{package} and {dep} import each other"


def reachable(edges: dict[str, set[str]], start: str) -> set[str]:
    seen, todo = set(), [start]
    while todo:
        node = todo.pop()
        for dep in edges.get(node, ()):
            if dep not in seen:
                seen.add(dep)
                todo.append(dep)
    return seen


def test_the_graph_sees_the_layers(graph):
    # guards the test itself: it must find the packages and real edges between them
    expected = {
        "warpcloth.strip.model",
        "warpcloth.kernels.strip",
        "warpcloth.scene.build",
        "warpcloth.cli.app",
        "warpcloth.track.markers",
        "warpcloth.cli.track",
    }
    assert expected <= set(graph)
    assert "warpcloth.track.calibration" in graph["warpcloth.track.markers"]
    assert "warpcloth.runs" in graph["warpcloth.track.render"]
    assert "warpcloth.strip" in graph["warpcloth.scene.build"]
    assert "warpcloth.kernels.forces" in graph["warpcloth.kernels.strip"]
