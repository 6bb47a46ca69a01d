"""Each task's ``parallel_env`` has an explicit, typed, documented signature that matches the env's defaults."""

from __future__ import annotations

import inspect
import re
import typing

import pytest

from swarm_envs import aggregation_v0, centroid_seeking_v0, flocking_v0, mid_angle_navigation_v0, parity_clustering_v0, sorted_following_v0
from swarm_envs.tasks.settings import COMMON_DEFAULTS, COMMON_SETTINGS, Choice
from swarm_envs.sim.platforms import PLATFORMS

TASK_MODULES = [aggregation_v0, flocking_v0, centroid_seeking_v0, sorted_following_v0, parity_clustering_v0, mid_angle_navigation_v0]
_CHOICES = {key: rule.choices for key, rule in COMMON_SETTINGS.items() if isinstance(rule, Choice)}
SECTIONS = ["Description", "Action Space", "Observation Space", "Rewards", "Starting State", "Episode End", "Arguments", "Version History"]


def _defaults(module) -> dict:
    return {**COMMON_DEFAULTS, **module.raw_env.TASK.TASK_DEFAULTS}


@pytest.mark.parametrize("module", TASK_MODULES, ids=lambda m: m.__name__)
def test_signature_defaults_match_env_defaults(module):
    params = inspect.signature(module.parallel_env).parameters
    assert all(p.kind is inspect.Parameter.KEYWORD_ONLY for p in params.values())
    assert {name: p.default for name, p in params.items()} == _defaults(module)


@pytest.mark.parametrize("module", TASK_MODULES, ids=lambda m: m.__name__)
def test_every_argument_is_typed_and_choices_match_validation(module):
    hints = typing.get_type_hints(module.parallel_env)
    choices = {**_CHOICES, **{k: r.choices for k, r in module.raw_env.TASK.SETTINGS.items() if isinstance(r, Choice)}}
    assert set(hints) == set(_defaults(module)) | {"return"}
    assert hints["return"] is module.raw_env
    for name, hint in hints.items():
        literals = [arg for arg in typing.get_args(hint) if typing.get_origin(arg) is typing.Literal]
        if typing.get_origin(hint) is typing.Literal:
            literals = [hint]
        values = {v for lit in literals for v in typing.get_args(lit)}
        if type(None) in typing.get_args(hint):
            values.add(None)
        if name in choices:
            assert values == set(choices[name]), name
        elif name == "platform":
            assert values == set(PLATFORMS)
        else:
            assert not literals, f"{name}: a Literal the env does not validate"


@pytest.mark.parametrize("module", TASK_MODULES, ids=lambda m: m.__name__)
def test_docstring_has_gymnasium_sections_and_every_argument(module):
    doc = inspect.getdoc(module.parallel_env)
    headings = re.findall(r"^## (.+)$", doc, flags=re.M)
    assert headings == SECTIONS
    arguments = doc.split("## Arguments", 1)[1].split("## Version History", 1)[0]
    documented = re.findall(r"^\| ``(\w+)`` \| ([^|]+) \|", arguments, flags=re.M)
    assert [name for name, _ in documented] == list(inspect.signature(module.parallel_env).parameters)
    for name, default in documented:  # the table's default column states the real default
        assert default.strip().strip("`") == repr(_defaults(module)[name]).replace("'", '"'), name


@pytest.mark.parametrize("module", TASK_MODULES, ids=lambda m: m.__name__)
def test_arguments_reach_the_env(module):
    env = module.parallel_env(n_robots=3, sensing="ideal", max_cycles=7, arena_size=2.0)
    assert env.n_agents == 3 and env.max_cycles == 7 and env.arena.size == 2.0
    assert env.config == {**_defaults(module), "n_robots": 3, "sensing": "ideal", "max_cycles": 7, "arena_size": 2.0}
    with pytest.raises(TypeError, match=r"unknown keyword argument\(s\) \['n_robot'\]; allowed: \[.*'n_robots'"):
        module.parallel_env(n_robot=3)  # misspelt: the message lists the allowed names
    with pytest.raises(TypeError):
        module.parallel_env(3)  # keyword-only
    aec = module.env(n_robots=2, sensing="ideal")
    assert aec.possible_agents == ["robot_0", "robot_1"]


def test_task_module_builds_the_entry_points_from_a_task():
    from swarm_envs.tasks.factories import task_module
    from swarm_envs.tasks.task import Default, Real, Task

    class GainTask(Task):
        SETTINGS = {"gain": Real(2.0, low=0.0, help="the gain of the test"), "n_robots": Default(3, help="three robots")}

        def rewards(self, state, first):
            raise NotImplementedError

    doc = "Make it.\n\n## Description\n\nA test.\n\n## Rewards\n\nNone.\n\n## Version History\n\n- v0: a test.\n"
    raw_env, parallel_env, env = task_module(GainTask, doc)
    assert raw_env.__name__ == "GainEnv" and raw_env.TASK is GainTask
    params = inspect.signature(parallel_env).parameters
    assert list(params)[:2] == ["n_robots", "gain"] and params["gain"].default == 2.0 and params["n_robots"].default == 3
    text = inspect.getdoc(parallel_env)
    assert re.findall(r"^## (.+)$", text, flags=re.M) == SECTIONS
    assert "| ``gain`` | 2.0 | the gain of the test |" in text and "| ``n_robots`` | 3 | three robots |" in text
    assert "default 500 = 50 s" in text  # the default truncation section
    with pytest.raises(ValueError, match=r"missing \['Rewards'\]"):
        task_module(GainTask, "Make it.\n\n## Description\n\nA test.\n\n## Version History\n\n- v0.\n")
    with pytest.raises(ValueError, match=r"unknown \['Reward'\]"):
        task_module(GainTask, doc.replace("## Rewards", "## Reward"))
