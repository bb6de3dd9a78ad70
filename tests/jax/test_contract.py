"""The contract of the kernels subenv.jax traces (subenv/jax/_trace.py's docstring), checked from their
source: a future edit that would not trace fails here, not in a user's program.

Every kernel reached from a ``traced(...)`` call in subenv/jax/ (and, through the names its code uses,
every kernel it calls) names only allowed globals, and its ``if``, conditional expressions, boolean
operators, chained comparisons, ``while`` and ``range`` bounds depend on static values only.
"""

from __future__ import annotations

import ast
import builtins
import importlib
import inspect
import textwrap
import typing
from pathlib import Path

import pytest

pytest.importorskip("jax", reason="the 'jax' extra is not installed")

import subenv.jax
from subenv.dynamics import _jit
from subenv.envs import transition as tr
from subenv.jax import _trace

JAX_PACKAGE = Path(subenv.jax.__file__).parent
ALLOWED_BUILTINS = frozenset({"range", "len"})
"""Builtins a traced kernel may call (``min``, ``max`` and ``abs`` are not: _jit's helpers and math.fabs)."""
RECORD_FIELDS = {
    "StateRecord": set(tr.STATE_DTYPE.names),
    "EpisodeRecord": set(tr.EPISODE_DTYPE.names),
    "ConfigRecord": set(tr.CONFIG_DTYPE.names),
}
"""The fields a record parameter (by its annotation, transition.py's aliases) may name: its dtype's."""
SHAPE_ATTRIBUTES = frozenset({"shape", "ndim"})
"""Static on every array: JAX's shapes are part of the program."""


def _resolve(node: ast.expr, namespace: dict) -> object:
    """The object a name or attribute chain (``tr.period_start``) stands for in ``namespace``, or None."""
    if isinstance(node, ast.Name):
        return namespace.get(node.id)
    if isinstance(node, ast.Attribute):
        base = _resolve(node.value, namespace)
        return None if base is None else getattr(base, node.attr, None)
    return None


def traced_roots() -> set:
    """The kernels subenv/jax/'s modules hand to ``traced`` by name (found in their source)."""
    roots = set()
    for path in sorted(JAX_PACKAGE.glob("*.py")):
        module = importlib.import_module(
            f"subenv.jax.{path.stem}" if path.stem != "__init__" else "subenv.jax"
        )
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "traced":
                target = _resolve(node.args[0], vars(module)) if node.args else None
                if hasattr(target, "py_func"):
                    roots.add(target)
    return roots


def _function_node(kernel) -> ast.FunctionDef:
    source = textwrap.dedent(inspect.getsource(kernel.py_func))
    node = ast.parse(source).body[0]
    assert isinstance(node, ast.FunctionDef), kernel
    return node


def _is_constant(value: object) -> bool:
    """A module constant a kernel may read: a number, a boolean, a string, or a tuple of them."""
    if isinstance(value, tuple):
        return all(_is_constant(v) for v in value)
    return isinstance(value, bool | int | float | str)


