"""The package's modules import one another in one direction: no cycles, and the dynamics below the rest.

Read from the sources (every ``import`` statement, those inside functions too), not by importing them.
Imports under ``if TYPE_CHECKING:`` are left out: they never run, and are how a module names in its
annotations a type whose module imports it.
"""

from __future__ import annotations

import ast
import graphlib
from pathlib import Path

import pytest

import subenv

PACKAGE = Path(subenv.__file__).resolve().parent


def _module_files() -> dict[str, Path]:
    files = {}
    for path in PACKAGE.rglob("*.py"):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        files[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return files


def _imports(path: Path, modules: set[str]) -> set[str]:
    """The package's modules that ``path`` imports (``from package import module`` names the module)."""
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and isinstance(node.test, ast.Name) and node.test.id == "TYPE_CHECKING":
            node.body = []
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names if alias.name in modules}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module in modules:
            for alias in node.names:
                submodule = f"{node.module}.{alias.name}"
                found.add(submodule if submodule in modules else node.module)
    return found


FILES = _module_files()
GRAPH = {name: _imports(path, set(FILES)) for name, path in FILES.items()}


def test_the_modules_import_one_another_without_cycles() -> None:
    try:
        graphlib.TopologicalSorter(GRAPH).prepare()
    except graphlib.CycleError as error:
        pytest.fail(f"an import cycle: {' -> '.join(error.args[1])}")


def test_the_dynamics_import_nothing_of_the_layers_above() -> None:
    allowed = ("subenv.dynamics", "subenv.vehicles", "subenv._typing", "subenv._validation")
    outside = {
        (name, imported)
        for name, imported_names in GRAPH.items()
        if name.startswith("subenv.dynamics")
        for imported in imported_names
        if not imported.startswith(allowed)
    }
    assert not outside
