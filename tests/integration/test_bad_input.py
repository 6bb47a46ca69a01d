"""Bad input fails loudly with a message naming the problem and the allowed values."""

import numpy as np
import pytest

import swarm_envs
from swarm_envs import aggregation_v0, centroid_seeking_v0, flocking_v0


@pytest.fixture
def env():
    e = aggregation_v0.parallel_env(n_robots=3, sensing="ideal")
    e.reset(seed=0)
    return e


def zeros(env):
    return {a: np.zeros(2, np.float32) for a in env.agents}


def test_wrong_action_shape(env):
    actions = zeros(env)
    actions["robot_0"] = np.zeros(3)
    with pytest.raises(ValueError, match=r"shape \(3,\); expected \(2,\)"):
        env.step(actions)


def test_non_numeric_action(env):
    actions = zeros(env)
    actions["robot_1"] = "forward"
    with pytest.raises(TypeError, match="numeric array"):
        env.step(actions)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_nan_inf_action(env, bad):
    actions = zeros(env)
    actions["robot_2"] = np.array([0.0, bad])
    with pytest.raises(ValueError, match="NaN or inf"):
        env.step(actions)


def test_unknown_and_missing_agents(env):
    actions = zeros(env)
    actions["robot_99"] = np.zeros(2)
    with pytest.raises(KeyError, match="robot_99"):
        env.step(actions)
    actions = zeros(env)
    del actions["robot_0"]
    with pytest.raises(KeyError, match="missing actions"):
        env.step(actions)
    with pytest.raises(TypeError, match="dict"):
        env.step([np.zeros(2)] * 3)
    with pytest.raises(KeyError, match="unknown agent"):
        env.action_space("robot_7")


def test_out_of_range_actions_are_clipped(env):
    start = env.world.positions.copy()
    big = {a: np.array([50.0, 0.0]) for a in env.agents}
    env.step(big)
    moved = np.linalg.norm(env.world.positions - start, axis=1)
    assert np.all(moved <= env.platform.max_speed * 0.1 + 1e-9)
    assert np.all(env.batched_observations()["proprio"][:, 8] == 1.0)  # clipped last action


def test_unknown_kwargs_and_names():
    with pytest.raises(TypeError, match=r"unknown keyword argument\(s\) \['n_robot'\]; allowed: .*n_robots"):
        aggregation_v0.parallel_env(n_robot=3)
    with pytest.raises(ValueError, match=r"unknown platform 'kilobot'; allowed values: \['droplet', 'epuck', 'rone'\]"):
        flocking_v0.parallel_env(platform="kilobot")
    with pytest.raises(ValueError, match="sensing='perfect' is not allowed"):
        flocking_v0.parallel_env(sensing="perfect")
    with pytest.raises(ValueError, match=r"n_robots must be an integer in \[1, 10000\]"):
        flocking_v0.parallel_env(n_robots=0)
    with pytest.raises(ValueError, match="arena_size"):
        flocking_v0.parallel_env(arena_size=-1.0)
    with pytest.raises(ValueError, match="n_anchors"):
        centroid_seeking_v0.parallel_env(n_anchors=2)
    with pytest.raises(ValueError, match="unknown environment id"):
        swarm_envs.make("swarm_envs/Dispersion-v0")
    with pytest.raises(ValueError, match="bitrate=300 is not allowed"):
        flocking_v0.parallel_env(bitrate=300)


def test_impossible_density_is_a_clear_error():
    # robots that cannot fit at all fail in the constructor (issue 9 item 5), not at reset
    with pytest.raises(ValueError, match="cannot place 200 robots"):
        aggregation_v0.parallel_env(n_robots=200, arena_size=0.5, sensing="ideal")


def test_reset_options_place_exactly_and_validate():
    env = aggregation_v0.parallel_env(n_robots=2, sensing="ideal", arena_size=1.0)
    pos = np.array([[0.1, 0.1], [-0.2, 0.15]])
    env.reset(seed=0, options={"positions": pos, "headings": np.array([0.3, -1.0])})
    np.testing.assert_allclose(env.world.positions, pos)
    np.testing.assert_allclose(env.world.headings, [0.3, -1.0])
    env.step({a: np.zeros(2) for a in env.agents})
    np.testing.assert_allclose(env.world.positions, pos, atol=1e-12)  # zero actions keep robots still
    with pytest.raises(ValueError, match="overlap"):
        env.reset(options={"positions": np.array([[0.0, 0.0], [0.01, 0.0]])})
    with pytest.raises(ValueError, match="outside"):
        env.reset(options={"positions": np.array([[0.0, 0.0], [5.0, 0.0]])})
    with pytest.raises(ValueError, match=r"shape \(2, 2\)"):
        env.reset(options={"positions": np.zeros((3, 2))})
    with pytest.warns(UserWarning, match="unknown reset option"):
        env.reset(options={"velocity": 1})


def test_step_after_end_raises():
    env = aggregation_v0.parallel_env(n_robots=2, sensing="ideal", max_cycles=1)
    env.reset(seed=0)
    env.step({a: np.zeros(2) for a in env.agents})
    assert env.agents == []
    with pytest.raises(RuntimeError, match="reset"):
        env.step({})
