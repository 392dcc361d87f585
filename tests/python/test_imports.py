"""The package's import graph, read statically (``ast``) from python/revcol: every ``import`` and
``from ... import``, function-local ones included, between modules of the package.

- no cycles (an explicit, commented allow-list holds the one pair still to be opened);
- nothing outside ``revcol.cli`` imports from ``revcol.cli`` (the command line is the top layer);
- no library module (outside ``revcol.studies``, ``revcol.cli`` and ``revcol.sweep``) imports from
  ``revcol.studies`` (studies build on the library, never the other way).

The graph is of the source tree, not of an installed package: it needs no build.
"""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[2] / "python" / "revcol"

#: cycles still to be opened, as unordered pairs of modules that import each other. Each entry
#: says why it is here; remove it when the cycle is gone (the test then keeps it gone).
ALLOWED_CYCLES: set = set()  # none: a pair that must import both ways is listed here, with why

#: modules that are the command line's entry points without being in revcol.cli
#: (``python -m revcol`` runs revcol/__main__.py)
CLI_ENTRY_POINTS = {"revcol.__main__"}

#: packages above the library: the studies, the sweep that runs them, and the command line
UPPER = ("revcol.studies", "revcol.sweep", "revcol.cli")


def _modules() -> dict[str, tuple[Path, bool]]:
    """Module name -> (file, is a package's __init__) for every .py file under python/revcol."""
    out = {}
    for p in sorted(PACKAGE.rglob("*.py")):
        parts = list(p.relative_to(PACKAGE.parent).with_suffix("").parts)
        is_pkg = parts[-1] == "__init__"
        out[".".join(parts[:-1] if is_pkg else parts)] = (p, is_pkg)
    return out


MODULES = _modules()
#: compiled modules (a stub beside them, no source): imported, but no edges of their own
COMPILED = {".".join(p.relative_to(PACKAGE.parent).with_suffix("").parts) for p in PACKAGE.rglob("*.pyi")}


def _ancestors(name: str) -> list[str]:
    parts = name.split(".")
    return [".".join(parts[:k]) for k in range(1, len(parts))]


def _targets(module: str, is_pkg: bool, node: ast.AST) -> list[tuple[str, int]]:
    """The package's modules an import statement loads, with its line: the module named, and for
    ``from M import name`` the submodule ``M.name`` when there is one (else ``M`` itself, whose
    body defines ``name``); the parent packages a submodule import also runs, except the
    importer's own (they are running already)."""
    if isinstance(node, ast.Import):
        named = [a.name for a in node.names]
    elif isinstance(node, ast.ImportFrom):
        if node.level:
            base = module.split(".") if is_pkg else module.split(".")[:-1]
            base = base[: len(base) - (node.level - 1)]
            mod = ".".join(base + ([node.module] if node.module else []))
        else:
            mod = node.module or ""
        named = [f"{mod}.{a.name}" if f"{mod}.{a.name}" in MODULES.keys() | COMPILED else mod
                 for a in node.names]
    else:
        return []
    own = set(_ancestors(module)) | {module}
    out = set()
    for t in named:
        if t not in MODULES:
            continue
        out.update(a for a in _ancestors(t) if a in MODULES and a not in own)
        if t != module:
            out.add(t)
    return [(t, node.lineno) for t in sorted(out)]


def _graph() -> dict[str, dict[str, int]]:
    """Module -> {imported module: first line importing it}."""
    graph = {}
    for name, (path, is_pkg) in MODULES.items():
        edges: dict[str, int] = {}
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            for t, line in _targets(name, is_pkg, node):
                edges.setdefault(t, line)
        graph[name] = edges
    return graph


GRAPH = _graph()


def _cycles(graph: dict[str, dict[str, int]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan), each sorted."""
    index, low, stack, on, comps, counter = {}, {}, [], set(), [], [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                comps.append(sorted(comp))

    for v in graph:
        if v not in index:
            visit(v)
    return comps


def _path(graph: dict[str, dict[str, int]], a: str, b: str, within: set[str]) -> list[str]:
    """A shortest import path a -> ... -> b inside ``within`` (breadth first; b reachable)."""
    prev, todo = {a: None}, [a]
    while b not in prev:
        v = todo.pop(0)
        for w in graph[v]:
            if w in within and w not in prev:
                prev[w] = v
                todo.append(w)
    out, v = [], b
    while v is not None:
        out.append(v)
        v = prev[v]
    return out[::-1]


def _describe(graph: dict[str, dict[str, int]], comp: list[str]) -> str:
    """One cycle of the component, each step with the file and line that imports."""
    a = comp[0]
    back = next(w for w in comp if a in graph[w])
    steps = _path(graph, a, back, set(comp)) + [a]
    return " -> ".join(f"{x} (line {graph[x][y]})" for x, y in zip(steps, steps[1:])) + f" -> {a}"


def test_the_graph_sees_every_module():
    assert len(MODULES) > 30 and "revcol" in MODULES and "revcol.engine" in MODULES
    assert "revcol.trajectory" in GRAPH["revcol.gas"]  # a function-local import is an edge too


def test_no_import_cycles():
    graph = {v: {w: line for w, line in edges.items()
                 if frozenset({v, w}) not in ALLOWED_CYCLES or v not in GRAPH[w]}
             for v, edges in GRAPH.items()}
    cycles = _cycles(graph)
    assert not cycles, "import cycles:\n" + "\n".join(_describe(graph, c) for c in cycles)


def test_each_allowed_cycle_is_still_there():
    """An allowed pair that no longer imports both ways is to be removed from ALLOWED_CYCLES
    (none is allowed today: this guards the list once one is)."""
    for a, b in (sorted(p) for p in ALLOWED_CYCLES):
        assert b in GRAPH[a] and a in GRAPH[b], f"{a} <-> {b} is no longer a cycle: remove it from ALLOWED_CYCLES"


def _in(module: str, package: str) -> bool:
    return module == package or module.startswith(package + ".")


def test_nothing_outside_the_command_line_imports_it():
    bad = [f"{v} imports {w} (line {line})" for v, edges in GRAPH.items()
           if not _in(v, "revcol.cli") and v not in CLI_ENTRY_POINTS for w, line in edges.items() if _in(w, "revcol.cli")]
    assert not bad, "\n".join(bad)


def test_the_library_does_not_import_the_studies():
    bad = [f"{v} imports {w} (line {line})" for v, edges in GRAPH.items()
           if not any(_in(v, p) for p in UPPER) for w, line in edges.items() if _in(w, "revcol.studies")]
    assert not bad, "\n".join(bad)