class Kernel:
    """One kernel's source, its locals, its static names and the globals it reads."""

    def __init__(self, kernel) -> None:
        self.kernel = kernel
        self.name = f"{kernel.py_func.__module__}.{kernel.py_func.__qualname__}"
        self.node = _function_node(kernel)
        self.globals = kernel.py_func.__globals__
        args = self.node.args
        self.parameters = [a.arg for a in (*args.posonlyargs, *args.args, *args.kwonlyargs)]
        hints = typing.get_type_hints(kernel.py_func, include_extras=True)
        self.static_parameters = {
            name for name in self.parameters if _jit.STATIC in getattr(hints.get(name), "__metadata__", ())
        }
        self.records = {
            a.arg: ast.unparse(a.annotation)
            for a in (*args.posonlyargs, *args.args, *args.kwonlyargs)
            if a.annotation is not None and ast.unparse(a.annotation) in RECORD_FIELDS
        }
        self.assignments: dict[str, list[ast.expr | None]] = {}
        for node in ast.walk(self.node):
            if isinstance(node, ast.Assign):
                for target in node.targets:
                    self._assign(target, node.value)
            elif isinstance(node, ast.AugAssign | ast.AnnAssign):
                self._assign(node.target, node.value)
            elif isinstance(node, ast.For):
                # An index of a static range is static (JAX unrolls the loop); of anything else, not.
                self._assign(node.target, node.iter if _is_range(node.iter) else None)
            elif isinstance(node, ast.NamedExpr | ast.comprehension):
                self._assign(node.target, None)
        self.locals = set(self.parameters) | set(self.assignments)
        self.static = self._static_names()

    def _assign(self, target: ast.expr, value: ast.expr | None) -> None:
        """Record that ``target`` gets ``value`` (None: a value not known to be static); an element of an
        unpacked value is static where the whole value is. (A subscript or attribute target stores into
        an object: no name.)"""
        if isinstance(target, ast.Name):
            self.assignments.setdefault(target.id, []).append(value)
        elif isinstance(target, ast.Tuple | ast.List):
            same = isinstance(value, ast.Tuple) and len(value.elts) == len(target.elts)
            for k, element in enumerate(target.elts):
                self._assign(element, value.elts[k] if same else value)

    def _static_names(self) -> set[str]:
        """The parameters annotated Static, and the locals that every assignment gives a static value (a
        fixed point)."""
        static = set(self.static_parameters)
        changed = True
        while changed:
            changed = False
            for name, values in self.assignments.items():
                if (
                    name not in static
                    and name not in self.parameters
                    and all(v is not None and self.is_static(v, static) for v in values)
                ):
                    static.add(name)
                    changed = True
        return static

    def is_static(self, node: ast.AST, static: set[str] | None = None) -> bool:
        """Whether ``node``'s value is fixed while the kernel is traced."""
        static = self.static if static is None else static
        if isinstance(node, ast.Constant):
            return True
        if isinstance(node, ast.Name):
            if node.id in self.locals:
                return node.id in static
            return _is_constant(self.globals.get(node.id))
        if isinstance(node, ast.Attribute):
            return node.attr in SHAPE_ATTRIBUTES or self.is_static(node.value, static)
        if isinstance(node, ast.Subscript):
            return self.is_static(node.value, static) and self.is_static(node.slice, static)
        if isinstance(node, ast.BinOp):
            return self.is_static(node.left, static) and self.is_static(node.right, static)
        if isinstance(node, ast.UnaryOp):
            return self.is_static(node.operand, static)
        if isinstance(node, ast.BoolOp):
            return all(self.is_static(v, static) for v in node.values)
        if isinstance(node, ast.Compare):
            return all(self.is_static(v, static) for v in (node.left, *node.comparators))
        if isinstance(node, ast.Tuple):
            return all(self.is_static(v, static) for v in node.elts)
        if isinstance(node, ast.IfExp):
            return all(self.is_static(v, static) for v in (node.test, node.body, node.orelse))
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
            return node.func.id in ("len", "range") and all(self.is_static(a, static) for a in node.args)
        return False

    def global_names(self) -> set[str]:
        """The names its body reads that are neither parameters nor locals (annotations aside)."""
        names = set()
        for statement in self.node.body:
            for node in ast.walk(statement):
                if (
                    isinstance(node, ast.Name)
                    and isinstance(node.ctx, ast.Load)
                    and node.id not in self.locals
                ):
                    names.add(node.id)
        return names

    def violations(self) -> list[str]:
        """What breaks the contract, one line each."""
        found = []
        body = [node for statement in self.node.body for node in ast.walk(statement)]
        for name in sorted(self.global_names()):
            value = self.globals.get(name, getattr(builtins, name, None))
            if name in ("math", "np"):
                allowed = vars(_trace.MATH if name == "math" else _trace.NUMPY)
                for node in body:
                    if _is_attribute_of(node, name) and node.attr not in allowed:
                        found.append(f"{name}.{node.attr} (not in subenv.jax._trace.{name.upper()})")
            elif hasattr(value, "py_func") or _is_constant(value):
                pass  # a kernel (checked in turn, or replaced: _trace.replacement) or a constant
            elif name in vars(builtins) and name not in self.globals:
                if name not in ALLOWED_BUILTINS:
                    found.append(f"the builtin {name} (allowed: {sorted(ALLOWED_BUILTINS)})")
            else:
                found.append(f"the global {name} = {value!r:.60} (not a kernel or a constant)")
        for node in body:
            for what, test in _conditions(node):
                if not self.is_static(test):
                    found.append(f"line {node.lineno}: {what} on {ast.unparse(test)!r}, not static")
            if isinstance(node, ast.For) and not (_is_range(node.iter) or self.is_static(node.iter)):
                found.append(
                    f"line {node.lineno}: a loop over {ast.unparse(node.iter)!r}, not a static range"
                )
            record = self.records.get(node.value.id) if _is_attribute_of(node, None) else None
            if record is not None and node.attr not in RECORD_FIELDS[record]:
                found.append(f"line {node.lineno}: {ast.unparse(node)!r}, not a field of {record}")
        return [f"{self.name}: {v}" for v in found]

    def callees(self) -> set:
        """The kernels it calls (by the names its body reads)."""
        return {value for name in self.global_names() if hasattr(value := self.globals.get(name), "py_func")}


def _is_range(node: ast.AST) -> bool:
    return isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "range"


def _is_attribute_of(node: ast.AST, name: str | None) -> bool:
    """Whether ``node`` is ``<name>.<attribute>`` (any name where ``name`` is None)."""
    return (
        isinstance(node, ast.Attribute)
        and isinstance(node.value, ast.Name)
        and (name is None or node.value.id == name)
    )


def _conditions(node: ast.AST) -> list[tuple[str, ast.expr]]:
    """The expressions Python turns into a bool (or a range bound) at ``node``: what must be static."""
    if isinstance(node, ast.If | ast.While | ast.IfExp | ast.Assert):
        return [(type(node).__name__.lower(), node.test)]
    if isinstance(node, ast.BoolOp):
        return [("and/or", v) for v in node.values]
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.Not):
        return [("not", node.operand)]
    if isinstance(node, ast.Compare) and len(node.comparators) > 1:
        return [("a chained comparison", node)]
    if _is_range(node):
        return [("a range bound", a) for a in node.args]
    return []


