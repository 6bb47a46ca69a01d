"""Griffe extensions for the documentation build (``mkdocs.yml`` loads them for mkdocstrings).

- :class:`AgentsSubpackage`: the repository's ``agents/`` folder installs as the subpackage
  ``swarm_envs.agents`` (setuptools ``package-dir``), a layout griffe's static finder does not follow.
  When griffe has loaded ``swarm_envs``, this visits each file of ``agents/`` as a module of that
  subpackage, so the API pages show the names users import.
- :class:`SphinxRoles`: the docstrings use Sphinx roles (``:class:`~pkg.Name```); MkDocs renders them
  as inline code (``Name``) instead of showing the role markup.
- :class:`TaskModules`: a task module makes its env class, ``parallel_env`` and ``env`` when it is imported
  (``swarm_envs.tasks.factories.task_module``), so static analysis sees only an assignment; this takes those
  members, with their generated signatures and docstrings, from the imported module.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import griffe

AGENTS = Path(__file__).resolve().parent.parent / "agents"
_ROLE = re.compile(r":(?:py:)?(?:mod|class|func|meth|attr|data|exc|obj):`(~?)([^`]+)`")


def _inline(match: re.Match) -> str:
    tilde, target = match.groups()
    return f"`{target.rsplit('.', 1)[-1] if tilde else target}`"


class SphinxRoles(griffe.Extension):
    """Render ``:role:`target``` as ``target`` (``~`` keeps the last dotted part, as in Sphinx)."""

    def on_instance(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        if obj.docstring is not None:
            obj.docstring.value = _ROLE.sub(_inline, obj.docstring.value)


class TaskModules(griffe.Extension):
    """Replace the members a task module assigns from ``task_module(...)`` by the imported objects."""

    def on_module_members(self, *, mod: griffe.Module, **kwargs: Any) -> None:
        imported = mod.members.get("task_module")
        if imported is None or not imported.is_alias:  # griffe does not follow ``a, b, c = call()``
            return
        runtime = griffe.inspect(mod.path)
        env_class = runtime.members["raw_env"].name  # the class as named in its module ("AggregationEnv")
        for name in ("parallel_env", "env", env_class):
            if name in runtime.members:
                mod.set_member(name, runtime.members[name])


class AgentsSubpackage(griffe.Extension):
    """Attach ``agents/*.py`` to the loaded ``swarm_envs`` package as ``swarm_envs.agents``."""

    def on_package(self, *, pkg: griffe.Module, loader: griffe.GriffeLoader, **kwargs: Any) -> None:
        if pkg.path != "swarm_envs" or "agents" in pkg.members:
            return

        def visit(name: str, path: Path, parent: griffe.Module) -> griffe.Module:
            module = griffe.visit(
                name,
                path,
                path.read_text(encoding="utf-8"),
                parent=parent,
                extensions=loader.extensions,
                docstring_parser=loader.docstring_parser,
                docstring_options=loader.docstring_options,
                lines_collection=loader.lines_collection,
                modules_collection=loader.modules_collection,
            )
            parent.set_member(name, module)
            return module

        package = visit("agents", AGENTS / "__init__.py", pkg)
        for path in sorted(AGENTS.glob("*.py")):
            if path.stem != "__init__":
                visit(path.stem, path, package)
