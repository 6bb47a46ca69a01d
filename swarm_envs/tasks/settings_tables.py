"""The settings as Markdown tables: the rules with the reasons for their bounds (docs/settings.md) and the
``## Arguments`` section of each env factory's docstring."""

from __future__ import annotations
from collections.abc import Mapping
from typing import Any

from swarm_envs.tasks.settings import COMMON_SETTINGS, Setting

__all__ = ["settings_table", "arguments_table"]


def settings_table(settings: Mapping[str, Setting] | None = None) -> str:
    """A Markdown table of ``settings`` (default: :data:`COMMON_SETTINGS`): name, default, rule and the reason
    for its bounds."""
    rows = ["| setting | default | rule | why these bounds |", "|---|---|---|---|"]
    for key, setting in (COMMON_SETTINGS if settings is None else settings).items():
        rule = setting.rule().replace("|", "\\|")
        rows.append(f"| `{key}` | `{setting.default!r}` | {rule} | {setting.why or '-'} |")
    return "\n".join(rows) + "\n"


def _shown_default(value: Any) -> str:
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return repr(value)
    return "``" + repr(value).replace("'", '"') + "``"


def arguments_table(settings: Mapping[str, Setting]) -> str:
    """The ``## Arguments`` section of an env factory's docstring: a Markdown table of ``settings`` (in
    order), with each argument's default and meaning (its ``help``; else its ``doc``, else its rule)."""
    rows = [
        "## Arguments",
        "",
        "Keyword-only, SI units. Unknown names raise ``TypeError``; bad values raise ``ValueError``.",
        "",
        "| argument | default | meaning |",
        "|---|---|---|",
    ]
    for key, setting in settings.items():
        meaning = (setting.help or setting.doc or setting.rule()).replace("|", "\\|")
        rows.append(f"| ``{key}`` | {_shown_default(setting.default)} | {meaning} |")
    return "\n".join(rows) + "\n"
