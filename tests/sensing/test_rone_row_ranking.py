"""r-one observation rows are ranked by what the robot measures (age of the last decoded frame), never by
the decoded id (swarm_envs.sensing.observation.ranked_slots)."""

import numpy as np
import pytest

import swarm_envs
from swarm_envs.sensing.observation import ranked_slots
from swarm_envs.sensing.full import BEACON_PERIOD

N = 10  # observer robot 0 at the centre, nine neighbours on a ring (one more than K = 8)
_ANGLES = np.deg2rad(np.arange(9) * 40.0)
_LAYOUT = np.vstack([[0.0, 0.0], np.c_[0.35 * np.cos(_ANGLES), 0.35 * np.sin(_ANGLES)]])
STEPS = 2 * BEACON_PERIOD + 1  # two complete beacon rounds


def _episodes(ring_of_robot: np.ndarray, seeds: range):
    """The observer's last observation and the env after STEPS still steps, per seed; robot 1 + i sits at
    ring position ``ring_of_robot[i]`` (the same positions, ids assigned differently)."""
    env = swarm_envs.make("swarm_envs/Aggregation-v0", n_robots=N, platform="rone", sensing="full", arena_size=2.0)
    pos = _LAYOUT.copy()
    pos[1:] = _LAYOUT[1:][ring_of_robot]
    for seed in seeds:
        obs, _ = env.reset(seed=seed, options={"positions": pos, "headings": np.zeros(N)})
        for _ in range(STEPS):
            obs, *_ = env.step({a: np.zeros(2, np.float32) for a in env.agents})
        yield obs["robot_0"], env


@pytest.mark.slow  # 80 episodes (statistical); run by .ci/run's slow step
def test_row_positions_carry_no_id_information():
    """Shuffling which robot carries which id (same positions) leaves each row slot's bearing statistics
    unchanged within sampling error (observe_ids=False). Ranked by id, slot 0 would always hold the lowest
    id's bearing: 0 degrees with ids in ring order, 320 degrees with them reversed."""
    seeds = range(40)
    a = np.array([o["range_bearing"] for o, _ in _episodes(np.arange(9), seeds)])
    b = np.array([o["range_bearing"] for o, _ in _episodes(np.arange(9)[::-1].copy(), seeds)])
    assert a[:, :6, 0].min() == 1.0 and b[:, :6, 0].min() == 1.0  # slots 0-5 always filled
    for col in (2, 3):  # cos, sin bearing
        mean_a, mean_b = a[:, :6, col].mean(0), b[:, :6, col].mean(0)
        se = np.sqrt(a[:, :6, col].var(0, ddof=1) / len(a) + b[:, :6, col].var(0, ddof=1) / len(b))
        z = np.abs(mean_a - mean_b) / np.maximum(se, 1e-12)
        assert np.all(z < 4.0), (col, mean_a, mean_b, z)


def test_more_than_k_neighbours_keeps_the_most_recently_heard():
    """With nine neighbours and K = 8, the kept readings are the eight youngest; the one dropped is never
    younger than a kept one, and over seeds the dropped one is not always the highest id."""
    dropped_ids = set()
    for obs, env in _episodes(np.arange(9), range(12)):
        nb = env.core.frame.neighbours
        mine = np.flatnonzero(nb.rx == 0)
        kept = nb.slots[0][nb.slots[0] >= 0]
        np.testing.assert_array_equal(obs["range_bearing"][: len(kept), 6], nb.age[kept].astype(np.float32))
        assert np.all(np.diff(nb.age[kept]) >= 0)  # most recently heard first
        rest = np.setdiff1d(mine, kept)
        if len(rest):
            assert len(kept) == 8
            assert nb.age[rest].min() >= nb.age[kept].max()
            dropped_ids.update(int(t) for t in nb.tx[rest])
    assert dropped_ids and dropped_ids != {9}, dropped_ids


def test_ranked_slots_orders_by_key_then_tie():
    row = np.array([0, 0, 0, 0, 1, 1])
    key = np.array([2.0, 1.0, 1.0, np.nan, 5.0, 5.0])
    tie = np.array([0.1, 0.9, 0.2, 0.0, 0.7, 0.3])
    np.testing.assert_array_equal(ranked_slots(3, row, key, tie, 3), [[2, 1, 0], [5, 4, -1], [-1, -1, -1]])
    np.testing.assert_array_equal(ranked_slots(2, row, key, tie, 5)[0], [2, 1, 0, 3, -1])  # NaN last


def test_ranking_is_seeded_per_copy():
    """The ties come from each copy's own stream: the same seed gives the same rows."""
    rows = []
    for _ in range(2):
        obs, _ = next(iter([(o, e) for o, e in _episodes(np.arange(9), range(3, 4))]))
        rows.append(obs["range_bearing"])
    np.testing.assert_array_equal(rows[0], rows[1])
