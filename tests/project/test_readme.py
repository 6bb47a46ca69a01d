"""The README is a newcomer's five minutes: short, its Quickstart is what CI runs and its links resolve
(its code blocks run in tests/project/test_doc_blocks.py)."""

from __future__ import annotations

import re
from pathlib import Path


ROOT = Path(__file__).resolve().parents[2]
README = (ROOT / "README.md").read_text(encoding="utf-8")


def _quickstart_commands() -> list[str]:
    section = README.split("## Quickstart", 1)[1].split("\n## ", 1)[0]
    block = re.search(r"```bash\n(.*?)```", section, re.S).group(1)
    return [line for line in block.splitlines() if line.strip() and not line.lstrip().startswith("#")]


def test_readme_is_short():
    assert len(README.splitlines()) <= 250


def test_quickstart_holds_two_commands_and_ci_runs_the_test_command():
    commands = _quickstart_commands()
    assert len(commands) == 2
    train, tests = commands
    assert "train.py --config configs/aggregation.yaml" in train
    assert tests.endswith("python -m pytest -q")
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8").splitlines()
    assert tests in ci, ".ci/run must call the README's test command verbatim"


def test_relative_links_resolve():
    links = re.findall(r"\]\(([^)\s#]+)(?:#[^)]*)?\)", README)
    local = [link for link in links if "://" not in link]
    assert local, "the README links to the docs"
    missing = [link for link in local if not (ROOT / link).exists()]
    assert not missing, missing
