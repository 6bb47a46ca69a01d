"""Global state for centralised critics and the PettingZoo space dicts."""

import numpy as np
import pytest

import swarm_envs
from swarm_envs.adapters.env import STATE_ROBOT_FIELDS

N_FIELDS = len(STATE_ROBOT_FIELDS)


def make(env_id: str, **kwargs):
    return swarm_envs.make(env_id, **{"n_robots": 4, "sensing": "ideal", "max_cycles": 20, **kwargs})


def random_actions(env, rng):
    return {a: rng.uniform(-1, 1, env.action_space(a).shape).astype(np.float32) for a in env.agents}


@pytest.mark.parametrize("env_id", swarm_envs.list_envs())
def test_space_dicts_match_the_space_methods(env_id):
    env = make(env_id)
    assert list(env.observation_spaces) == env.possible_agents == list(env.action_spaces)
    for agent in env.possible_agents:
        assert env.observation_spaces[agent] == env.observation_space(agent)
        assert env.action_spaces[agent] == env.action_space(agent)
    obs, _ = env.reset(seed=0)
    assert all(env.observation_spaces[a].contains(o) for a, o in obs.items())


@pytest.mark.parametrize("env_id", swarm_envs.list_envs())
def test_state_shape_and_inside_its_space_over_an_episode(env_id):
    env = make(env_id)
    with pytest.raises(RuntimeError, match="reset"):
        env.state()
    env.reset(seed=1)
    n_markers = len(env._markers())
    assert n_markers >= 1  # every task has at least the centroid
    assert env.state_space.shape == (N_FIELDS * env.n_world + 2 * n_markers + 1,)
    rng = np.random.default_rng(0)
    while env.agents:
        state = env.state()
        assert state.dtype == np.float32 and state.shape == env.state_space.shape
        assert env.state_space.contains(state), "state outside state_space"
        env.step(random_actions(env, rng))
    assert env.state()[-1] == pytest.approx(1.0)  # progress at the last step


@pytest.mark.parametrize("env_id", swarm_envs.list_envs())
def test_state_equals_ground_truth(env_id):
    env = make(env_id)
    _, infos = env.reset(seed=2)
    rng = np.random.default_rng(1)
    for _ in range(3):
        _, _, _, _, infos = env.step(random_actions(env, rng))
    state = env.state().astype(float)
    w = env.world
    robots = state[: N_FIELDS * env.n_world].reshape(env.n_world, N_FIELDS)
    np.testing.assert_allclose(robots[:, 0:2], w.positions, atol=1e-6)
    np.testing.assert_allclose(robots[:, 2], np.cos(w.headings), atol=1e-6)
    np.testing.assert_allclose(robots[:, 3], np.sin(w.headings), atol=1e-6)
    np.testing.assert_allclose(robots[:, 4:6], w.velocities, atol=1e-5)
    np.testing.assert_allclose(robots[:, 6], w.angular_velocities, atol=1e-5)
    # the agents' rows agree with what infos report as ground truth
    for i, agent in enumerate(env.possible_agents):
        row = robots[env.agent_robots[i]]
        np.testing.assert_allclose(row[0:2], infos[agent]["ground_truth"]["position"], atol=1e-6)
        np.testing.assert_allclose(row[4:6], infos[agent]["ground_truth"]["velocity"], atol=1e-5)
        heading = infos[agent]["ground_truth"]["heading"]
        np.testing.assert_allclose(row[2:4], [np.cos(heading), np.sin(heading)], atol=1e-6)
    # marker: every task's centroid marker
    markers = state[N_FIELDS * env.n_world : -1].reshape(-1, 2)
    names = sorted(env._markers())
    centroid = markers[names.index("centroid")]
    if env_id == "swarm_envs/CentroidSeeking-v0":  # the static anchors' centroid, and the anchors are in the state
        assert env.n_static == 4
        np.testing.assert_allclose(centroid, w.positions[: env.n_static].mean(axis=0), atol=1e-6)
    else:
        np.testing.assert_allclose(centroid, w.positions[env.agent_robots].mean(axis=0), atol=1e-6)
    assert state[-1] == pytest.approx(3 / env.max_cycles)


def test_state_changes_with_motion_only():
    env = make("swarm_envs/Flocking-v0", max_cycles=50)
    env.reset(seed=3)
    still = {a: np.zeros(2, np.float32) for a in env.agents}
    env.step(still)
    s1 = env.state()
    env.step(still)
    s2 = env.state()
    np.testing.assert_array_equal(s1[:-1], s2[:-1])  # nothing moved: only the progress differs
    assert s2[-1] > s1[-1]
    env.step({a: np.array([1.0, 0.0], np.float32) for a in env.agents})
    s3 = env.state()
    moved = np.abs(s3 - s2)[: N_FIELDS * env.n_world].reshape(env.n_world, N_FIELDS)
    assert np.all(moved[:, 0:2].max(axis=1) > 0), "every driven robot's position must change"
    assert np.all(np.abs(s3[: N_FIELDS * env.n_world].reshape(env.n_world, N_FIELDS)[:, 4:6]).max(axis=1) > 0)


def test_state_is_not_in_the_observations():
    env = make("swarm_envs/Aggregation-v0")
    obs, _ = env.reset(seed=4)
    state = env.state()
    positions = state[: N_FIELDS * env.n_world].reshape(env.n_world, N_FIELDS)[:, 0:2]
    for o in obs.values():
        assert set(o) == {"range_bearing", "messages", "scale_free", "rigid", "proprio"}
        flat = np.concatenate([np.ravel(v) for v in o.values()])
        # no absolute (arena-frame) coordinate of any robot appears in an observation
        assert not np.any(np.isin(np.round(positions.ravel(), 6), np.round(flat, 6)[np.abs(flat) > 1e-3]))
