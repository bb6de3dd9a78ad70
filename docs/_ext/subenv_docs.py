"""The Sphinx extension that writes the generated pages before Sphinx reads the sources.

Each generator writes one folder of the source tree (git ignores them) and is run again only when
its inputs changed: a stamp in the folder holds the hash of the sources it reads (the packages, the
generators, the benchmarks' records). A reference to an object of this project that does not
resolve is a warning, so a build with warnings as errors (``./dev docs``) fails on it.
"""

from __future__ import annotations

import hashlib
import re
import shutil
import time
from collections.abc import Callable, Iterable
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any, Final

from sphinx.application import Sphinx
from sphinx.util import logging

logger = logging.getLogger(__name__)

DOCS = Path(__file__).resolve().parents[1]
ROOT = DOCS.parent
PACKAGES = ("subenv", "subenv_baselines")
STAMP = ".stamp"


def source_hash(paths: Iterable[Path]) -> str:
    """The hash of the files' names and contents (``*.py``, ``*.toml``, ``*.json`` under folders)."""
    digest = hashlib.sha256()
    files: list[Path] = []
    for path in paths:
        if path.is_dir():
            files += [p for p in path.rglob("*") if p.suffix in (".py", ".toml", ".json") and p.is_file()]
        elif path.is_file():
            files.append(path)
    for file in sorted(files):
        digest.update(str(file.relative_to(ROOT)).encode())
        digest.update(file.read_bytes())
    return digest.hexdigest()


def generate(folder: Path, inputs: Iterable[Path], write: Callable[[Path], Any]) -> None:
    """Run ``write(tmp)`` into a fresh folder and put it at ``folder``, unless ``folder``'s stamp says
    that ``inputs`` are unchanged since it was written."""
    stamp = source_hash([*inputs, *(ROOT / p for p in PACKAGES)])
    if (folder / STAMP).is_file() and (folder / STAMP).read_text() == stamp:
        return
    started = time.perf_counter()
    fresh = folder.with_name(folder.name + ".tmp")
    shutil.rmtree(fresh, ignore_errors=True)
    fresh.mkdir()
    write(fresh)
    (fresh / STAMP).write_text(stamp)
    shutil.rmtree(folder, ignore_errors=True)
    fresh.rename(folder)
    logger.info(f"subenv_docs: wrote {folder.relative_to(DOCS)}/ in {time.perf_counter() - started:.0f} s")


def _generate(name: str) -> None:
    """Run the generator ``name`` (a module of ``_ext/`` that writes the folder of that name)."""
    import envpages
    import performance
    import reproduction

    ext = DOCS / "_ext"
    if name == "environments":
        generate(DOCS / "environments", [ext / "envpages.py"], envpages.write_pages)
    elif name == "reproduction":
        generate(DOCS / "reproduction", [ext / "reproduction.py"], reproduction.write_pages)
    else:
        generate(
            DOCS / "performance",
            [ext / "performance.py", ROOT / "benchmarks" / "records"],
            performance.write_pages,
        )


GENERATED: Final = ("environments", "reproduction", "performance")
"""The generated folders (git ignores them)."""


def _generate_all(app: Sphinx) -> None:
    # The generators are independent and CPU-bound (the animations, the reproduction's numbers and
    # figures): one process each, so that a cold build takes the longest one's time, not their sum.
    with ProcessPoolExecutor(max_workers=len(GENERATED)) as pool:
        for done in [pool.submit(_generate, name) for name in GENERATED]:
            done.result()  # (a generator's exception fails the build, with its traceback)


_MISSING = object()


def _is_private(target: str) -> bool:
    return any(part.startswith("_") for part in target.split("."))


def canonical_name(target: str) -> str | None:
    """The name under which ``target`` (``subenv.envs.DivePlaneConfig``, a re-export) is documented:
    the defining module's (``subenv.envs.config.DivePlaneConfig``), for a module, a class or a
    function and for what is reached through them (a method, a property, an attribute); None if
    ``target`` names nothing importable."""
    import importlib
    import inspect

    parts = target.split(".")
    for split in range(len(parts), 0, -1):
        try:
            obj: Any = importlib.import_module(".".join(parts[:split]))
        except ImportError:
            continue
        base, rest = obj.__name__, parts[split:]
        for k, attr in enumerate(rest):
            fields = getattr(obj, "__dataclass_fields__", {})
            obj = getattr(obj, attr, fields.get(attr, _MISSING))
            if obj is _MISSING:
                return None
            if inspect.ismodule(obj):
                base, rest = obj.__name__, rest[k + 1 :]
            elif inspect.isclass(obj) or inspect.isfunction(obj):
                home, qualname = getattr(obj, "__module__", None), getattr(obj, "__qualname__", None)
                if home and qualname:
                    base, rest = f"{home}.{qualname}", rest[k + 1 :]
        return ".".join([base, *rest])
    return None


