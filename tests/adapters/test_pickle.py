"""Envs can be copied (``pickle``, ``copy.deepcopy``) before a reset and mid-episode, and the copy continues bit
for bit like the original under the same actions: the ParallelEnv and make_vec, every task, every platform."""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest

import swarm_envs
from swarm_envs.sim import world as world_module
from tests.conftest import assert_tree_equal

TASKS = [i for i in swarm_envs.list_envs() if i.startswith("swarm_envs/")]  # every task of the suite
DENSE = {"epuck": 0.45, "droplet": 0.3, "rone": 0.7}  # small arenas: robots collide, so contacts are copied too


def _kwargs(env_id: str, platform: str, sensing: str) -> dict:
    n = 2 if "Centroid" in env_id else 8
    kw = dict(platform=platform, sensing=sensing, n_robots=n, message_bits=2, max_cycles=200)
    if "Centroid" not in env_id and "MidAngle" not in env_id:  # MidAngleNavigation: its seekers crowd the start square
        kw["arena_size"] = DENSE[platform]
    return kw


def _step_all(envs, actions):
    return [env.step(actions) for env in envs]


def _assert_same_step(a, b):
    obs_a, rew_a, term_a, trunc_a, info_a = a
    obs_b, rew_b, term_b, trunc_b, info_b = b
    assert rew_a == rew_b and term_a == term_b and trunc_a == trunc_b
    for agent in obs_a:
        for key in obs_a[agent]:
            np.testing.assert_array_equal(obs_a[agent][key], obs_b[agent][key], err_msg=f"{agent} {key}")
        assert_tree_equal(info_a[agent], info_b[agent], agent)


@pytest.mark.parametrize(
    "env_id, platform, sensing",
    [(t, "epuck", "full") for t in TASKS] + [("swarm_envs/Flocking-v0", p, "full") for p in ("droplet", "rone")]
    + [("swarm_envs/Aggregation-v0", "epuck", "ideal")],
)
def test_parallel_env_copies_continue_bit_for_bit(env_id, platform, sensing):
    env = swarm_envs.make(env_id, **_kwargs(env_id, platform, sensing))
    fresh = pickle.loads(pickle.dumps(env))  # before any reset
    obs, _ = env.reset(seed=5)
    fresh_obs, _ = fresh.reset(seed=5)
    for agent in obs:
        for key in obs[agent]:
            np.testing.assert_array_equal(obs[agent][key], fresh_obs[agent][key])
    rng = np.random.default_rng(1)
    size = env.layout.action_size
    actions = [{a: rng.uniform(-1, 1, size) for a in env.possible_agents} for _ in range(60)]
    for a in actions[:30]:
        _assert_same_step(*_step_all([env, fresh], a))  # a copy made before the reset runs the same episode
    assert env.world.bumps.any() or platform == "droplet" or "Centroid" in env_id  # contacts happened
    copies = [pickle.loads(pickle.dumps(env)), copy.deepcopy(env)]
    for a in actions[30:]:
        original, *copied = _step_all([env, *copies], a)
        for step in copied:
            _assert_same_step(original, step)
    np.testing.assert_array_equal(env.state(), copies[0].state())


def test_copy_of_a_rendered_env_draws_again():
    env = swarm_envs.make("swarm_envs/Flocking-v0", n_robots=4, sensing="ideal", render_mode="rgb_array")
    env.reset(seed=0)
    frame = env.render()
    twin = copy.deepcopy(env)
    assert twin._renderer is None and np.array_equal(twin.render(), frame)


@pytest.mark.parametrize("sensing", ["full", "ideal"])
def test_make_vec_copies_continue_bit_for_bit_through_autoreset(sensing):
    vec = swarm_envs.make_vec("swarm_envs/Flocking-v0", 3, n_robots=5, sensing=sensing, max_cycles=25, arena_size=0.4)
    twin = pickle.loads(pickle.dumps(vec))  # before reset
    rng = np.random.default_rng(2)
    actions = rng.uniform(-1, 1, (70, 3, 5, 2))
    for v in (vec, twin):
        v.reset(seed=[4, 9, 1])
    for t in range(20):
        a, b = vec.step(actions[t]), twin.step(actions[t])
        np.testing.assert_array_equal(a[0]["range_bearing"], b[0]["range_bearing"])
    copies = [pickle.loads(pickle.dumps(vec)), copy.deepcopy(vec)]
    for t in range(20, 70):  # through two automatic resets
        out = vec.step(actions[t])
        for c in copies:
            other = c.step(actions[t])
            for key in out[0]:
                np.testing.assert_array_equal(out[0][key], other[0][key], err_msg=key)
            np.testing.assert_array_equal(out[1], other[1])
            np.testing.assert_array_equal(out[4]["ground_truth"]["position"], other[4]["ground_truth"]["position"])


def test_a_copy_of_an_episode_beyond_the_log_bound_warns(monkeypatch):
    """Past its bound the command log is dropped: the copy is pymunk's copy of the space, with a warning."""
    monkeypatch.setattr(world_module, "COPY_LOG_BYTES", 16 * 4 * 10)  # 10 steps of 4 robots
    env = swarm_envs.make("swarm_envs/Aggregation-v0", n_robots=4, sensing="ideal")
    env.reset(seed=0)
    for _ in range(12):
        env.step({a: np.full(2, 0.5) for a in env.agents})
    with pytest.warns(RuntimeWarning, match="episode log exceeded"):
        twin = copy.deepcopy(env)
    np.testing.assert_array_equal(twin.world.positions, env.world.positions)
    twin.step({a: np.full(2, 0.5) for a in env.agents})  # it steps on
