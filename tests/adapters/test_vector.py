"""The vector API (swarm_envs.make_vec) over the batched core: copy independence, autoreset, shapes, bad input."""

from __future__ import annotations

import numpy as np
import pytest

import swarm_envs

STEPS = 300
PLATFORMS = ["epuck", "droplet", "rone"]


def _actions(rng: np.random.Generator, shape: tuple[int, ...]) -> np.ndarray:
    return rng.uniform(-1, 1, shape)


def _single_rollout(env_id: str, seed: int, actions: np.ndarray, **kwargs):
    env = swarm_envs.make(env_id, **kwargs)
    obs, infos = env.reset(seed=seed)
    agents = list(env.possible_agents)
    out = [(obs, None, infos)]
    for t in range(actions.shape[0]):
        obs, rew, term, trunc, infos = env.step({a: actions[t, i] for i, a in enumerate(agents)})
        out.append((obs, rew, infos))
        if not env.agents:
            break
    return agents, out


def _assert_copy_equals_single(vec_obs, vec_rew, vec_infos, b, agents, single, flatten):
    obs, rew, infos = single
    for i, a in enumerate(agents):
        if flatten:
            np.testing.assert_array_equal(vec_obs[b, i], obs[a])
        else:
            for k, v in obs[a].items():
                np.testing.assert_array_equal(vec_obs[k][b, i], v, err_msg=f"{k} of {a}")
        if rew is not None:
            assert vec_rew[b, i] == np.float32(rew[a])
        gt = infos[a]["ground_truth"]
        np.testing.assert_array_equal(vec_infos["ground_truth"]["position"][b, i], gt["position"])
        assert vec_infos["ground_truth"]["heading"][b, i] == gt["heading"]
        for k, v in infos[a]["metrics"].items():
            np.testing.assert_array_equal(vec_infos["metrics"][k][b], v, err_msg=k)
        for k, v in infos[a]["reward_terms"].items():
            assert vec_infos["reward_terms"][k][b, i] == v, k


def _check_copies_equal_singles(env_id, sensing, platform, steps):
    seeds = [11, 4, 27]
    kwargs = dict(sensing=sensing, platform=platform, max_cycles=steps, n_robots=6 if "Centroid" not in env_id else 2, message_bits=3)
    vec = swarm_envs.make_vec(env_id, len(seeds), **kwargs)
    rng = np.random.default_rng(0)
    actions = _actions(rng, (steps, len(seeds), vec.n_agents, vec.layout.action_size))
    singles = [_single_rollout(env_id, s, actions[:, b], **kwargs) for b, s in enumerate(seeds)]
    obs, infos = vec.reset(seed=seeds)
    for b in range(len(seeds)):
        agents, traj = singles[b]
        _assert_copy_equals_single(obs, None, infos, b, agents, traj[0], False)
    for t in range(steps):
        obs, rew, term, trunc, infos = vec.step(actions[t])
        for b in range(len(seeds)):
            agents, traj = singles[b]
            _assert_copy_equals_single(obs, rew, infos, b, agents, traj[t + 1], False)
    assert trunc.all()


@pytest.mark.parametrize("sensing", [pytest.param("ideal", marks=pytest.mark.slow), "full"])
@pytest.mark.parametrize("env_id", swarm_envs.list_envs())
def test_each_copy_equals_a_single_env_bit_for_bit(env_id, sensing):
    """Copy b of a 3-copy vector env reset with seed s_b equals a single env reset with s_b, 300 steps
    (ideal sensing with `-m slow`; it is also a case of the slow every-task-platform-and-mode test)."""
    _check_copies_equal_singles(env_id, sensing, "epuck", STEPS)


@pytest.mark.parametrize("platform", ["droplet", "rone"])
def test_copies_equal_single_envs_on_other_platforms(platform):
    _check_copies_equal_singles("swarm_envs/Flocking-v0", "full", platform, 100)


@pytest.mark.slow
@pytest.mark.parametrize("platform", PLATFORMS)
@pytest.mark.parametrize("sensing", ["ideal", "full"])
@pytest.mark.parametrize("env_id", swarm_envs.list_envs())
def test_copies_equal_single_envs_every_task_platform_and_mode(env_id, sensing, platform):
    _check_copies_equal_singles(env_id, sensing, platform, STEPS)


def test_flattened_observation_matches_single_env():
    kwargs = dict(sensing="ideal", n_robots=5, flatten=True)
    vec = swarm_envs.make_vec("swarm_envs/Aggregation-v0", 2, **kwargs)
    obs, infos = vec.reset(seed=[3, 8])
    assert obs.shape == (2, 5, vec.agent_observation_space.shape[0]) and obs.dtype == np.float32
    env = swarm_envs.make("swarm_envs/Aggregation-v0", **kwargs)
    single, _ = env.reset(seed=8)
    np.testing.assert_array_equal(obs[1], np.stack([single[a] for a in env.possible_agents]))


