"""The scripted mid-angle seeker ([L] Alg. 8) on hand-made observations: it takes each relay's lowest hop
count, and once it has driven through a gap it goes on instead of steering back to the relays behind it."""

from __future__ import annotations

import numpy as np
import pytest

from swarm_envs.adapters.env import DT
from swarm_envs.agents.evaluation import make_env
from swarm_envs.agents.scripted import make_scripted
from swarm_envs.sim.world import N_BUMP_SECTORS


@pytest.fixture(scope="module")
def env():
    return make_env("mid_angle_navigation", sensing="ideal")  # 6 robots: goal 0, relays 1-4, seeker 5


def _obs(env, relays: dict[int, tuple[int, float]], turn: float = 0.0) -> dict[str, np.ndarray]:
    """One seeker's observation: each relay id -> (hop count it broadcasts, its bearing (rad, body frame)),
    as a fresh range & bearing row and a decoded message; ``turn`` is the last action's angular fraction."""
    layout = env.layout
    n_world, b = layout.n_world, layout.message_bits
    obs = {k: np.zeros((1,) + v.shape, np.float32) for k, v in layout.dict_space().spaces.items()}
    obs["own_id"][0, :2] = [1.0, (n_world - 1) / (n_world - 1)]  # the seeker: id 5
    obs["proprio"][0, N_BUMP_SECTORS + 1] = turn
    for slot, (who, (hop, bearing)) in enumerate(relays.items()):
        obs["range_bearing"][0, slot, [0, 2, 3]] = [1.0, np.cos(bearing), np.sin(bearing)]  # age 0
        obs["range_bearing_ids"][0, slot, :2] = [1.0, who / (n_world - 1)]
        obs["messages"][0, slot, :2] = [1.0, bearing / np.pi]
        obs["messages"][0, slot, 2 : 2 + b] = [(hop >> k) & 1 for k in range(b)]
        obs["message_ids"][0, slot, :2] = [1.0, who / (n_world - 1)]
    return obs


def _act(policy, env, relays, turn: float = 0.0, steps: int = 1) -> np.ndarray:
    for _ in range(steps):
        action = policy.act_batch(_obs(env, relays, turn))[0]
    return action


def test_seeker_takes_each_relays_lowest_hop_count(env):
    """A relay whose hop count rose (it lost its own links for a while) still counts with its lowest one:
    the seeker keeps steering to it (left) rather than to a relay of the next hop count (right)."""
    policy = make_scripted("mid_angle_navigation", env, memory=50)
    policy.reset(1)
    left, right = np.deg2rad(60.0), np.deg2rad(-60.0)
    assert _act(policy, env, {1: (1, left), 2: (2, right)}, steps=3)[1] > 0  # hop 1 on the left: turn left
    assert _act(policy, env, {1: (3, left), 2: (2, right)}, steps=3)[1] > 0  # relay 1 now says 3: still its 1
    # once its 1 is older than `memory` steps, its newer count is its own
    assert _act(policy, env, {1: (3, left), 2: (2, right)}, steps=50)[1] < 0


def test_seeker_goes_on_through_the_gap_it_crossed(env):
    """Two hop-1 relays ahead at +-30 degrees, then behind at +-150 degrees with no turn in between: the
    seeker drove through their gap, so it drives on (no turn) instead of turning back to their mid-angle."""
    policy = make_scripted("mid_angle_navigation", env)
    policy.reset(1)
    ahead = {3: (1, np.deg2rad(30.0)), 4: (1, np.deg2rad(-30.0))}
    behind = {3: (1, np.deg2rad(150.0)), 4: (1, np.deg2rad(-150.0))}
    a = _act(policy, env, ahead, steps=3)
    assert a[0] == pytest.approx(policy.speed) and a[1] == pytest.approx(0.0, abs=1e-6)
    a = _act(policy, env, behind, steps=5)
    assert a[0] == pytest.approx(policy.speed) and a[1] == pytest.approx(0.0, abs=1e-6)
    behind_left = {3: (1, np.deg2rad(110.0)), 4: (1, np.deg2rad(-170.0))}  # their mid-angle at 150 degrees
    assert _act(policy, env, behind_left)[1] < 0  # directly away from it: -30 degrees, to the right
    assert _act(policy, env, {**behind, 0: (0, np.deg2rad(20.0))}, steps=2)[1] > 0  # the goal (left) takes over


def test_seeker_that_turned_round_steers_back_to_the_gap(env):
    """The same relays behind it after the seeker turned on the spot (its own rotation, from its last
    actions): it has not crossed their line, so it turns back to their mid-angle."""
    policy = make_scripted("mid_angle_navigation", env)
    policy.reset(1)
    _act(policy, env, {3: (1, np.deg2rad(30.0)), 4: (1, np.deg2rad(-30.0))}, steps=3)
    steps = 12
    turn = np.pi / (steps * env.platform.max_angular_speed * DT)  # half a turn in `steps` steps
    assert 0 < turn <= 1
    for k in range(1, steps + 1):
        heading = k * turn * env.platform.max_angular_speed * DT
        relays = {3: (1, np.deg2rad(30.0) - heading), 4: (1, np.deg2rad(-30.0) - heading)}
        a = _act(policy, env, relays, turn=turn)
    assert abs(a[1]) == pytest.approx(1.0)  # the mid-angle is dead behind: a full turn
