"""numba's cache of the compiled kernels is dropped when any file a kernel inlines changes.

numba checks a cached kernel against its own file only; the environments' kernel inlines the
physics from other files, so a stale cache would run old physics after an edit. Each package that
compiles kernels declares its kernel sources (:func:`subenv.dynamics._jit.declare_kernel_sources`:
its files, and the packages whose kernels they inline), and the guard in
:mod:`subenv.dynamics._jit` stamps each package's cache directory with a digest of them all.
"""

from __future__ import annotations

import ast
import importlib.util
from pathlib import Path
from typing import Any

import pytest

from subenv.dynamics import _jit
from subenv.envs import transition

PACKAGE = Path(_jit.__file__).resolve().parents[1]
DECLARATIONS = (_jit.KERNEL_SOURCES, transition.KERNEL_SOURCES)
"""Every package's declaration (the dynamics', the environments')."""
_MARKERS = ("@kernel", "@inline_kernel", "@parallel_kernel", "= kernel(", "= parallel_kernel(", "gufunc(")


def _files(directory: Path) -> set[str]:
    return {p.name for p in directory.iterdir()}


def test_a_new_stamp_drops_the_kernels_of_these_sources_only(tmp_path: Path) -> None:
    ours = [
        "transition.step-286.py311.nbi",
        "transition.step-286.py311.1.nbc",
        "guf-transition._loop-258.py311.1.nbc",
    ]
    others = [
        "solver.residual-10.py311.nbi",  # another module's kernel
        "transition.py",  # not caches
        "notes.txt",
    ]
    for name in [*ours, *others, "subenv-kernels.0123456789abcdef"]:
        (tmp_path / name).write_bytes(b"x")
    check = _jit._check_directory.__wrapped__  # (the once-per-process memo bypassed)
    stamp = transition.KERNEL_SOURCES.stamp
    check(tmp_path, stamp, ("transition",))
    assert _files(tmp_path) == {*others, f"subenv-kernels.{stamp}"}

    (tmp_path / "transition.step-286.py311.nbi").write_bytes(b"compiled from these sources")
    check(tmp_path, stamp, ("transition",))  # stamped for these sources: the new cache stays
    assert "transition.step-286.py311.nbi" in _files(tmp_path)


def test_an_edit_of_a_file_a_kernel_inlines_changes_the_stamp_of_every_package_that_inlines_it(
    tmp_path: Path,
) -> None:
    for name in ("physics/model.py", "physics/helpers.py", "envs/step.py"):
        (tmp_path / name).parent.mkdir(exist_ok=True)
        (tmp_path / name).write_text("x = 1\n")

    def stamps() -> tuple[str, str]:  # (fresh declarations: a declaration reads its files once)
        physics = _jit.KernelSources(tmp_path / "physics", ("model.py", "helpers.py"))
        envs = _jit.KernelSources(tmp_path / "envs", ("step.py",), inlines=(physics,))
        return physics.stamp, envs.stamp

    before = stamps()
    (tmp_path / "physics/helpers.py").write_text("x = 2\n")
    after_physics = stamps()
    assert after_physics[0] != before[0] and after_physics[1] != before[1]
    (tmp_path / "envs/step.py").write_text("x = 2\n")
    after_envs = stamps()
    assert after_envs[0] == after_physics[0] and after_envs[1] != after_physics[1]


def test_every_file_with_kernels_is_declared_in_its_package() -> None:
    with_kernels = {
        path.resolve()
        for path in PACKAGE.rglob("*.py")
        if any(marker in path.read_text() for marker in _MARKERS) and path.name != "_jit.py"
    }
    declared = {
        path for sources in DECLARATIONS for path in sources.folder.glob("*.py") if path.name in sources.files
    }
    assert with_kernels <= declared
    for path in with_kernels:  # (what the decorators look up)
        assert _jit.kernel_sources(path) in DECLARATIONS
    assert all(len(sources.stamp) == 16 and int(sources.stamp, 16) >= 0 for sources in DECLARATIONS)


def test_a_package_inlines_every_package_whose_kernel_modules_it_imports() -> None:
    """The layering leak this replaces: the dynamics' sources listed the environments' transition.py.
    Now each package declares what it inlines, and the dynamics inline nothing above them."""
    module_of = {
        ".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts): sources
        for sources in DECLARATIONS
        for path in (sources.folder / name for name in sources.files)
    }
    for sources in DECLARATIONS:
        inlined = {path for other in sources.inlines for path in other.paths()}
        for name in sources.files:
            tree = ast.parse((sources.folder / name).read_text())
            for node in ast.walk(tree):
                if isinstance(node, ast.ImportFrom) and node.module in module_of:
                    other = module_of[node.module]
                    assert other is sources or set(other.paths()) <= inlined, (name, node.module)
    assert _jit.KERNEL_SOURCES.inlines == ()
    assert transition.KERNEL_SOURCES.inlines == (_jit.KERNEL_SOURCES,)


def _module(path: Path, source: str) -> Any:
    path.parent.mkdir(exist_ok=True)
    path.write_text(source)
    spec = importlib.util.spec_from_file_location(f"_kernel_cache_{path.parent.name}_{path.stem}", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_kernel_in_an_undeclared_file_is_refused_when_defined(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(_jit, "_DECLARED", dict(_jit._DECLARED))  # (the declaration below is the test's)
    source = "def twice(x):\n    return 2.0 * x\n"
    undeclared = _module(tmp_path / "undeclared" / "mod.py", source)
    with pytest.raises(
        RuntimeError, match=r"mod\.py defines kernels but is not among its package's kernel sources"
    ):
        _jit.kernel(undeclared.twice)
    _jit.declare_kernel_sources(str(tmp_path / "declared" / "__init__.py"), ("other.py",))
    unlisted = _module(tmp_path / "declared" / "mod.py", source)
    with pytest.raises(RuntimeError, match=r"declared: \['other.py'\]"):
        _jit.inline_kernel(unlisted.twice)