@pytest.mark.parametrize("sensing", ["ideal", "full"])
def test_autoreset_next_step_restarts_like_a_single_env(sensing):
    """Both copies end after 5 steps and restart on the next step (zero reward, not done); the restarted
    copy equals a single env whose generator continued after its first episode."""
    kwargs = dict(sensing=sensing, n_robots=4, max_cycles=5, message_bits=2)
    vec = swarm_envs.make_vec("swarm_envs/Flocking-v0", 2, **kwargs)
    rng = np.random.default_rng(1)
    actions = rng.uniform(-1, 1, (12, 2, 4, 4))
    obs, _ = vec.reset(seed=[5, 6])
    positions = []
    for t in range(12):
        obs, rew, term, trunc, infos = vec.step(actions[t])
        positions.append(infos["ground_truth"]["position"].copy())
        if t == 4:
            assert trunc.all()  # both end at step 5
        if t == 5:  # next-step autoreset: zero reward, not done, episode_step 0
            assert not trunc.any() and np.all(rew == 0) and np.all(infos["episode_step"] == 0)
    # the restarted copy 0 equals a fresh single env whose generator continued after its first episode
    env = swarm_envs.make("swarm_envs/Flocking-v0", **kwargs)
    env.reset(seed=5)
    for t in range(5):
        env.step({a: actions[t, 0, i] for i, a in enumerate(env.possible_agents)})
    _, infos = env.reset()
    np.testing.assert_array_equal(positions[5][0], np.stack([infos[a]["ground_truth"]["position"] for a in env.possible_agents]))
    for t in range(6, 11):  # the second episode: 5 steps, then copy 0 restarts again at t = 11
        _, _, _, _, infos = env.step({a: actions[t, 0, i] for i, a in enumerate(env.possible_agents)})
        np.testing.assert_array_equal(positions[t][0], np.stack([infos[a]["ground_truth"]["position"] for a in env.possible_agents]))


@pytest.mark.parametrize("sensing", ["ideal", "full"])
def test_restarting_one_copy_leaves_the_others_unchanged(sensing):
    """Copy 0 restarts mid-way (it alone reached its step limit); copy 1 must not notice: its
    observations equal those of a run in which copy 0 never restarts."""
    rng = np.random.default_rng(2)
    actions = rng.uniform(-1, 1, (30, 2, 4, 4))

    def run(limit_copy0):
        vec = swarm_envs.make_vec("swarm_envs/Aggregation-v0", 2, sensing=sensing, n_robots=4, max_cycles=100, message_bits=2)
        vec.reset(seed=[1, 2])
        out = []
        for t in range(30):
            if t == limit_copy0:
                vec.batch._needs_reset[0] = True  # as if copy 0's episode had ended: it restarts on this step
            obs, _, _, _, infos = vec.step(actions[t])
            out.append((obs["range_bearing"][1].copy(), obs["messages"][1].copy(), obs["scale_free"][1].copy(), infos["ground_truth"]["position"][1].copy()))
        return out

    restarted, plain = run(10), run(-1)
    for a, b in zip(restarted, plain):
        for x, y in zip(a, b):
            np.testing.assert_array_equal(x, y)


def test_shapes_dtypes_and_spaces():
    vec = swarm_envs.make_vec("swarm_envs/CentroidSeeking-v0", 3, sensing="ideal", n_robots=2, message_bits=2)
    obs, infos = vec.reset(seed=0)
    assert vec.action_space.shape == (3, 2, 4)
    for k, space in vec.observation_space.spaces.items():
        assert obs[k].shape == space.shape and obs[k].dtype == np.float32
        for b in range(3):
            for i in range(2):
                assert vec.agent_observation_space[k].contains(obs[k][b, i]), k
    obs, rew, term, trunc, infos = vec.step(vec.action_space.sample())
    assert rew.shape == term.shape == trunc.shape == (3, 2)
    assert infos["metrics"]["mean_distance_to_centroid"].shape == (3,)
    assert infos["ground_truth"]["position"].shape == (3, 2, 2)
    assert infos["reward_terms"]["distance_to_centroid"].shape == (3, 2)


@pytest.mark.parametrize(
    "bad, error",
    [
        (np.zeros((2, 3, 2)), ValueError),  # wrong copy count
        (np.zeros((3, 3)), ValueError),  # missing action axis
        (np.full((3, 3, 2), np.nan), ValueError),
        (np.full((3, 3, 2), np.inf), ValueError),
        (np.zeros((3, 3, 2), dtype=complex), TypeError),
        (np.full((3, 3, 2), "1"), TypeError),
    ],
)
def test_bad_actions_raise_before_any_state_changes(bad, error):
    vec = swarm_envs.make_vec("swarm_envs/Flocking-v0", 3, sensing="ideal", n_robots=3)
    vec.reset(seed=0)
    before = vec.core.positions.copy()
    cycles = vec.core.num_cycles.copy()
    with pytest.raises(error):
        vec.step(bad)
    np.testing.assert_array_equal(vec.core.positions, before)
    np.testing.assert_array_equal(vec.core.num_cycles, cycles)
    vec.step(np.zeros((3, 3, 2)))  # still usable


def test_bad_arguments():
    with pytest.raises(ValueError):
        swarm_envs.make_vec("swarm_envs/Nope-v0", 2)
    with pytest.raises(ValueError):
        swarm_envs.make_vec("swarm_envs/Flocking-v0", 0)
    with pytest.raises(TypeError):
        swarm_envs.make_vec("swarm_envs/Flocking-v0", 2, not_a_setting=1)
    vec = swarm_envs.make_vec("swarm_envs/Flocking-v0", 2, sensing="ideal", n_robots=2)
    with pytest.raises(ValueError):
        vec.reset(seed=[1])
    with pytest.raises(RuntimeError):
        swarm_envs.make_vec("swarm_envs/Flocking-v0", 2, sensing="ideal", n_robots=2).step(np.zeros((2, 2, 2)))
