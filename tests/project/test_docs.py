"""The documentation site covers the whole package and its figures exist (CI builds it with ``mkdocs build --strict``)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
#: source folder -> installed package (as in tests/project/test_imports.py)
SOURCES = {"swarm_envs": "swarm_envs", "agents": "swarm_envs.agents"}


def _modules() -> list[str]:
    names = []
    for folder, package in SOURCES.items():
        for path in sorted((ROOT / folder).rglob("*.py")):
            parts = list(path.relative_to(ROOT / folder).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            names.append(".".join([package, *parts]))
    return names


def _pages() -> dict[Path, str]:
    return {p: p.read_text(encoding="utf-8") for p in DOCS.rglob("*.md")}


def test_every_module_has_an_api_entry():
    documented = {m for text in _pages().values() for m in re.findall(r"^::: ([\w.]+)", text, flags=re.M)}
    missing = [m for m in _modules() if m not in documented]
    assert not missing, f"add '::: <module>' lines for {missing} to a page under docs/api/"


def test_every_nav_page_exists():
    nav = re.findall(r":\s*([\w/]+\.md)\s*$|^\s*-\s*([\w/]+\.md)\s*$", (ROOT / "mkdocs.yml").read_text(), flags=re.M)
    pages = [a or b for a, b in nav]
    assert len(pages) >= 10
    for page in pages:
        assert (DOCS / page).is_file(), page


def test_images_exist_and_are_small():
    linked = [(page, img) for page, text in _pages().items() for img in re.findall(r"!\[[^\]]*\]\(([^)\s]+)\)", text)]
    assert any("validation" in str(page) for page, _ in linked), "the validation page shows its figures"
    for page, img in linked:
        path = (page.parent / img).resolve()
        assert path.is_file(), f"{page.name}: {img}"
        assert path.stat().st_size < 200_000, f"{img} is {path.stat().st_size} bytes; keep committed figures < 200 KB"


@pytest.mark.parametrize("name", ["aggregation", "flocking", "centroid_seeking", "sorted_following", "parity_clustering", "mid_angle_navigation"])
def test_environment_page_renders_the_task_docstring(name):
    text = (DOCS / "environments" / f"{name}.md").read_text(encoding="utf-8")
    assert f"::: swarm_envs.tasks.{name}_v0.parallel_env" in text