def traced_kernels() -> dict:
    """Every kernel subenv.jax traces: the roots and, transitively, the kernels they call (those
    _trace.replacement stands in for are not traced, whatever their code)."""
    seen, todo = {}, list(traced_roots())
    while todo:
        kernel = todo.pop()
        if kernel in seen or _trace.replacement(kernel, True) is not None:
            continue
        seen[kernel] = Kernel(kernel)
        todo.extend(seen[kernel].callees())
    return seen


@pytest.fixture(scope="module")
def kernels():
    return traced_kernels()


def test_the_roots_and_the_kernels_they_reach_are_found(kernels):
    names = {k.py_func.__name__ for k in kernels}
    # (what the environment and the dynamics trace, and kernels reached only through them)
    expected = {
        "rhs_point",
        "period_start",
        "period_end",
        "report_values",
        "wave_term",
        "station_depth",
    }
    expected |= {"sincos_point", "crossflow_root", "plane_angles", "clip", "minimum", "maximum"}
    assert expected <= names, expected - names
    replaced = {"select", "hull_segment", "suction_point", "wave_force_point"}
    assert not replaced & names  # (replaced, not traced)


def test_every_traced_kernel_keeps_the_contract(kernels):
    violations = [v for kernel in kernels.values() for v in kernel.violations()]
    assert violations == []


def test_static_parameters_are_the_configuration_and_a_count(kernels):
    static = {k.name.rsplit(".", 1)[-1]: k.static_parameters for k in kernels.values() if k.static_parameters}
    assert static["plane_angles"] == {"cfg"}
    assert all(names <= {"cfg", "n"} for names in static.values()), static


REFUSED = {
    "the builtin max": """
        def kernel(x: float) -> float:
            return max(x, 0.0)
    """,
    "the builtin abs": """
        def kernel(x: float) -> float:
            return abs(x)
    """,
    "math.tanh": """
        def kernel(x: float) -> float:
            return math.tanh(x)
    """,
    "np.clip": """
        def kernel(x: float) -> float:
            return np.clip(x, 0.0, 1.0)
    """,
    "if on 'x > 0.0'": """
        def kernel(x: float) -> float:
            if x > 0.0:
                return x
            return 0.0
    """,
    "a range bound on 'n'": """
        def kernel(x: float, n: int) -> float:
            for k in range(n):
                x = x + 1.0
            return x
    """,
    "ifexp on 'y'": """
        def kernel(x: float) -> float:
            y = x * 2.0
            return 1.0 if y else 0.0
    """,
    "and/or on 'x > 0.0'": """
        def kernel(x: float, y: float) -> bool:
            return x > 0.0 and y > 0.0
    """,
    "a chained comparison": """
        def kernel(x: float) -> bool:
            return 0.0 < x < 1.0
    """,
    "'s.depth', not a field of StateRecord": """
        def kernel(s: StateRecord) -> float:
            return s.depth
    """,
    "the global helper": """
        def kernel(x: float) -> float:
            return helper(x)
    """,
}
ALLOWED = [
    """
    def kernel(x: float, cfg: ConfigRecord) -> float:
        if cfg.dual:
            return x
        return 0.0
    """,
    """
    def kernel(x: float, hull: FloatArray) -> float:
        n = hull.shape[1] - 1
        for k in range(1, n):
            x = x + hull[0, k]
        return x
    """,
    """
    def kernel(x: float) -> float:
        for k in range(1, MAX_KNOTS):
            x = select(k < 2, x, x + 1.0)
        return clip(x, -1.0, 1.0)
    """,
    """
    def kernel(x: float, cfg: ConfigRecord) -> float:
        lo = cfg.obs_low
        return 1.0 if lo[0] > 0.0 else math.fabs(x)
    """,
]


def _violations(source, monkeypatch):
    """The contract's findings on a kernel of ``source`` (not compiled: only its code is read) in a
    namespace of transition.py's names."""
    source = textwrap.dedent(source)
    namespace = {**vars(tr), "helper": lambda x: x}
    exec(compile(source, "<contract test>", "exec"), namespace)
    holder = type("Holder", (), {"py_func": namespace["kernel"]})()
    monkeypatch.setattr(inspect, "getsource", lambda obj: source)
    return Kernel(holder).violations()


@pytest.mark.parametrize("message", list(REFUSED))
def test_the_contract_refuses_what_would_not_trace(message, monkeypatch):
    """The checker itself: each of these breaks the contract and is reported (so the test above can fail)."""
    violations = _violations(REFUSED[message], monkeypatch)
    assert any(message in v for v in violations), violations


@pytest.mark.parametrize("source", ALLOWED)
def test_the_contract_allows_branches_on_static_values(source, monkeypatch):
    assert _violations(source, monkeypatch) == []
