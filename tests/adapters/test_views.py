"""The env views share their checks and infos (swarm_envs.adapters.views): the same messages and the same numbers."""

from __future__ import annotations

import numpy as np
import pytest

import swarm_envs

ID = "swarm_envs/Flocking-v0"


def test_vector_nan_action_names_the_agent_and_copy():
    vec = swarm_envs.make_vec(ID, 2, n_robots=3, sensing="ideal")
    vec.reset(seed=0)
    actions = np.zeros((2, 3, 2))
    actions[1, 2, 0] = np.nan
    with pytest.raises(ValueError, match=r"action for robot_2 of copy 1 contains NaN or inf"):
        vec.step(actions)
    with pytest.raises(TypeError, match="real-valued numeric array"):
        vec.step(np.zeros((2, 3, 2), dtype=bool))
    with pytest.raises(ValueError, match=r"actions has shape \(2, 3, 3\); expected \(num_envs, n_agents, action_size\)"):
        vec.step(np.zeros((2, 3, 3)))


def test_env_and_vector_infos_agree():
    env = swarm_envs.make(ID, n_robots=3)
    vec = swarm_envs.make_vec(ID, 1, n_robots=3)
    _, infos = env.reset(seed=5)
    _, vinfos = vec.reset(seed=5)
    actions = np.full((1, 3, 2), 0.5)
    for _ in range(3):
        *_, infos = env.step({a: actions[0, i] for i, a in enumerate(env.agents)})
        *_, vinfos = vec.step(actions)
    for i, agent in enumerate(env.possible_agents):
        info = infos[agent]
        assert info["ground_truth"]["position"] == tuple(vinfos["ground_truth"]["position"][0, i])
        assert info["ground_truth"]["heading"] == vinfos["ground_truth"]["heading"][0, i]
        assert info["reward_terms"] == {k: v[0, i] for k, v in vinfos["reward_terms"].items()}
        assert info["metrics"] == {k: v[0] for k, v in vinfos["metrics"].items()}
        assert info["sensing"] == {k: v[0, i] for k, v in vinfos["sensing"].items()} and info["sensing"]
