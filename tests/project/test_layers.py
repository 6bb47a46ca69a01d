"""The package's layers hold (pyproject.toml ``[tool.importlinter]``): `lint-imports` finds no import from a
lower layer to a higher one (no package cycle, e.g. platforms -> comm -> platforms), none between the two
adapters, and no task module importing an adapter."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

pytest.importorskip("importlinter", reason="import-linter is not installed (the test extra installs it)")


def test_import_contracts_are_kept():
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    code = "import sys; from importlinter.cli import lint_imports; sys.exit(lint_imports(config_filename='pyproject.toml', no_cache=True))"
    result = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stdout[-4000:] + result.stderr[-2000:]
    assert "Contracts: 2 kept, 0 broken." in result.stdout


def _private_name_imports(folder: Path) -> list[str]:
    """``from swarm_envs.x import _name`` (or ``agents``) in the modules under ``folder``: one module reading
    another's private name."""
    import ast

    found = []
    for path in sorted(folder.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] in ("swarm_envs", "agents"):
                found += [f"{path.relative_to(ROOT)}:{node.lineno} {node.module}.{a.name}" for a in node.names if a.name.startswith("_") and not a.name.startswith("__")]
    return found


@pytest.mark.parametrize("folder", ["swarm_envs", "agents"])
def test_no_module_imports_another_modules_private_names(folder):
    assert _private_name_imports(ROOT / folder) == []


def test_the_private_import_check_finds_one():
    assert _private_name_imports(ROOT / "swarm_envs" / "export") == [] and _private_name_imports(ROOT / "tests") != []
