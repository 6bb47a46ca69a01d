"""Every module of the package imports, and the package has no import cycle.

The import graph is read from the source with :mod:`ast` and counts every ``import`` statement,
including the ones inside functions (a lazy import still ties two modules together). Implicit
imports of parent packages are not edges. ``agents/`` is the package ``swarm_envs.agents``.
"""

from __future__ import annotations

import ast
import importlib
from graphlib import CycleError, TopologicalSorter
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
#: source folder -> package name (pyproject's package-dir; tests/project/test_packaging.py checks they agree)
SOURCES = {"swarm_envs": "swarm_envs", "agents": "swarm_envs.agents"}


def module_files(root: Path, sources: dict[str, str]) -> dict[str, Path]:
    """Dotted module name -> source file, for every ``.py`` file under the source folders."""
    modules = {}
    for folder, package in sources.items():
        base = root / folder
        for path in sorted(base.rglob("*.py")):
            parts = list(path.relative_to(base).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            modules[".".join([package, *parts])] = path
    return modules


def _imported(module: str, path: Path, node: ast.Import | ast.ImportFrom, modules: dict[str, Path]) -> set[str]:
    """The package's modules one import statement names."""
    found = set()
    if isinstance(node, ast.Import):
        for alias in node.names:
            name = alias.name
            while name and name not in modules:  # "import a.b.c" where c is an attribute
                name = name.rpartition(".")[0]
            if name:
                found.add(name)
        return found
    if node.level:  # relative import
        package = module if path.name == "__init__.py" else module.rpartition(".")[0]
        for _ in range(node.level - 1):
            package = package.rpartition(".")[0]
        base = f"{package}.{node.module}" if node.module else package
    else:
        base = node.module or ""
    for alias in node.names:
        if f"{base}.{alias.name}" in modules:  # "from pkg import submodule"
            found.add(f"{base}.{alias.name}")
        elif base in modules:
            found.add(base)
    return found


def import_graph(modules: dict[str, Path]) -> dict[str, set[str]]:
    """Module -> the package's modules it imports anywhere in its source."""
    graph = {}
    for module, path in modules.items():
        deps: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                deps |= _imported(module, path, node, modules)
        deps.discard(module)
        graph[module] = deps
    return graph


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One import cycle (``[a, b, ..., a]``) or None."""
    try:
        TopologicalSorter(graph).prepare()
    except CycleError as err:
        return list(err.args[1])
    return None


MODULES = module_files(ROOT, SOURCES)


def test_graph_finds_a_lazy_cycle_and_a_relative_import(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "sub" / "__init__.py").write_text("from . import b\n")
    (pkg / "a.py").write_text("def f():\n    from pkg.sub.b import g\n    return g\n")
    (pkg / "sub" / "b.py").write_text("import numpy\nfrom ..a import f\n")
    (pkg / "c.py").write_text("from pkg import a\n")
    graph = import_graph(module_files(tmp_path, {"pkg": "pkg"}))
    assert graph["pkg.sub"] == {"pkg.sub.b"}
    assert graph["pkg.c"] == {"pkg.a"}
    assert graph["pkg.sub.b"] == {"pkg.a"}
    cycle = find_cycle(graph)
    assert cycle is not None and set(cycle) == {"pkg.a", "pkg.sub.b"}
    graph["pkg.a"].clear()
    assert find_cycle(graph) is None


def test_sources_found():
    assert "swarm_envs.adapters.env" in MODULES and "swarm_envs.agents.scripted" in MODULES
    assert "swarm_envs.sensing.scale_free" in MODULES and "swarm_envs.validate.__main__" in MODULES


def test_no_import_cycle():
    cycle = find_cycle(import_graph(MODULES))
    assert cycle is None, "import cycle: " + " -> ".join(cycle or [])


@pytest.mark.parametrize("module", sorted(MODULES))
def test_module_imports(module):
    try:
        importlib.import_module(module)
    except ModuleNotFoundError as err:
        if err.name and not err.name.startswith("swarm_envs"):
            pytest.skip(f"optional dependency {err.name!r} is not installed")
        raise
