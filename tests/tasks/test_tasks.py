"""Each task's reward moves the right way on a hand-built scenario."""

import numpy as np

from swarm_envs import aggregation_v0, centroid_seeking_v0, flocking_v0


def run(env, action_fn, steps):
    total = np.zeros(env.n_agents)
    infos = None
    for _ in range(steps):
        _, rewards, _, _, infos = env.step({a: action_fn(env, i) for i, a in enumerate(env.agents)})
        total += np.array([rewards[a] for a in env.possible_agents])
    return total, infos


def towards(point):
    def act(env, i):
        r = env.agent_robots[i]
        delta = point - env.world.positions[r]
        turn = np.arctan2(delta[1], delta[0]) - env.world.headings[r]
        turn = (turn + np.pi) % (2 * np.pi) - np.pi
        return np.array([np.cos(turn) > 0.5, np.clip(2 * turn, -1, 1)], dtype=np.float32)
    return act


def test_aggregation_rewards_moving_together():
    start = np.array([[-0.4, -0.4], [0.4, -0.4], [0.4, 0.4], [-0.4, 0.4]])
    heads = np.arctan2(-start[:, 1], -start[:, 0])
    for mode in ("global", "local"):
        env = aggregation_v0.parallel_env(n_robots=4, sensing="ideal", arena_size=1.2, reward_mode=mode)
        _, info0 = env.reset(seed=0, options={"positions": start, "headings": heads})
        inward, info = run(env, towards(np.zeros(2)), 20)
        env.reset(seed=0, options={"positions": start, "headings": heads + np.pi})
        outward, _ = run(env, lambda e, i: np.array([1.0, 0.0]), 20)
        assert np.all(inward > 0) and np.all(outward < 0), (mode, inward, outward)
        assert info["robot_0"]["metrics"]["mean_distance_to_centroid"] < info0["robot_0"]["metrics"]["mean_distance_to_centroid"]


def test_aggregation_cluster_metrics():
    env = aggregation_v0.parallel_env(n_robots=4, sensing="ideal", arena_size=2.0)
    pos = np.array([[0.0, 0.0], [0.08, 0.0], [0.7, 0.7], [-0.7, 0.7]])
    _, infos = env.reset(seed=0, options={"positions": pos, "headings": np.zeros(4)})
    m = infos["robot_0"]["metrics"]
    assert m["n_clusters"] == 3 and m["largest_cluster_fraction"] == 0.5


def test_flocking_rewards_aligned_motion():
    pos = np.array([[0.0, 0.0], [0.0, 0.15], [0.0, -0.15], [0.15, 0.0]])
    env = flocking_v0.parallel_env(n_robots=4, sensing="ideal", arena_size=3.0)
    env.reset(seed=0, options={"positions": pos, "headings": np.zeros(4)})
    aligned, info = run(env, lambda e, i: np.array([1.0, 0.0]), 10)
    assert info["robot_0"]["metrics"]["polarisation"] > 0.99
    env.reset(seed=0, options={"positions": pos, "headings": np.array([0.0, np.pi, np.pi / 2, -np.pi / 2])})
    opposed, info = run(env, lambda e, i: np.array([1.0, 0.0]), 10)
    assert info["robot_0"]["metrics"]["polarisation"] < 0.05
    env.reset(seed=0, options={"positions": pos, "headings": np.zeros(4)})
    still, _ = run(env, lambda e, i: np.zeros(2), 10)
    assert np.all(aligned > opposed + 5) and np.all(aligned > still + 5)


def test_centroid_seeker_approaching_raises_reward():
    env = centroid_seeking_v0.parallel_env(sensing="ideal", max_cycles=40)
    env.reset(seed=4)
    centroid = env.centroid
    toward, info = run(env, towards(centroid), 40)
    env.reset(seed=4)
    away, _ = run(env, towards(2 * env.world.positions[env.agent_robots[0]] - centroid), 40)
    assert toward[0] > away[0]
    m = info["robot_0"]["metrics"]
    assert m["mean_distance_to_centroid"] < 0.05
    assert np.isfinite(m["mean_distance_second_half"])
    # anchors never move and are not agents
    assert env.possible_agents == ["robot_0"] and env.n_static == 4


def test_batched_components_equal_one_graph_per_copy():
    """largest_component_fraction over B copies at once equals scipy's components of each copy's own graph."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    from swarm_envs.tasks.metrics import largest_component_fraction

    def cluster_stats(positions, link_distance):  # one copy: (largest-cluster fraction, number of clusters)
        n = len(positions)
        pairs = cKDTree(positions).query_pairs(link_distance, output_type="ndarray").reshape(-1, 2)
        graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
        sizes = np.bincount(connected_components(graph, directed=False)[1])
        return sizes.max() / n, len(sizes)

    rng = np.random.default_rng(0)
    for B, N in [(1, 5), (7, 10), (3, 50)]:
        pos = rng.uniform(0, 1, (B, N, 2))
        largest, count = largest_component_fraction(pos, 0.2)
        expected = np.array([cluster_stats(p, 0.2) for p in pos])
        np.testing.assert_array_equal(largest, expected[:, 0])
        np.testing.assert_array_equal(count, expected[:, 1])
