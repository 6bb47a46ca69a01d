"""The SB3 VecEnv adapter: row <-> (copy, agent) ordering, auto-reset, per-robot rewards, PPO save/load."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from stable_baselines3 import PPO
from stable_baselines3.common.vec_env import VecCheckNan

from swarm_envs.agents.base import flatten_batch
from swarm_envs.agents.sb3_vec_env import SB3Policy, SwarmVecEnv
from swarm_envs import aggregation_v0, flocking_v0

N_ROBOTS = 4


def make_vec(n_copies=2, **kwargs) -> SwarmVecEnv:
    kw = {"sensing": "ideal", "n_robots": N_ROBOTS, "max_cycles": 6, **kwargs}
    return SwarmVecEnv(aggregation_v0.parallel_env, n_copies, kw)


def test_rows_match_copies_and_agents():
    """Row c * N + i is agent i of copy c: it equals a single env seeded like copy c (seed + first row)."""
    vec = make_vec(3)
    assert vec.num_envs == 3 * N_ROBOTS
    vec.seed(100)
    obs = vec.reset()
    assert obs.shape == (vec.num_envs,) + vec.observation_space.shape and obs.dtype == np.float32
    for c in range(3):
        env = aggregation_v0.parallel_env(sensing="ideal", n_robots=N_ROBOTS, max_cycles=6, flatten=True)
        single, _ = env.reset(seed=100 + c * N_ROBOTS)
        for agent in env.possible_agents:
            np.testing.assert_array_equal(obs[vec.row_of(c, agent)], single[agent])
            assert vec.observation_space.contains(obs[vec.row_of(c, agent)])
    # copies are seeded differently (seed + first row), so their observations differ
    assert not np.allclose(obs[vec.rows(0)], obs[vec.rows(1)])


def test_action_round_trip_through_proprio():
    """Row r's action comes back in the last-action part of row r's next observation."""
    vec = make_vec(2)
    vec.seed(0)
    vec.reset()
    actions = np.stack([np.linspace(-0.9, 0.9, vec.num_envs), -np.linspace(-0.8, 0.8, vec.num_envs)], axis=1)
    obs, _, _, _ = vec.step(actions.astype(np.float32))
    layout = vec.layout
    last_action = layout.unflatten(obs)["proprio"][:, -2:]
    np.testing.assert_allclose(last_action, actions, atol=1e-6)


def test_rewards_match_an_independent_env_per_row():
    """Local (per-robot) rewards land in the row of their robot: compare with standalone envs."""
    vec = make_vec(2, reward_mode="local")
    vec.seed(7)
    vec.reset()
    refs = []
    for c in range(2):
        ref = aggregation_v0.parallel_env(sensing="ideal", n_robots=N_ROBOTS, max_cycles=6, reward_mode="local", flatten=True)
        ref.reset(seed=7 + c * N_ROBOTS)
        refs.append(ref)
    rng = np.random.default_rng(1)
    for _ in range(3):
        actions = rng.uniform(-1, 1, (vec.num_envs, 2)).astype(np.float32)
        obs, rewards, dones, infos = vec.step(actions)
        for c, ref in enumerate(refs):
            ref_obs, ref_rew, *_ = ref.step({a: actions[vec.row_of(c, a)] for a in ref.possible_agents})
            for a in ref.possible_agents:
                row = vec.row_of(c, a)
                assert rewards[row] == pytest.approx(ref_rew[a], abs=1e-7)
                np.testing.assert_array_equal(obs[row], ref_obs[a])
                terms = vec.last_infos["reward_terms"]["own_distance_decrease"].reshape(-1)
                assert terms[row] == pytest.approx(ref_rew[a], abs=1e-7)
        assert np.ptp(rewards) > 0  # per-robot rewards really differ between rows


def test_auto_reset_terminal_observation_and_episode_stats():
    vec = make_vec(2, max_cycles=5)
    vec.seed(3)
    vec.reset()
    total = np.zeros(vec.num_envs)
    rng = np.random.default_rng(0)
    for t in range(5):
        actions = rng.uniform(-1, 1, (vec.num_envs, 2)).astype(np.float32)
        obs, rewards, dones, infos = vec.step(actions)
        total += rewards
        if t < 4:
            assert not dones.any() and "terminal_observation" not in infos[0]
    assert dones.all()
    layout = vec.layout
    for row in range(vec.num_envs):
        info = infos[row]
        assert info["TimeLimit.truncated"] is True
        assert info["episode"]["l"] == 5
        assert info["episode"]["r"] == pytest.approx(total[row], rel=1e-5, abs=1e-6)
        # the terminal observation still shows the last action; the returned one is a fresh episode's
        np.testing.assert_allclose(layout.unflatten(info["terminal_observation"])["proprio"][-2:], actions[row], atol=1e-6)
        assert np.all(layout.unflatten(obs[row])["proprio"][-2:] == 0)
    assert np.all(vec.last_infos["episode_step"] == 0)
    # the next episode runs and counts from zero again
    obs, rewards, dones, infos = vec.step(np.zeros((vec.num_envs, 2), np.float32))
    assert not dones.any() and np.all(vec.last_infos["episode_step"] == 1)


def test_sb3_checks_and_attributes():
    vec = VecCheckNan(make_vec(2, max_cycles=4), raise_exception=True)
    vec.seed(0)
    vec.reset()
    for _ in range(6):  # crosses an auto-reset
        vec.step(np.random.default_rng(0).uniform(-1, 1, (vec.num_envs, 2)).astype(np.float32))
    inner = vec.venv
    assert inner.get_attr("max_cycles") == [4] * inner.num_envs
    assert inner.get_attr("max_cycles", indices=[0, N_ROBOTS]) == [4, 4]
    assert inner.env_is_wrapped(object) == [False] * inner.num_envs
    with pytest.raises(AttributeError):
        inner.set_attr("max_cycles", 9, indices=[N_ROBOTS])


def test_flatten_batch_matches_env_flattening():
    env = flocking_v0.parallel_env(sensing="ideal", n_robots=5, flatten=True, message_bits=2)
    obs, _ = env.reset(seed=2)
    env.step({a: np.full(4, 0.3) for a in env.agents})
    obs = env._observations()
    parts = {k: v[env.agent_robots] for k, v in env.batched_observations().items()}
    np.testing.assert_array_equal(flatten_batch(env.layout, parts), np.stack([obs[a] for a in env.possible_agents]))


def test_short_ppo_run_save_reload_same_actions(tmp_path):
    torch.set_num_threads(1)
    vec = make_vec(2, max_cycles=20)
    vec.seed(0)
    model = PPO("MlpPolicy", vec, n_steps=64, batch_size=128, n_epochs=2, seed=0, device="cpu",
                policy_kwargs={"net_arch": [32, 32]})
    before = [p.detach().clone() for p in model.policy.parameters()]
    model.learn(2048)
    assert model.num_timesteps >= 2048
    assert any(not torch.equal(a, b) for a, b in zip(before, model.policy.parameters())), "training changed nothing"
    assert len(model.ep_info_buffer) > 0  # episode statistics reached SB3's logger buffer
    model.save(tmp_path / "m.zip")
    loaded = PPO.load(tmp_path / "m.zip", device="cpu")
    obs = vec.reset()
    a1, _ = model.predict(obs, deterministic=True)
    a2, _ = loaded.predict(obs, deterministic=True)
    np.testing.assert_array_equal(a1, a2)
    # and through the Policy wrapper on named observations
    parts = vec.layout.unflatten(obs[vec.rows(0)])
    # a batch of one copy's rows against the whole batch: float32 matrix products may round differently
    # with the batch size (blocking), so equal up to float32 rounding, not bit for bit
    np.testing.assert_allclose(
        SB3Policy(loaded, vec.platform, vec.layout).act_batch(parts), np.clip(a2[vec.rows(0)], -1, 1), rtol=1e-5, atol=1e-6
    )


def test_adapter_with_full_sensing():
    vec = SwarmVecEnv("swarm_envs/Aggregation-v0", 2, {"sensing": "full", "n_robots": 3, "max_cycles": 3})
    vec.seed(0)
    obs = vec.reset()
    assert obs.shape == (6,) + vec.observation_space.shape and np.all(np.isfinite(obs))
    for _ in range(3):
        obs, rewards, dones, infos = vec.step(np.zeros((6, 2), np.float32))
    assert dones.all() and all(np.all(np.isfinite(i["terminal_observation"])) for i in infos)


def test_worker_processes_give_the_same_rows():
    """Copies split over 2 worker processes equal one process bit for bit, across an episode end."""
    kw = {"sensing": "full", "n_robots": 3, "max_cycles": 4, "message_bits": 2}
    one = SwarmVecEnv("swarm_envs/Flocking-v0", 3, kw)
    two = SwarmVecEnv("swarm_envs/Flocking-v0", 3, kw, n_workers=2)
    try:
        one.seed(5)
        two.seed(5)
        np.testing.assert_array_equal(one.reset(), two.reset())
        rng = np.random.default_rng(0)
        for _ in range(7):  # crosses the auto-reset after 4 steps
            act = rng.uniform(-1, 1, (9, 4)).astype(np.float32)
            for a, b in zip(one.step(act)[:3], two.step(act)[:3]):
                np.testing.assert_array_equal(a, b)
            np.testing.assert_array_equal(one.last_infos["ground_truth"]["position"], two.last_infos["ground_truth"]["position"])
    finally:
        two.close()
    with pytest.raises(ValueError):
        SwarmVecEnv("swarm_envs/Flocking-v0", 2, kw, n_workers=3)
