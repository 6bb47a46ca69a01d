"""[T20] Fig. 21 with moving robots (swarm_envs.validate.swarmcom_moving): the lit-robot count reads the
listeners' own decoded frames through the env; a tiny parked scene checks who counts."""

import numpy as np
import pytest

import swarm_envs
from swarm_envs.agents.scripted import RandomWalk
from swarm_envs.validate.swarmcom_moving import (
    CentreBroadcast,
    centre_heard,
    count_lit,
    moving_channels,
)


class _ThirdDeaf(CentreBroadcast):
    """The Fig. 21 set-up with world robot 3's detectors switched off as well."""

    def receive_off(self, num_cycles):
        mask = super().receive_off(num_cycles)
        mask[:, 3] = True
        return mask


def _parked_env(task):
    """Centre at the origin of a 3 m arena; listener 1 facing it 10 cm away, listener 2 facing it 1.3 m away
    (beyond the e-puck's 1 m IR range), listener 3 facing it 10 cm away on the other side."""
    env = swarm_envs.make_vec(task, 1, n_robots=3, arena_size=3.0, message_bits=8, observe_ids=True,
                              relative_threshold=10, exchange="ideal", max_cycles=200)
    pos = np.array([[0.0, 0.0], [0.10, 0.0], [1.30, 0.0], [-0.10, 0.0]])
    head = np.array([0.0, np.pi, np.pi, 0.0])
    obs, _ = env.reset(seed=3, options={"positions": pos, "headings": head})
    return env, obs


def test_parked_listener_next_to_the_centre_counts_far_or_deaf_ones_do_not():
    env, obs = _parked_env(_ThirdDeaf)
    lit = count_lit(env, None, n_counts=3, period_s=1.0, windows_s=(0.3, 1.0), observations=obs)
    # robot 1 hears the centre; robot 2 is out of range, robot 3's detectors are off: one lit robot per count
    np.testing.assert_array_equal(lit[1.0], [[1, 1, 1]])
    np.testing.assert_array_equal(lit[0.3], [[1, 1, 1]])
    env.close()


def test_centre_heard_reads_the_decoded_sender_id():
    env, obs = _parked_env(CentreBroadcast)
    heard = np.zeros(3, dtype=int)
    for _ in range(20):
        obs, *_ = env.step(np.zeros((1, 3, env.layout.action_size), np.float32))
        heard += centre_heard(obs, n_world=4)[0]
        # a row naming another robot (id 2) is not the centre
        assert not centre_heard(obs, n_world=4, centre=2).any()
    assert heard[0] >= 8 and heard[2] >= 8  # a frame every 0.2 s at 10 cm
    assert heard[1] == 0
    env.close()


def test_moving_count_is_bounded():
    res = moving_channels(6, 10, [0, 1], n_counts=2, period_s=3.0, windows_s=(1.0,))
    lit = res["lit"][1.0]
    assert res["centre_drift_m"].shape == (2,) and (res["centre_drift_m"] < 0.36).all()
    assert lit.shape == (2, 2)
    assert (lit >= 0).all() and (lit <= 5).all() and lit.sum() > 0


def test_the_random_walk_moves_the_listeners_and_not_the_centre():
    env = swarm_envs.make_vec(CentreBroadcast, 1, n_robots=5, message_bits=8, observe_ids=True, exchange="ideal", max_cycles=100)
    obs, _ = env.reset(seed=2)
    start = env.core.positions.copy()
    count_lit(env, RandomWalk(env.platform, env.layout, np.random.default_rng(0)), n_counts=1, period_s=5.0, observations=obs)
    moved = np.linalg.norm(env.core.positions - start, axis=1)
    assert moved[0] == 0.0 and (moved[1:] > 0.01).all()
    env.close()


def test_an_episode_ending_during_the_count_is_an_error():
    env = swarm_envs.make_vec(CentreBroadcast, 1, n_robots=3, message_bits=8, observe_ids=True, exchange="ideal", max_cycles=5)
    obs, _ = env.reset(seed=0)
    with pytest.raises(RuntimeError, match="max_cycles"):
        count_lit(env, None, n_counts=1, period_s=1.0, observations=obs)
    env.close()
