"""Code blocks of docs/ run as written (in a fresh folder, with their own budgets)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[1] / "docs"


def snippet(page: str, marker: str) -> str:
    """The python code block of ``docs/<page>`` that contains ``marker``."""
    blocks = re.findall(r"```python\n(.*?)```", (DOCS / page).read_text(encoding="utf-8"), flags=re.S)
    found = [b for b in blocks if marker in b]
    assert len(found) == 1, f"{page}: {len(found)} python blocks contain {marker!r}"
    return found[0]


@pytest.mark.slow  # 20,480 PPO steps in two worker processes; tests/test_vector_wrappers.py trains the same SuperSuit path briefly
def test_supersuit_snippet_runs(tmp_path, monkeypatch):
    """docs/training.md's SuperSuit + SB3 snippet: two worker processes, 20,480 PPO steps (about 15 s idle)."""
    pytest.importorskip("supersuit", reason="supersuit is not installed: pip install -e '.[test]'")
    monkeypatch.chdir(tmp_path)
    code = snippet("training.md", "import supersuit")
    assert "set_torch_threads()" in code
    exec(compile(code, "docs/training.md", "exec"), {"__name__": "__docs__"})
