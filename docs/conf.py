"""Sphinx configuration of subenv's documentation (``./dev docs`` builds it into docs/_build/html).

The pages are Markdown (MyST). Some are generated at build time, before Sphinx reads the sources
(:func:`generate`, on ``builder-inited``), into folders that git ignores:

- ``environments/``: one page per registered id, from :class:`subenv.envs.DivePlaneEnv`'s docstring,
  the id's registration and its scenario, with an animation rendered by ``render_mode="rgb_array"``
  (``_ext/envpages.py``);
- ``reproduction/``: the reproduction report of Riedel (1993), for SUBOFF and the REMUS 100, with its
  figures (``_ext/reproduction.py``);
- ``performance/``: the figures of the benchmarks' JSON records in ``benchmarks/records/``
  (``_ext/performance.py``).

The design note ``design.md`` says why Sphinx, furo and MyST.
"""

from __future__ import annotations

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path[:0] = [str(ROOT), str(DOCS / "_ext")]  # this checkout's subenv, and the generators

import subenv  # noqa: E402  (after the path: the checkout's own package, not another installed one)

project = "subenv"
author = "the subenv developers"
copyright = "2026, the subenv developers"  # (Sphinx's name for it)
release = version = subenv.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "subenv_docs",
]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
# Not pages of the site: the figures the README shows (until its rewrite), the committed reference
# results (rendered on their own page through an include), the build and the generators.
exclude_patterns = ["_build", "_ext", "remus100", "reference", "*.png", "README.md"]

myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3  # (links to #a-heading within and across pages)

# The docstrings are numpydoc; napoleon turns them into Sphinx fields.
napoleon_google_docstring = False
napoleon_numpy_docstring = True
autodoc_member_order = "bysource"
# Each object where it is defined: a module's members, not what it imports (its __all__ may re-export).
autodoc_default_options = {"ignore-module-all": True}
# The numpydoc sections give the types in words; annotations (FloatArray's expansion) would repeat them.
autodoc_typehints = "none"
autodoc_preserve_defaults = True

html_theme = "furo"
html_title = f"subenv {release}"
html_static_path: list[str] = []
html_copy_source = False
html_last_updated_fmt = None
