"""docs/settings.md states the rules as they are: its tables are the ones generated from the settings
rules (``settings_table``) and from train.py's config bounds (``bounds_table``), and every bound has a reason."""

from __future__ import annotations

from pathlib import Path

import pytest

from swarm_envs.agents.config import BOUNDS, bounds_table
from swarm_envs.registry import list_envs, task_class
from swarm_envs.settings import COMMON_SETTINGS, Choice, Flag, settings_table

PAGE = Path(__file__).resolve().parents[1] / "docs" / "settings.md"


def test_settings_page_holds_the_generated_tables():
    text = PAGE.read_text(encoding="utf-8")
    assert settings_table() in text, "regenerate the common table of docs/settings.md from settings_table()"
    for env_id in (i for i in list_envs() if i.startswith("swarm_envs/")):  # the suite's own (tests register others)
        own = {k: v for k, v in task_class(env_id).settings().items() if v.why}
        if own:
            assert settings_table(task_class(env_id).settings()) in text, f"the table of {env_id}'s settings"
    assert bounds_table() in text, "regenerate the train.py table of docs/settings.md from bounds_table()"


@pytest.mark.parametrize("key", sorted(COMMON_SETTINGS))
def test_every_bounded_setting_states_why(key):
    rule = COMMON_SETTINGS[key]
    if not isinstance(rule, Flag) and not (isinstance(rule, Choice) and len(rule.choices) <= 3):
        assert rule.why, f"{key}: state the reason for its bounds (Setting.why)"


def test_every_config_bound_states_why():
    assert all(why for _, _, why in BOUNDS.values())
