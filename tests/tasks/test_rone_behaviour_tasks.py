"""SortedFollowing-v0, ParityClustering-v0 and MidAngleNavigation-v0: metrics on hand-made layouts, the leader's
removal, the corridor and the relays' hop-count firmware."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.sparse.csgraph import shortest_path

import swarm_envs
from swarm_envs.tasks.mid_angle_navigation_v0 import MidAngleNavigationTask
from swarm_envs.tasks.task import BatchState, distance_to_segments, segments_crossed


def _state(positions, headings, steps=5):
    positions = np.asarray(positions, float)[None]
    n = positions.shape[1]
    return BatchState(positions, np.asarray(headings, float)[None], np.zeros((1, n, 2)), np.zeros((1, n, 8), bool), np.array([steps]))


# -- sorted following ------------------------------------------------------------------------------------
def test_following_line_order_and_the_removed_leader():
    env = swarm_envs.make("swarm_envs/SortedFollowing-v0", n_robots=3, sensing="ideal", follow_distance=0.5, remove_leader_at=10)
    task = env.task
    # robot 1 is 0.4 m behind robot 0 and faces it; robot 2 is 0.4 m behind robot 1 but faces away
    state = _state([[1.0, 0.0], [0.6, 0.0], [0.2, 0.0]], [0.0, 0.0, np.pi])
    _, _, metrics = task.rewards(state, np.array([False]))
    assert metrics["following_fraction"][0] == 0.5 and metrics["line_order"][0] == 0.5
    state = _state([[1.0, 0.0], [0.6, 0.0], [0.2, 0.0]], [0.0, 0.0, 0.0])  # both face their predecessor
    _, _, metrics = task.rewards(state, np.array([False]))
    assert metrics["following_fraction"][0] == 1.0 and metrics["line_order"][0] == 1.0
    state.positions[0, 2] = [-0.1, 0.0]  # robot 2 too far behind (0.7 m)
    _, _, metrics = task.rewards(state, np.array([False]))
    assert metrics["following_fraction"][0] == 0.5
    # after the removal robot 1 leads and robot 2 follows robot 1
    state = _state([[5.0, 5.0], [0.6, 0.0], [0.2, 0.0]], [0.0, 0.0, 0.0], steps=10)
    rewards, _, metrics = task.rewards(state, np.array([False]))
    assert metrics["following_fraction"][0] == 1.0 and rewards[0, 0] == 0.0  # the switched-off robot earns nothing


def test_the_leader_is_switched_off_at_remove_leader_at():
    env = swarm_envs.make("swarm_envs/SortedFollowing-v0", n_robots=4, sensing="full", remove_leader_at=5)
    env.reset(seed=0)
    for t in range(1, 9):
        env.step({a: np.r_[0.5, 0.0, 1.0] for a in env.agents})
        assert env.core.switched_off[0] == (t >= 5) and not env.core.switched_off[1:].any()
    assert not env.core.last_actions[0].any()


# -- parity clustering --------------------------------------------------------------------------------------
def test_segregation_and_parity_clusters():
    env = swarm_envs.make("swarm_envs/ParityClustering-v0", n_robots=4, sensing="ideal")
    d = env.platform.diameter
    # even ids 0, 2 touching on the left, odd ids 1, 3 touching on the right, far apart
    pure = [[-1.0, 0.0], [1.0, 0.0], [-1.0 + 1.1 * d, 0.0], [1.0 + 1.1 * d, 0.0]]
    _, _, m = env.task.rewards(_state(pure, np.zeros(4)), np.array([False]))
    assert m["segregation"][0] == 1.0 and m["parity_cluster_fraction"][0] == 1.0 and m["n_parity_clusters"][0] == 2
    # one mixed chain 0 - 1 - 2 - 3: every robot's neighbours have the other parity
    mixed = [[k * 1.1 * d, 0.0] for k in range(4)]
    _, _, m = env.task.rewards(_state(mixed, np.zeros(4)), np.array([False]))
    assert m["segregation"][0] == 0.0 and m["n_parity_clusters"][0] == 4 and m["parity_cluster_fraction"][0] == 0.5
    apart = [[-0.5, -0.5], [0.5, 0.5], [-0.5, 0.5], [0.5, -0.5]]
    _, _, m = env.task.rewards(_state(apart, np.zeros(4)), np.array([False]))
    assert m["segregation"][0] == 0.0


def test_segregation_reward_term_pays_the_metric_and_the_separation_gain():
    """reward_term="segregation": each robot's own same-parity share of its contacts plus the step's gain in
    (distance to the other parity - to its own) / one step's drive; no gain on the step that starts an
    episode; the default reward_term keeps the separation reward."""
    d = 0.11  # r-one diameter
    pure = [[-1.0, 0.0], [1.0, 0.0], [-1.0 + 1.1 * d, 0.0], [1.0 + 1.1 * d, 0.0]]
    moved = [[-1.0, 0.3], [1.0, 0.0], [-1.0 + 1.1 * d, 0.0], [1.0 + 1.1 * d, 0.0]]  # robot 0 left its partner
    env = swarm_envs.make("swarm_envs/ParityClustering-v0", n_robots=4, sensing="ideal", reward_mode="local", reward_term="segregation")
    task, step_drive = env.task, env.platform.max_speed * 0.1
    rewards, terms, _ = task.rewards(_state(pure, np.zeros(4)), np.array([True]))
    np.testing.assert_allclose(terms["segregation"][0], 1.0)
    np.testing.assert_allclose(rewards[0], terms["segregation"][0])  # no gain on the first step
    before = terms["separation"][0] * task.arena.size  # m: distance to the other parity - to the own
    rewards, terms, _ = task.rewards(_state(moved, np.zeros(4)), np.array([False]))
    after = terms["separation"][0] * task.arena.size
    np.testing.assert_allclose(rewards[0], terms["segregation"][0] + (after - before) / step_drive)
    assert terms["segregation"][0, 0] == 0.0 and rewards[0, 0] < 0.0, "robot 0 lost its contact and drove off"
    default = swarm_envs.make("swarm_envs/ParityClustering-v0", n_robots=4, sensing="ideal", reward_mode="local")
    rewards, terms, _ = default.task.rewards(_state(moved, np.zeros(4)), np.array([True]))
    np.testing.assert_allclose(rewards[0], terms["separation"][0])


# -- mid-angle navigation -----------------------------------------------------------------------------------
@pytest.mark.parametrize("platform", ["rone", "epuck", "droplet"])
@pytest.mark.parametrize("lanes", [1, 3])
def test_the_corridor_hides_the_goal_and_leaves_room(platform, lanes):
    env = swarm_envs.make("swarm_envs/MidAngleNavigation-v0", platform=platform, lanes=lanes, sensing="ideal")
    c, r = env.task.corridor, env.platform.radius
    for seed in range(3):
        env.reset(seed=seed)
        pos = env.world.positions
        assert distance_to_segments(pos, c.walls).min() >= r and np.all(np.abs(pos) <= env.arena.half - r)
        seeker, goal = pos[-1], pos[0]
        # out of sight at the start: beyond the IR range, or behind a wall
        assert np.linalg.norm(seeker - goal) > env.platform.ir_range or segments_crossed(seeker, goal, c.walls)
    # the shortest path is never shorter than the straight line, and longer when walls are in the way
    start = c.start_centre
    assert c.distance_to_goal(start) >= np.linalg.norm(start - c.goal) - 1e-12
    if lanes > 1:
        assert c.distance_to_goal(start) > np.linalg.norm(start - c.goal) + c.lane_width


def test_the_relays_build_the_hop_gradient_of_the_link_graph():
    """With ideal sensing every static robot's hop count is its hop distance to the goal over what it hears:
    the messages of its M nearest senders (the observation's message rows)."""
    env = swarm_envs.make("swarm_envs/MidAngleNavigation-v0", sensing="ideal", lanes=3)
    env.reset(seed=1)
    for _ in range(60):
        env.step({a: np.zeros(env.layout.action_size) for a in env.agents})
    nb = env.core.frame.neighbours
    S, M = env.n_static, env.layout.n_messages
    graph = np.zeros((S, S))  # graph[r, t] = 1: static robot r hears static robot t
    for r in range(S):
        mine = np.flatnonzero(nb.rx == r)
        heard = nb.tx[mine[np.argsort(nb.range[mine], kind="stable")][:M]]
        heard = heard[heard < S]
        graph[r, heard] = 1
    hops = shortest_path(graph.T, unweighted=True, indices=0)  # along "hears" edges, from each robot to the goal
    sent = env.core._static_payloads[:S].astype(int) @ (1 << np.arange(env.layout.message_bits))
    expected = np.minimum(hops, 2**env.layout.message_bits - 1)
    np.testing.assert_array_equal(sent, expected)
    assert expected.max() >= 4  # a gradient several hops deep


def test_arrival_time_and_path_ratio():
    env = swarm_envs.make("swarm_envs/MidAngleNavigation-v0", sensing="ideal", max_cycles=50)
    env.reset(seed=0)
    start = env.world.positions.copy()
    goal = start[0]
    # put the seeker 0.3 m in front of the goal, facing it, and drive into it
    placed = start.copy()
    placed[-1] = goal - [0.3, 0.0]
    env.reset(seed=0, options={"positions": placed, "headings": np.zeros(env.n_world)})
    for _ in range(40):
        _, _, _, _, infos = env.step({"robot_0": np.r_[1.0, 0.0, -np.ones(env.layout.message_bits)]})
    m = infos["robot_0"]["metrics"]
    assert m["success_rate"] == 1.0 and 0 < m["time_to_goal"] < 4.0
    assert 0.9 < m["path_ratio"] < 1.2  # a straight drive: about the shortest path
    assert isinstance(env.task, MidAngleNavigationTask)


def test_bad_corridor_settings_name_the_setting():
    with pytest.raises(ValueError, match="arena='square'"):
        swarm_envs.make("swarm_envs/MidAngleNavigation-v0", arena="circle")
    with pytest.raises(ValueError, match=r"message_bits must be an integer in \[1, 63\].*hop count"):
        swarm_envs.make("swarm_envs/MidAngleNavigation-v0", message_bits=0)
    with pytest.raises(ValueError, match="lanes at least 4.5 robot diameters wide"):
        swarm_envs.make("swarm_envs/MidAngleNavigation-v0", arena_size=1.0, lanes=3)


@pytest.mark.parametrize(
    "env_id, kwargs",
    [("swarm_envs/SortedFollowing-v0", {"remove_leader_at": 15}), ("swarm_envs/MidAngleNavigation-v0", {"lanes": 3}),
     ("swarm_envs/ParityClustering-v0", {})],
)
def test_copies_equal_single_envs_on_the_rone(env_id, kwargs):
    """Switched-off leaders, walls and the relays' firmware keep every copy equal to a single env (r-one, full)."""
    seeds, steps = [4, 9], 40
    kwargs = {**kwargs, "sensing": "full", "max_cycles": steps}
    vec = swarm_envs.make_vec(env_id, len(seeds), **kwargs)
    actions = np.random.default_rng(2).uniform(-1, 1, (steps, len(seeds), vec.n_agents, vec.layout.action_size))
    v_obs, _ = vec.reset(seed=seeds)
    history = []
    for t in range(steps):
        v_obs, v_rew, _, _, v_infos = vec.step(actions[t])
        history.append(({k: v.copy() for k, v in v_obs.items()}, v_rew.copy(), {k: v.copy() for k, v in v_infos["metrics"].items()}))
    for b, seed in enumerate(seeds):
        env = swarm_envs.make(env_id, **kwargs)
        env.reset(seed=seed)
        for t in range(steps):
            obs, rew, _, _, infos = env.step({a: actions[t, b, i] for i, a in enumerate(env.possible_agents)})
            for i, a in enumerate(env.possible_agents):
                for key, value in obs[a].items():
                    np.testing.assert_array_equal(history[t][0][key][b, i], value, err_msg=f"{key} copy {b} step {t}")
                assert history[t][1][b, i] == np.float32(rew[a])
            for name, value in infos[env.possible_agents[0]]["metrics"].items():
                np.testing.assert_array_equal(history[t][2][name][b], value, err_msg=name)
