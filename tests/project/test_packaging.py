"""Packaging: agents/ installs as ``swarm_envs.agents`` (no top-level ``agents``), and the console commands run."""

from __future__ import annotations

import importlib
import importlib.util
import json
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

tomllib = pytest.importorskip("tomllib", reason="tomllib needs Python >= 3.11")

ROOT = Path(__file__).resolve().parents[2]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
SCRIPTS = PYPROJECT["project"]["scripts"]
DIST_INFO = f"swarm_envs-{PYPROJECT['project']['version']}.dist-info"
#: source folder -> installed package (the same mapping as tests/project/test_imports.py)
SOURCES = {"swarm_envs": "swarm_envs", "agents": "swarm_envs.agents"}


def _package_folders() -> set[str]:
    """Every package (folder with an __init__.py) under the source folders, by installed name."""
    found = set()
    for folder, package in SOURCES.items():
        for init in (ROOT / folder).rglob("__init__.py"):
            parts = init.parent.relative_to(ROOT / folder).parts
            found.add(".".join([package, *parts]))
    return found


def test_pyproject_lists_every_package_and_maps_agents():
    setuptools_cfg = PYPROJECT["tool"]["setuptools"]
    assert set(setuptools_cfg["packages"]) == _package_folders()
    assert setuptools_cfg["package-dir"] == {"swarm_envs.agents": "agents"}
    assert not any(p == "agents" or p.startswith("agents.") for p in setuptools_cfg["packages"])


def test_console_scripts_declared():
    assert set(SCRIPTS) == {"swarm-train", "swarm-validate", "swarm-benchmark", "swarm-demo", "swarm-export"}
    for target in SCRIPTS.values():
        module, _, function = target.partition(":")
        assert module.startswith("swarm_envs.") and function in ("main", "train")
        assert callable(getattr(importlib.import_module(module), function))


def test_installed_agents_is_not_a_top_level_package(tmp_path):
    """Outside the repository (so the current directory does not shadow anything), the installed suite
    provides swarm_envs.agents, and no top-level ``agents`` of ours."""
    code = (
        "import importlib.util, json\n"
        "a = importlib.util.find_spec('swarm_envs.agents')\n"
        "t = importlib.util.find_spec('agents')\n"
        "print(json.dumps([a and a.origin, t and t.origin]))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, check=True)
    agents_origin, top_origin = json.loads(out.stdout)
    if agents_origin is None:
        pytest.skip("swarm_envs is not installed in this Python (pip install -e .)")
    assert top_origin is None or not Path(top_origin).resolve().is_relative_to(ROOT / "agents")
    assert Path(agents_origin).name == "__init__.py"


def _script(name: str) -> str | None:
    beside = Path(sys.executable).parent / name  # the scripts of the Python running the tests
    return str(beside) if beside.exists() else shutil.which(name)


@pytest.mark.parametrize("command", sorted(SCRIPTS))
def test_console_command_help(command):
    module = SCRIPTS[command].split(":")[0]
    if importlib.util.find_spec(module) is None:
        pytest.skip(f"{command}'s target module {module} is not in this checkout yet")
    path = _script(command)
    if path is None:
        pytest.skip(f"{command} is not on PATH (install the package: pip install -e .)")
    result = subprocess.run([path, "--help"], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    assert "usage" in result.stdout.lower()


def test_wheel_has_no_top_level_agents(tmp_path):
    """Build a wheel from a copy of the sources: agents/ lands as swarm_envs/agents/, nothing else at the top."""
    if importlib.util.find_spec("setuptools") is None:
        pytest.skip("setuptools is not installed (needed to build the wheel without network)")
    src = tmp_path / "src"
    src.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, src / name)
    for folder in SOURCES:
        shutil.copytree(ROOT / folder, src / folder, ignore=shutil.ignore_patterns("__pycache__"))
    out = tmp_path / "wheel"
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q", "-w", str(out), str(src)],
        check=True,
        capture_output=True,
        timeout=600,
    )
    (wheel,) = out.glob("swarm_envs-*.whl")
    with zipfile.ZipFile(wheel) as archive:
        names = archive.namelist()
        entry_points = archive.read(f"{DIST_INFO}/entry_points.txt").decode()
    assert {n.split("/")[0] for n in names} == {"swarm_envs", DIST_INFO}
    for f in (ROOT / "agents").glob("*.py"):
        assert f"swarm_envs/agents/{f.name}" in names
    for command, target in SCRIPTS.items():
        assert f"{command} = {target}" in entry_points
