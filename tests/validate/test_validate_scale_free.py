"""[L Sec. 6.1, Fig. 6.2] edge-error validation: the thesis-style metric and the run through the env's stack."""

import numpy as np

import swarm_envs

from swarm_envs.sensing.scale_free import coordinates_all, knowledge_from_matrix
from swarm_envs.validate.envs import copy_knowledge, scene_core
from swarm_envs.validate.scale_free import VARIANTS, EdgeErrors, bearing_matrix, edge_error_env, edge_error_experiment, thesis_robot


def _results(pos, headings):
    kn = knowledge_from_matrix(bearing_matrix(pos, headings, 1.0))
    return {v: coordinates_all(kn, **kw) for v, kw in VARIANTS.items()}


def test_thesis_metric_uses_one_fully_connected_robot_per_configuration():
    rng = np.random.default_rng(1)
    res = edge_error_experiment(rng, configs=12, workspace=1.0)
    assert res["configs"] == 12
    assert 0 < res["thesis_configs"] <= 12
    for v in VARIANTS:
        # 5 edges per evaluated configuration: exactly one robot with all 5 others
        assert res["thesis_edges"][v] == 5 * res["thesis_configs"]
        # the all-rigid average counts many robots per configuration
        assert res["edges"][v] > res["thesis_edges"][v]


def test_thesis_robot_needs_coordinates_of_every_other_robot():
    # a chain: nobody sees everyone (1 m range, robots 0.6 m apart in a line)
    pos = np.array([[0.0, 0.0], [0.6, 0.0], [1.2, 0.0], [1.8, 0.0], [2.4, 0.0], [3.0, 0.0]])
    head = np.zeros(6)
    assert thesis_robot(_results(pos, head), 6, np.random.default_rng(0)) is None
    errors = EdgeErrors()
    errors.add(_results(pos, head), pos, np.random.default_rng(0))
    assert errors.thesis_configs == 0 and errors.configs == 1
    # a tight cluster: every robot sees every other one, so one of them is drawn
    ring = 0.3 * np.stack([np.cos(np.arange(6)), np.sin(np.arange(6))], -1)
    u = thesis_robot(_results(ring, np.zeros(6)), 6, np.random.default_rng(0))
    assert u is not None and 0 <= u < 6


def test_edge_error_through_the_env_reads_message_borne_knowledge():
    rng = np.random.default_rng(2)
    scenes = edge_error_experiment(rng, configs=4, workspace=0.8)["_scenes"]
    res = edge_error_env(scenes, seed=10, steps=48, rng=np.random.default_rng(3))
    assert res["configs"] == 4
    assert res["max_displacement_m"] < 1e-9  # static robots
    assert sum(res["robots_evaluated"].values()) > 0
    # before any exchange message went out, nobody knows anything
    core = scene_core("swarm_envs/Aggregation-v0", [p for p, _ in scenes], [h for _, h in scenes], [10, 11, 12, 13],
                      n_robots=6, platform="rone", arena_size=1.5)
    kn = copy_knowledge(core, 1)
    assert kn.ids.shape[0] == 6 and (kn.row_ids < 0).all()
    for _ in range(48):
        core.step(np.zeros((core.n_total, 2)))
    kn = copy_knowledge(core, 1)
    assert (kn.ids >= 0).any() and kn.ids.max() < 6  # the copy's own ids
    # copy 1 is the single env reset with seed 11 and these positions and headings
    env = swarm_envs.make("swarm_envs/Aggregation-v0", n_robots=6, platform="rone", arena_size=1.5)
    env.reset(seed=11, options={"positions": scenes[1][0], "headings": scenes[1][1]})
    for _ in range(48):
        env.step({a: np.zeros(2) for a in env.agents})
    single = env.sensing.exchange.knowledge()
    np.testing.assert_array_equal(kn.ids, single.ids)
    np.testing.assert_array_equal(kn.bearings, single.bearings)
    np.testing.assert_array_equal(kn.row_ids, single.row_ids)
