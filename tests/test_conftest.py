"""The suite's own set-up: how its tests are imported."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent


@pytest.mark.parametrize(
    "folder", sorted(p.name for p in TESTS.iterdir() if p.is_dir() and p.name.isidentifier())
)
def test_no_test_folder_is_found_for_a_module_of_its_name(folder: str) -> None:
    # Under pytest's default import mode tests/ was on sys.path, and tests/jax (no __init__.py) was the
    # package `jax` where JAX is not installed: importorskip("jax") passed, then the tests failed to import.
    spec = importlib.util.find_spec(folder)
    found = [*(spec.submodule_search_locations or ()), spec.origin or ""] if spec else []
    assert not any(Path(place).resolve().is_relative_to(TESTS) for place in found if place), found
