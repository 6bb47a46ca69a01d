"""Infos: nested dicts of plain Python values (``json.dumps`` works), ``info_group``, ``flat_info`` and ``FlatInfos``."""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import pytest

import swarm_envs
from swarm_envs.adapters.env import INFO_GROUPS, FlatInfos, flat_info, info_group
from tests.conftest import assert_tree_equal

ENV_IDS = swarm_envs.list_envs()


def _settings(env_id: str, sensing: str) -> dict[str, Any]:
    return {"n_robots": 2 if "Centroid" in env_id else 3, "sensing": sensing, "max_cycles": 4}


def _is_plain(value: Any) -> bool:
    """A Python bool, int or float, or a tuple or list of plain values (no numpy types)."""
    if isinstance(value, (tuple, list)):
        return all(_is_plain(v) for v in value)
    return type(value) in (bool, int, float)


def _array_as_list(value: Any) -> list:
    """``json.dumps`` default for the vector env: numpy arrays only (anything else is still refused)."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not an array")


def _str_keys(tree: Any, path: str = "") -> None:
    if isinstance(tree, dict):
        for key, value in tree.items():
            assert isinstance(key, str), f"key {key!r} at {path or '/'} is not a string"
            _str_keys(value, f"{path}/{key}")


@pytest.mark.parametrize("env_id", ENV_IDS)
@pytest.mark.parametrize("sensing", ["full", "ideal"])
def test_json_dumps_the_parallel_env_infos(env_id, sensing):
    """``json.dumps(infos)`` after reset and after a step; a metric without a value yet (e.g. ``time_to_goal``
    before any arrival) is NaN, which Python's json writes as ``NaN``."""
    env = swarm_envs.make(env_id, **_settings(env_id, sensing))
    _, infos = env.reset(seed=3)
    assert_tree_equal(json.loads(json.dumps(infos)), infos)
    rng = np.random.default_rng(0)
    _, _, _, _, infos = env.step({a: rng.uniform(-1, 1, env.action_space(a).shape) for a in env.agents})
    assert_tree_equal(json.loads(json.dumps(infos)), infos)


@pytest.mark.parametrize("env_id", ENV_IDS)
@pytest.mark.parametrize("sensing", ["full", "ideal"])
def test_vector_infos_are_nested_with_string_keys_and_arrays(env_id, sensing):
    """make_vec's infos: string keys at every level, numpy arrays per copy (Gymnasium's VectorEnv convention)."""
    copies = 2
    vec = swarm_envs.make_vec(env_id, copies, **_settings(env_id, sensing))
    _, infos = vec.reset(seed=[3, 4])
    rng = np.random.default_rng(0)
    _, _, _, _, stepped = vec.step(rng.uniform(-1, 1, (copies, vec.n_agents, vec.layout.action_size)))
    for tree in (infos, stepped):
        _str_keys(tree)
        assert set(INFO_GROUPS) <= set(tree)
        assert all(np.shape(v) == (copies,) for v in tree["metrics"].values())
        assert tree["ground_truth"]["position"].shape == (copies, vec.n_agents, 2)
        json.dumps(tree, default=_array_as_list)


@pytest.mark.parametrize("env_id", ENV_IDS)
@pytest.mark.parametrize("sensing", ["ideal", "full"])
def test_infos_are_nested_groups_of_fixed_shape_plain_values(env_id, sensing):
    env = swarm_envs.make(env_id, **_settings(env_id, sensing))
    _, infos = env.reset(seed=5)

    def shapes(info: dict) -> dict:
        return {(group, name): np.shape(value) for group, values in info.items() for name, value in values.items()}

    first = shapes(infos["robot_0"])
    rng = np.random.default_rng(2)
    while env.agents:
        for info in infos.values():
            assert tuple(info) == INFO_GROUPS
            assert shapes(info) == first, "info names and shapes must not change"
            for group, values in info.items():
                for name, value in values.items():
                    assert isinstance(name, str) and _is_plain(value), f"{group}/{name} is {type(value).__name__}"
        _, _, _, _, infos = env.step({a: rng.uniform(-1, 1, env.action_space(a).shape) for a in env.agents})
    info = infos["robot_0"]
    assert set(info["ground_truth"]) == {"position", "heading", "velocity"}
    assert len(info["ground_truth"]["position"]) == 2 and len(info["ground_truth"]["velocity"]) == 2
    assert info["metrics"] and info["reward_terms"]
    assert bool(info["sensing"]) == (sensing == "full")
    # one dict per agent and group: changing one agent's info leaves the others' alone
    infos["robot_0"]["metrics"]["extra"] = 1.0
    assert "extra" not in infos["robot_1"]["metrics"]


def test_info_group_reads_the_nested_and_the_flat_form():
    env = swarm_envs.make("swarm_envs/Aggregation-v0", n_robots=3, sensing="full")
    _, infos = env.reset(seed=0)
    info = infos["robot_1"]
    for group in INFO_GROUPS:
        assert info_group(info, group) is info[group]
        assert info_group(flat_info(info), group) == info[group]
    with pytest.raises(KeyError, match="groups"):
        info_group(info, "metric")


def test_flat_infos_keys_every_value_by_group_and_name():
    env = swarm_envs.make("swarm_envs/Flocking-v0", n_robots=3, sensing="full", max_cycles=3)
    flat = FlatInfos(swarm_envs.make("swarm_envs/Flocking-v0", n_robots=3, sensing="full", max_cycles=3))
    assert flat.possible_agents == env.possible_agents and flat.unwrapped.n_agents == 3
    assert flat.observation_space("robot_0") == env.observation_space("robot_0")
    _, infos = env.reset(seed=1)
    _, flat_infos = flat.reset(seed=1)
    assert flat_infos == {a: flat_info(info) for a, info in infos.items()}
    assert flat_infos["robot_0"]["metrics", "polarisation"] == infos["robot_0"]["metrics"]["polarisation"]
    assert all(isinstance(k, tuple) and k[0] in INFO_GROUPS for k in flat_infos["robot_2"])
    np.testing.assert_array_equal(flat.state(), env.state())
    rng = np.random.default_rng(0)
    while env.agents:
        actions = {a: rng.uniform(-1, 1, env.action_space(a).shape) for a in env.agents}
        *_, infos = env.step(actions)
        *_, truncations, flat_infos = flat.step(actions)
        assert flat_infos == {a: flat_info(info) for a, info in infos.items()}
    assert all(truncations.values()) and not flat.agents
