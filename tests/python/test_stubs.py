"""The stub of the compiled module (python/revcol/_core.pyi) against the binding itself.

mypy.stubtest (run by scripts/test.sh) checks that every name exists on both sides, but it
cannot read a pybind11 function's signature (there is no __text_signature__). This test
does: it reads the signature pybind11 writes on the first line of each docstring and
compares, for every function and method, the parameter names, their kinds (positional,
keyword-only), which have defaults and the default values the stub spells out; and for
every class its properties (read-only or settable) and its static properties (ClassVar).
"""
from __future__ import annotations

import ast
import inspect
from pathlib import Path

import pytest

import revcol
from revcol import _core

STUB = Path(revcol.__file__).with_name("_core.pyi")
if not STUB.exists():  # running against an install without the stub: use the source tree's
    STUB = Path(__file__).resolve().parents[2] / "python" / "revcol" / "_core.pyi"


def _params(fn: ast.FunctionDef) -> list[tuple[str, str, object]]:
    """(name, kind, default) of each parameter; default is absent, '...' or a literal."""
    a = fn.args
    out: list[tuple[str, str, object]] = []
    positional = a.posonlyargs + a.args
    pos_defaults = [None] * (len(positional) - len(a.defaults)) + list(a.defaults)
    for k, (arg, d) in enumerate(zip(positional, pos_defaults)):
        out.append((arg.arg, "posonly" if k < len(a.posonlyargs) else "positional", _default(d)))
    for arg, d in zip(a.kwonlyargs, a.kw_defaults):
        out.append((arg.arg, "kwonly", _default(d)))
    return out


def _default(node: ast.expr | None) -> object:
    if node is None:
        return "<absent>"
    if isinstance(node, ast.Constant) and node.value is Ellipsis:
        return "..."
    return ast.literal_eval(node)


def _runtime_signature(obj: object, name: str) -> ast.FunctionDef:
    """The signature pybind11 wrote on the first line of the docstring, parsed."""
    first = (obj.__doc__ or "").lstrip().splitlines()[0]
    assert first.startswith(name + "("), f"{name}: no pybind11 signature in {first!r}"
    return ast.parse(f"def {first}: ...").body[0]  # type: ignore[return-value]


def _stub() -> ast.Module:
    return ast.parse(STUB.read_text(encoding="utf-8"))


def _public(names) -> set[str]:
    return {n for n in names if not n.startswith("_")}


def _stub_members(cls: ast.ClassDef) -> dict[str, ast.AST]:
    """Members of a stub class, with those of its stub-only bases (_Logged)."""
    out: dict[str, ast.AST] = {}
    classes = {n.name: n for n in _stub().body if isinstance(n, ast.ClassDef)}
    for base in cls.bases:
        if isinstance(base, ast.Name) and base.id in classes:
            out.update(_stub_members(classes[base.id]))
    for node in cls.body:
        if isinstance(node, ast.FunctionDef):
            decorators = [ast.unparse(d) for d in node.decorator_list]
            if any(d.endswith(".setter") for d in decorators):
                out[node.name + ".setter"] = node
            else:
                out[node.name] = node
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            out[node.target.id] = node
    return out


def _compare(stub_fn: ast.FunctionDef, runtime_fn: ast.FunctionDef, where: str, method: bool) -> None:
    stub_p, run_p = _params(stub_fn), _params(runtime_fn)
    if method:  # pybind11 writes self without a default; the stub too
        assert stub_p[0][0] == "self" and run_p[0][0] == "self", where
        stub_p, run_p = stub_p[1:], run_p[1:]
    assert [(n, k) for n, k, _ in stub_p] == [(n, k) for n, k, _ in run_p], where
    for (n, _, sd), (_, _, rd) in zip(stub_p, run_p):
        assert (sd == "<absent>") == (rd == "<absent>"), f"{where}: default of {n}"
        if sd not in ("<absent>", "..."):
            assert sd == rd, f"{where}: default of {n}: stub {sd!r}, binding {rd!r}"


def test_every_name_is_in_both():
    stub_names = set()
    for node in _stub().body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            stub_names.add(node.name)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            stub_names.add(node.target.id)  # module attributes (build)
    runtime = {n for n in dir(_core) if not n.startswith("__")}
    assert _public(stub_names) == _public(runtime)


FUNCTIONS = [n.name for n in _stub().body if isinstance(n, ast.FunctionDef)]
CLASSES = [n.name for n in _stub().body if isinstance(n, ast.ClassDef) and not n.name.startswith("_")]


@pytest.mark.parametrize("name", FUNCTIONS)
def test_function_signatures(name):
    stub_fn = next(n for n in _stub().body if isinstance(n, ast.FunctionDef) and n.name == name)
    _compare(stub_fn, _runtime_signature(getattr(_core, name), name), name, method=False)


@pytest.mark.parametrize("name", CLASSES)
def test_class_members(name):
    cls = next(n for n in _stub().body if isinstance(n, ast.ClassDef) and n.name == name)
    runtime_cls = getattr(_core, name)
    stub = _stub_members(cls)
    if issubclass(runtime_cls, Exception):
        return  # InvalidArgument: registered by pybind11 as a ValueError, no members of its own
    runtime = {m: v for m, v in vars(runtime_cls).items()
               if not m.startswith("_") or m in ("__init__", "__eq__", "__getstate__", "__setstate__")}
    assert set(runtime) == {m for m in stub if not m.endswith(".setter")}, name
    for m, v in runtime.items():
        where = f"{name}.{m}"
        node = stub[m]
        kind = type(v).__name__
        if kind == "property":
            assert isinstance(node, ast.FunctionDef) and "property" in [ast.unparse(d) for d in node.decorator_list], where
            assert (v.fset is not None) == (m + ".setter" in stub), f"{where}: settable"
        elif kind == "pybind11_static_property":
            assert isinstance(node, ast.AnnAssign) and ast.unparse(node.annotation).startswith("ClassVar"), where
        elif isinstance(v, staticmethod):
            assert isinstance(node, ast.FunctionDef) and "staticmethod" in [ast.unparse(d) for d in node.decorator_list], where
            _compare(node, _runtime_signature(getattr(runtime_cls, m), m), where, method=False)
        else:
            assert isinstance(node, ast.FunctionDef), where
            assert inspect.isroutine(v), where
            _compare(node, _runtime_signature(v, m), where, method=True)