def _missing_reference(app: Sphinx, env: Any, node: Any, contnode: Any) -> Any:
    """Resolve a reference to a re-exported object through its defining module, and warn (so fail the
    build) when a reference to this project's objects resolves nowhere."""
    target = node.get("reftarget", "").lstrip("~.")
    if node.get("refdomain") != "py" or target.split(".")[0] not in PACKAGES or _is_private(target):
        return None  # (a private name is not in the reference: it stays code text, as it reads)
    canonical = canonical_name(target)
    if canonical and _is_private(canonical):
        return None  # (defined in a private module: not in the reference)
    if canonical and canonical != target:
        domain = env.get_domain("py")
        for role in ("obj", "class", "func", "meth", "attr", "data", "mod", "exc"):
            found = domain.resolve_xref(env, node["refdoc"], app.builder, role, canonical, node, contnode)
            if found is not None:
                return found
    logger.warning(f"unresolved reference to {target!r}", location=node)
    return None


def _escape_bars(line: str) -> str:
    """``|x|`` (an absolute value, as the docstrings write it) outside inline literals, escaped: reST
    would read it as a substitution."""
    text = line.strip()
    if text.startswith(("+", "=")) or (text.startswith("|") and text.endswith("|")):  # a table's lines
        return line
    parts = line.split("``")
    return "``".join(part if k % 2 else part.replace("|", r"\|") for k, part in enumerate(parts))


def _indent(line: str) -> int:
    return len(line) - len(line.lstrip())


def _formula_blocks(lines: list[str]) -> list[str]:
    """The docstrings' indented blocks (formulas set apart, as ``eq. 3.9`` is written out) as literal
    blocks: the paragraph before one ends with ``::``, so reST neither reflows it nor reads a
    definition list into it. Lists, examples, directives and fields keep their meaning."""
    out = list(lines)
    for i in range(2, len(lines)):
        line, blank, before = lines[i], lines[i - 1], lines[i - 2]
        if not line.strip() or blank.strip() or not before.strip() or _indent(line) <= _indent(before):
            continue
        text = line.strip()
        if text.startswith(("- ", "* ", ">>>", ".. ", ":", "|", "+", "=")) or re.match(r"\d+\. ", text):
            continue
        if before.rstrip().endswith("::") or before.lstrip().startswith((".. ", ":")):
            continue
        out[i - 2] = before.rstrip() + " ::"
    return out


def _docstring(app: Sphinx, what: str, name: str, obj: Any, options: Any, lines: list[str]) -> None:
    """A docstring as reST. One written in Markdown (the environment's, with Gymnasium's ``## Section``
    headings) is the environments' pages' source: in the API reference it points there instead."""
    if lines and lines[0].startswith("Alias for field number"):  # (a named tuple's field: its name says it)
        lines[:] = []
    if any(line.startswith("## ") for line in lines):
        lines[:] = [lines[0], "", "Its documentation, section by section: :doc:`/environments/index`.", ""]
    lines[:] = _formula_blocks([_escape_bars(line) for line in lines])


def _numba_documenter() -> type:
    """An autodoc documenter for numba's compiled functions (``@njit``, ``@guvectorize``), which autodoc
    does not take for functions: documented as the Python function they compile (``py_func``)."""
    from sphinx.ext.autodoc import FunctionDocumenter

    class NumbaFunctionDocumenter(FunctionDocumenter):
        objtype = "numbafunction"
        directivetype = "function"
        priority = FunctionDocumenter.priority + 1

        @classmethod
        def can_document_member(cls, member: Any, membername: str, isattr: bool, parent: Any) -> bool:
            return callable(getattr(member, "py_func", None)) and not isinstance(member, type)

        def import_object(self, raiseerror: bool = False) -> bool:
            imported = super().import_object(raiseerror)
            if imported and callable(getattr(self.object, "py_func", None)):
                self.object = self.object.py_func
            return imported

    return NumbaFunctionDocumenter


def setup(app: Sphinx) -> dict[str, Any]:
    """Register the generators and the check of references (Sphinx's extension entry point)."""
    app.setup_extension("sphinx.ext.autodoc")
    app.add_autodocumenter(_numba_documenter())
    app.connect("builder-inited", _generate_all)
    app.connect("missing-reference", _missing_reference)
    app.connect("autodoc-process-docstring", _docstring)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
