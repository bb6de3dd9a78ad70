"""The optional dependencies (the package's extras) and the one message that says how to install them.

``subenv`` needs matplotlib for plots (``plot``), pygame for rendering (``render``) and
Stable-Baselines3 for the agents (``rl``); each is imported only where it is used, and a missing one
is reported in one line that names the extra, in a form that works for a wheel and for a clone.
"""

from __future__ import annotations

import re
from importlib.metadata import PackageNotFoundError, requires
from importlib.util import find_spec

__all__ = ["MissingExtra", "extra_requirements", "missing_extra_message", "require"]


class MissingExtra(ModuleNotFoundError):
    """An optional dependency is not installed; the message names the extra that installs it."""


def extra_requirements(extra: str) -> list[str]:
    """The requirements the installed ``subenv`` declares for ``extra`` (``["matplotlib>=3.7"]`` for
    ``"plot"``), read from its metadata: pyproject.toml's optional-dependencies; [] if unknown."""
    try:
        declared = requires("subenv") or []
    except PackageNotFoundError:
        return []
    marker = re.compile(r"""extra\s*==\s*["']""" + re.escape(extra) + r"""["']""")
    return [
        req.strip() for req, _, condition in (r.partition(";") for r in declared) if marker.search(condition)
    ]


def missing_extra_message(extra: str, purpose: str) -> str:
    """One line: ``extra`` is needed for ``purpose``, and the commands that install it, for an
    installed wheel (the extra, or its requirements by name where subenv is not on the index) and a
    clone."""
    packages = " ".join(f'"{req}"' for req in extra_requirements(extra))
    alternative = f"or pip install {packages}; " if packages else ""
    return (
        f'the {extra!r} extra is needed for {purpose}: pip install "subenv[{extra}]" '
        f"({alternative}in a clone of the repository, ./dev installs every extra)"
    )


def require(extra: str, purpose: str, *modules: str) -> None:
    """Raise :class:`MissingExtra` unless every top-level module of ``modules`` can be imported.

    Only looks the modules up (nothing is imported), so that it is cheap to call early, before any
    work starts.
    """
    for module in modules:
        if find_spec(module) is None:
            raise MissingExtra(missing_extra_message(extra, purpose), name=module)
