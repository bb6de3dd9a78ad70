"""subenv.analysis imports its modules on use: ``import subenv`` stays light, and every public name
is still there (``from subenv.analysis import X`` for each X of ``__all__``)."""

from __future__ import annotations

import ast
import importlib
import json
import subprocess
import sys
from pathlib import Path

import pytest

import subenv.analysis as analysis

ROOT = Path(__file__).resolve().parents[2]


def _fresh(code: str) -> object:
    """What ``code`` prints (as JSON) in a fresh interpreter that imports this checkout's subenv."""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=False)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def test_import_subenv_loads_neither_scipy_optimize_nor_the_analysis_it_does_not_use() -> None:
    loaded = _fresh(
        "import json, sys, subenv; "
        "print(json.dumps(sorted(m for m in sys.modules if m.startswith(('scipy.', 'subenv.analysis')))))"
    )
    assert isinstance(loaded, list)
    assert not [m for m in loaded if m.startswith(("scipy.optimize", "scipy.signal", "scipy.integrate"))]
    # The environments' own needs: the allocation's check and the critical speed.
    assert {m for m in loaded if m.startswith("subenv.analysis")} <= {
        "subenv.analysis",
        "subenv.analysis.linear",
        "subenv.analysis.critical",
    }


@pytest.mark.parametrize("name", analysis.__all__)
def test_every_public_name_is_its_module_s(name: str) -> None:
    module = importlib.import_module(f"subenv.analysis.{analysis._HOME[name]}")
    namespace: dict[str, object] = {}
    exec(f"from subenv.analysis import {name}", namespace)
    assert namespace[name] is getattr(module, name) is getattr(analysis, name)


def test_functions_named_as_their_modules_stay_functions_whatever_was_imported_first() -> None:
    # continuation imports the module equilibria; the import system then binds the module to the
    # package's attribute of that name, which must stay the function.
    kinds = _fresh(
        "import json, subenv.analysis.continuation, subenv.analysis.winnable; "
        "from subenv.analysis import equilibria, winnable; import subenv.analysis as a; "
        "print(json.dumps([type(f).__name__ for f in (equilibria, winnable, a.equilibria, a.winnable)]))"
    )
    assert kinds == ["function"] * 4


def test_the_names_for_the_type_checkers_are_those_imported_on_use() -> None:
    tree = ast.parse(Path(analysis.__file__).read_text())
    (block,) = [node for node in tree.body if isinstance(node, ast.If)]  # if TYPE_CHECKING:
    declared = {
        alias.name: node.module.removeprefix("subenv.analysis.")
        for node in block.body
        if isinstance(node, ast.ImportFrom) and node.module
        for alias in node.names
    }
    assert declared == analysis._HOME
    assert sorted(analysis.__all__) == sorted(analysis._HOME)


def test_an_unknown_name_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="has no attribute 'critical_velocity'"):
        analysis.critical_velocity  # noqa: B018 - the attribute access is the test
