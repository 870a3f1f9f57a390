"""The package's import graph: no circle, no module importing one above it,
every import of the package at the top of its module.

The layers below are the architecture written down once (lowest first); a
module may import its own layer or any layer below it.  The graph is read
from the source with ``ast`` (imports anywhere in a file count), so an import
hidden inside a function cannot hide a tie.
"""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "ivkernels"

#: Layers, lowest first: each entry is a module or a package prefix.
LAYERS = [
    # leaves: they import nothing of the package, or only each other
    ["ivkernels._version", "ivkernels.colour", "ivkernels.kernels.checks", "ivkernels.kernels.thread_count",
     "ivkernels.kernels.cache", "ivkernels.kernels.workspace"],
    # the rules on what users hand in, and the settings
    ["ivkernels.validation"],
    ["ivkernels.params", "ivkernels.priors"],
    # reading and writing files, pictures
    ["ivkernels.io", "ivkernels.flowio", "ivkernels.viz"],
    # the kernels (every backend, the references, the cases), then the backend objects
    ["ivkernels.kernels"],
    ["ivkernels.backends"],
    # host side: the solver, then the flow that uses its pyramid
    ["ivkernels.solver"],
    ["ivkernels.flow"],
    # the public API, what runs it at scale, the command line
    ["ivkernels.decompose"],
    ["ivkernels.parallel"],
    ["ivkernels.cli"],
    # the research harness sits above the library
    ["ivkernels.evaluation"],
    ["ivkernels"],
]

#: Third-party modules that may be imported inside a function: optional
#: dependencies, and the two kernel runtimes, each loaded only when its
#: backend is asked for (Taichi's import starts a runtime and prints a banner;
#: the Taichi and NumPy backends never load Warp).
LAZY_ALLOWED = {"ray", "scipy", "taichi", "warp", "psutil", "OpenEXR"}


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _is_package(path: Path) -> bool:
    return path.name == "__init__.py"


def _imports(name: str, path: Path, known: set[str]):
    """Yield (imported module, line, at top level) for every import in ``path``."""
    tree = ast.parse(path.read_text(), str(path))
    top_level = {id(node) for node in tree.body}
    # imports inside `if TYPE_CHECKING:` or try/except at module level count as top level
    for node in tree.body:
        if isinstance(node, (ast.If, ast.Try)):
            for sub in ast.walk(node):
                top_level.add(id(sub))
    base = name if _is_package(path) else name.rpartition(".")[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, node.lineno, id(node) in top_level
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                parent = base
                for _ in range(node.level - 1):
                    parent = parent.rpartition(".")[0]
                mod = f"{parent}.{node.module}" if node.module else parent
            else:
                mod = node.module
            for alias in node.names:
                full = f"{mod}.{alias.name}"
                yield (full if full in known else mod), node.lineno, id(node) in top_level


def _layer(module: str) -> int:
    best, best_len = None, -1
    for rank, prefixes in enumerate(LAYERS):
        for prefix in prefixes:
            if (module == prefix or module.startswith(prefix + ".")) and len(prefix) > best_len:
                best, best_len = rank, len(prefix)
    if best is None:
        raise AssertionError(f"module {module} is in no layer of tests/test_import_graph.py")
    return best


def _graph():
    modules = _modules()
    known = set(modules)
    edges, lazy = {}, []
    for name, path in modules.items():
        targets = set()
        for target, line, top in _imports(name, path, known):
            root = target.split(".")[0]
            if root == "ivkernels":
                if target != name:
                    targets.add(target)
                if not top:
                    lazy.append(f"{name}:{line} imports {target} inside a function")
            elif not top and root not in LAZY_ALLOWED:
                lazy.append(f"{name}:{line} imports {target} inside a function")
        edges[name] = targets
    return edges, lazy


def test_every_module_has_a_layer():
    for name in _modules():
        _layer(name)


def test_no_module_imports_one_above_it():
    edges, _ = _graph()
    upward = [f"{a} (layer {_layer(a)}) imports {b} (layer {_layer(b)})"
              for a, targets in edges.items() for b in sorted(targets) if _layer(b) > _layer(a)]
    assert not upward, "\n".join(upward)


def test_no_import_circle():
    edges, _ = _graph()
    # A package's __init__ that imports its own submodules is not a circle:
    # the submodule importing its package's name resolves to the submodule.
    state, stack, circles = {}, [], []

    def visit(node):
        state[node] = "open"
        stack.append(node)
        for nxt in sorted(edges.get(node, ())):
            if nxt not in edges:
                continue
            if state.get(nxt) == "open":
                circles.append(" -> ".join(stack[stack.index(nxt):] + [nxt]))
            elif nxt not in state:
                visit(nxt)
        stack.pop()
        state[node] = "done"

    for node in sorted(edges):
        if node not in state:
            visit(node)
    assert not circles, "\n".join(circles)


def test_imports_sit_at_the_top():
    _, lazy = _graph()
    assert not lazy, "\n".join(lazy)


@pytest.mark.parametrize("hidden", ["def f():\n    from ivkernels import decompose\n"])
def test_the_checker_sees_an_import_inside_a_function(tmp_path, hidden):
    path = tmp_path / "probe.py"
    path.write_text(hidden)
    found = list(_imports("ivkernels.probe", path, {"ivkernels.decompose"}))
    assert found == [("ivkernels.decompose", 2, False)]
