"""docs/settings.md states the rules as they are: its tables are the ones generated from the settings
rules (``settings_table``) and from train.py's config bounds (``bounds_table``), and every bound has a reason."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import pytest

from swarm_envs.agents.config import BOUNDS, bounds_table
from swarm_envs.registry import list_envs, task_class
from swarm_envs.tasks.settings import COMMON_SETTINGS, Choice, Flag, Int, Real
from swarm_envs.tasks.settings_tables import settings_table

PAGE = Path(__file__).resolve().parents[2] / "docs" / "settings.md"


def test_settings_page_holds_the_generated_tables():
    spec = importlib.util.spec_from_file_location("settings_tables", PAGE.parent / "settings_tables.py")
    generator = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(generator)
    text = PAGE.read_text(encoding="utf-8")
    marked = set(re.findall(r"<!-- generated: (\S+) -->", text))
    assert marked == set(generator.tables()), "every table has its marker: add the missing ones, then run python docs/settings_tables.py"
    assert generator.render(text) == text, "regenerate the tables: python docs/settings_tables.py"
    assert settings_table() in text and bounds_table() in text


def test_every_task_setting_with_bounds_states_why():
    for env_id in (i for i in list_envs() if i.startswith("swarm_envs/")):
        for key, rule in task_class(env_id).settings().items():
            if isinstance(rule, (Int, Real)):
                assert rule.why, f"{env_id}: {key}: state the reason for its bounds (why=...)"


@pytest.mark.parametrize("key", sorted(COMMON_SETTINGS))
def test_every_bounded_setting_states_why(key):
    rule = COMMON_SETTINGS[key]
    if not isinstance(rule, Flag) and not (isinstance(rule, Choice) and len(rule.choices) <= 3):
        assert rule.why, f"{key}: state the reason for its bounds (Setting.why)"


def test_every_config_bound_states_why():
    assert all(why for _, _, why in BOUNDS.values())
