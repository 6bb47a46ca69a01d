"""Seeding: same seed -> identical trajectories (100 steps of every env in the default run, 300 in the slow
run); different seeds differ."""

import numpy as np
import pytest

import swarm_envs
from tests.conftest import assert_tree_equal

SENSING = ["ideal", "full"]


def rollout(env_id: str, seed: int, sensing: str, steps: int = 300, **kwargs):
    env = swarm_envs.make(env_id, n_robots=6, sensing=sensing, max_cycles=steps, **kwargs)
    obs, infos = env.reset(seed=seed)
    action_rng = np.random.default_rng(seed + 1000)
    record = [(obs, infos)]
    for _ in range(steps):
        actions = {a: action_rng.uniform(-1, 1, env.action_space(a).shape).astype(np.float32) for a in env.agents}
        record.append(env.step(actions))
    return record


@pytest.mark.parametrize("steps", [100, pytest.param(300, marks=pytest.mark.slow)])
@pytest.mark.parametrize("env_id", swarm_envs.list_envs())
@pytest.mark.parametrize("sensing", SENSING)
def test_same_seed_same_trajectory(env_id, sensing, steps):
    a = rollout(env_id, 7, sensing, steps)
    b = rollout(env_id, 7, sensing, steps)
    assert_tree_equal(a, b)


@pytest.mark.parametrize("sensing", SENSING)
def test_different_seed_differs(sensing):
    a = rollout("swarm_envs/Flocking-v0", 1, sensing, steps=20)
    b = rollout("swarm_envs/Flocking-v0", 2, sensing, steps=20)
    with pytest.raises(AssertionError):
        assert_tree_equal(a, b)


def test_reset_without_seed_continues_the_stream():
    env = swarm_envs.make("swarm_envs/Aggregation-v0", n_robots=5, sensing="ideal")
    env.reset(seed=3)
    first = env.world.positions.copy()
    env.reset()
    assert not np.array_equal(first, env.world.positions)
    env.reset(seed=3)
    np.testing.assert_array_equal(first, env.world.positions)
