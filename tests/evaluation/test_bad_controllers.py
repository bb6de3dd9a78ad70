"""Bad controllers: a controller cannot publish under another one's name.

The controllers are defined here and declared as an installed package declares its controllers (entry
points of the ``subenv.controllers`` group, as ``tests/conftest.py`` declares the shipped ones), in a
registry of the test's own.
"""

from __future__ import annotations

from collections.abc import Mapping
from importlib.metadata import EntryPoint
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from subenv.cli import main
from subenv.evaluation import ENTRY_POINT_GROUP, controller, discover_controllers, evaluate, make_controller
from subenv.vehicles import Vehicle


class GoodP:
    """Planes proportional to the depth error, one episode at a time: runs every episode to its end."""

    name = "good_p"
    control = "dual"
    alpha = 0.0

    def reset(self, info: Mapping[str, Any], vehicle: Vehicle) -> None:
        self.steps = 0

    def act(self, observation: np.ndarray) -> np.ndarray:
        self.steps += 1
        return np.clip([0.3 * float(observation[0])], -1.0, 1.0).astype(np.float32)


class Liar(GoodP):
    """Declared as ``liar``, it calls itself ``lqr``: its rows would be another controller's."""

    name = "lqr"


DECLARED = {"good_p": GoodP, "liar": Liar}


@pytest.fixture
def declared(monkeypatch: pytest.MonkeyPatch) -> None:
    """The controllers above declared as entry points, beside the shipped ones, for this test only."""
    monkeypatch.setattr(controller, "_REGISTRY", dict(controller._REGISTRY))
    monkeypatch.setattr(controller, "_UNAVAILABLE", dict(controller._UNAVAILABLE or {}))
    discover_controllers(
        EntryPoint(name, f"{__name__}:{cls.__name__}", ENTRY_POINT_GROUP) for name, cls in DECLARED.items()
    )


LIAR = (
    "controller 'liar' is invalid: its name attribute is 'lqr', and must be 'liar', the name it is "
    "registered under (results are published by name)"
)


def test_a_controller_that_calls_itself_by_another_name_is_refused(declared, tmp_path: Path) -> None:
    with pytest.raises(ValueError) as error:
        make_controller("liar")
    assert str(error.value) == LIAR
    with pytest.raises(ValueError) as error:
        evaluate(["good_p", "liar"], ["Nominal"], episodes=1, progress=False)
    assert str(error.value) == LIAR
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as exit_:
        main(["evaluate", "--controllers", "good_p,liar", "--suite", "Nominal", "--out", str(out)])
    assert exit_.value.code == f"subenv evaluate: {LIAR}"
    assert not out.exists()
    assert make_controller("lqr").name == "lqr"  # the real one is untouched
