"""Write the generated tables of docs/settings.md from the settings rules: ``python docs/settings_tables.py``.

The tables sit between ``<!-- generated: NAME -->`` and ``<!-- end generated -->`` markers: ``common`` (every
env's settings, :func:`swarm_envs.tasks.settings_tables.settings_table`), one per suite task with settings of its own
(its env id), and ``train`` (:func:`swarm_envs.agents.config.bounds_table`). Text outside the markers is
kept. ``tests/integration/test_reliability_docs.py`` checks that the page holds what this script writes.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

PAGE = Path(__file__).resolve().parent / "settings.md"


def tables() -> dict[str, str]:
    """Marker name -> the table it holds."""
    from swarm_envs.agents.config import bounds_table
    from swarm_envs.registry import list_envs, task_class
    from swarm_envs.tasks.settings_tables import settings_table

    out = {"common": settings_table()}
    for env_id in list_envs():
        if env_id.startswith("swarm_envs/") and task_class(env_id).settings():
            out[env_id] = settings_table(task_class(env_id).settings())
    out["train"] = bounds_table()
    return out


def render(text: str) -> str:
    """``text`` with every marked block replaced by its table; ``KeyError`` for a marker without one."""
    generated = tables()

    def block(match: re.Match) -> str:
        return f"{match.group(1)}\n{generated[match.group(2)].rstrip()}\n<!-- end generated -->"

    return re.sub(r"(<!-- generated: (\S+) -->)\n.*?<!-- end generated -->", block, text, flags=re.S)


if __name__ == "__main__":
    new = render(PAGE.read_text(encoding="utf-8"))
    PAGE.write_text(new, encoding="utf-8")
    sys.exit(0)
