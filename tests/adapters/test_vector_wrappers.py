"""Gymnasium's vector wrappers and SuperSuit's standard path on the suite: ``make_vec(..., agents_as_envs=True)``
(every robot of every copy one sub-env) and ``pettingzoo_env_to_vec_env_v1`` + ``concat_vec_envs_v1``."""

from __future__ import annotations

import numpy as np
import pytest
from gymnasium.wrappers.vector import ClipAction, NormalizeObservation, RecordEpisodeStatistics

import swarm_envs


def test_agents_as_envs_rows_are_the_copies_robots():
    kwargs = dict(n_robots=4, sensing="ideal", max_cycles=6, message_bits=1)
    rows = swarm_envs.make_vec("swarm_envs/Flocking-v0", 3, agents_as_envs=True, **kwargs)
    vec = swarm_envs.make_vec("swarm_envs/Flocking-v0", 3, **kwargs)
    assert rows.num_envs == 12 and rows.single_action_space.shape == (3,) and rows.action_space.shape == (12, 3)
    obs_rows, info_rows = rows.reset(seed=2)
    obs, infos = vec.reset(seed=2)
    actions = np.random.default_rng(0).uniform(-1, 1, (8, 3, 4, 3))
    for t in range(8):
        obs_rows, rew_rows, term_rows, trunc_rows, info_rows = rows.step(actions[t].reshape(12, 3))
        obs, rew, term, trunc, infos = vec.step(actions[t])
        for key in obs:
            np.testing.assert_array_equal(obs_rows[key], obs[key].reshape(12, *obs[key].shape[2:]))
        np.testing.assert_array_equal(rew_rows, rew.reshape(-1))
        np.testing.assert_array_equal(trunc_rows, trunc.reshape(-1))
        np.testing.assert_array_equal(info_rows["metrics"]["polarisation"], np.repeat(infos["metrics"]["polarisation"], 4))
        np.testing.assert_array_equal(info_rows["ground_truth"]["position"], infos["ground_truth"]["position"].reshape(12, 2))
    with pytest.raises(ValueError, match=r"actions must have shape \(num_envs, action_size\) = \(12, 3\)"):
        rows.step(np.zeros((3, 4, 3)))
    with pytest.raises(TypeError, match="agents_as_envs must be True or False"):
        swarm_envs.make_vec("swarm_envs/Flocking-v0", 2, agents_as_envs="yes")


def test_gymnasium_vector_wrappers_work_on_it():
    """RecordEpisodeStatistics records each robot's return and length; NormalizeObservation and ClipAction run."""
    vec = swarm_envs.make_vec("swarm_envs/Aggregation-v0", 2, agents_as_envs=True, flatten=True, n_robots=3,
                              sensing="ideal", max_cycles=5, reward_mode="local")
    env = NormalizeObservation(RecordEpisodeStatistics(ClipAction(vec)))
    obs, _ = env.reset(seed=0)
    assert obs.shape == (6, vec.single_observation_space.shape[0])
    returns = np.zeros(6)
    rng = np.random.default_rng(1)
    for _ in range(5):
        obs, rewards, _, truncations, infos = env.step(rng.uniform(-2, 2, (6, 2)))  # ClipAction clips to the box
        returns += rewards
        assert np.all(np.isfinite(obs))
    assert truncations.all() and infos["_episode"].all()
    np.testing.assert_allclose(infos["episode"]["r"], returns)
    np.testing.assert_array_equal(infos["episode"]["l"], 5)


def test_supersuit_standard_path_trains_sb3_ppo():
    """SuperSuit's pettingzoo_env_to_vec_env_v1 + concat_vec_envs_v1 with worker processes (num_cpus > 0,
    which pickles the env into each worker) trains SB3 PPO on a swarm env."""
    ss = pytest.importorskip("supersuit")
    pytest.importorskip("stable_baselines3")
    import torch
    from stable_baselines3 import PPO

    torch.set_num_threads(1)
    env = swarm_envs.make("swarm_envs/Aggregation-v0", n_robots=3, flatten=True, sensing="ideal", max_cycles=16)
    venv = ss.concat_vec_envs_v1(ss.pettingzoo_env_to_vec_env_v1(env), 2, num_cpus=2, base_class="stable_baselines3")
    try:
        assert venv.num_envs == 6
        torch.manual_seed(0)  # (PPO(seed=...) would call venv.seed, which SuperSuit's process vec env lacks)
        model = PPO("MlpPolicy", venv, n_steps=16, batch_size=48, n_epochs=1, device="cpu")
        before = [p.detach().clone() for p in model.policy.parameters()]
        model.learn(192)
        assert model.num_timesteps >= 192
        assert any(not torch.equal(a, b) for a, b in zip(before, model.policy.parameters()))
    finally:
        venv.close()
