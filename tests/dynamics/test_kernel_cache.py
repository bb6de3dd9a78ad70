"""numba's cache of the compiled kernels is dropped when any kernel source changes.

numba checks a cached kernel against its own file only; the environments' kernel inlines the
physics from other files, so a stale cache would run old physics after an edit. The guard in
:mod:`subenv.dynamics._jit` stamps each cache directory with a digest of all kernel sources.
"""

from __future__ import annotations

from pathlib import Path

from subenv.dynamics import _jit


def _files(directory: Path) -> set[str]:
    return {p.name for p in directory.iterdir()}


def test_a_new_stamp_drops_the_kernels_of_these_sources_only(tmp_path: Path) -> None:
    ours = [
        "transition.step-286.py311.nbi",
        "transition.step-286.py311.1.nbc",
        "hull.crossflow_point-120.py311.nbi",
        "guf-model._derivatives_loop-258.py311.1.nbc",
        "integrate.control_period_lanes-55.py311.nbi",
    ]
    others = [
        "solver.residual-10.py311.nbi",
        "transition.py",
        "notes.txt",
    ]  # another package's kernel, not caches
    for name in [*ours, *others, "subenv-kernels.0123456789abcdef"]:
        (tmp_path / name).write_bytes(b"x")
    check = _jit._check_directory.__wrapped__  # (the once-per-process memo bypassed)
    check(tmp_path)
    assert _files(tmp_path) == {*others, f"subenv-kernels.{_jit.sources_stamp()}"}

    (tmp_path / "transition.step-286.py311.nbi").write_bytes(b"compiled from these sources")
    check(tmp_path)  # stamped for these sources: the new cache stays
    assert "transition.step-286.py311.nbi" in _files(tmp_path)


def test_the_stamp_covers_every_file_with_a_cached_kernel() -> None:
    package = Path(_jit.__file__).resolve().parents[1]
    with_kernels = {
        str(path.relative_to(package))
        for path in package.rglob("*.py")
        if any(marker in path.read_text() for marker in ("@kernel", "@inline_kernel", "gufunc("))
        and path.name != "_jit.py"
    }
    assert with_kernels <= set(_jit.KERNEL_SOURCES)
    assert len(_jit.sources_stamp()) == 16 and int(_jit.sources_stamp(), 16) >= 0
