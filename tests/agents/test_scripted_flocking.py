"""ReynoldsFlocking: its three rules on hand-made observations, that it reads only the observation, and that
it flocks better than [L] Alg. 5's OrientationFlocking in the flocking GIF's scene."""

from __future__ import annotations

import numpy as np
import pytest

from swarm_envs.agents.evaluation import evaluate, make_env
from swarm_envs.agents.scripted import (
    OrientationFlocking,
    ReynoldsFlocking,
    make_scripted,
)
from swarm_envs.demo import SHOWCASE

#: the flocking GIF's scene (swarm_envs.demo.SHOWCASE["flocking"])
GIF_SCENE = {"platform": "droplet", "n_robots": 16, "max_cycles": 900, "arena_size": 1.0, "sensing": "full"}


def _obs(env, rows: list[tuple[float, float, float]]) -> dict[str, np.ndarray]:
    """One robot's observation with ``range_bearing`` rows (range m, bearing rad, relative heading rad), age 0."""
    obs = {k: np.zeros((1, *space.shape), dtype=np.float32) for k, space in env.layout.dict_space().spaces.items()}
    for i, (r, bearing, heading) in enumerate(rows):
        obs["range_bearing"][0, i] = [1.0, r, np.cos(bearing), np.sin(bearing), np.cos(heading), np.sin(heading), 0.0]
    return obs


@pytest.fixture(scope="module")
def droplets():
    env = make_env("flocking", platform="droplet", n_robots=4, sensing="ideal")
    yield env
    env.close()


def _turn(env, rows, **kwargs) -> float:
    policy = make_scripted("reynolds_flocking", env, **kwargs)
    policy.reset(1)
    return float(policy.act_batch(_obs(env, rows))[0, 1])


def test_each_rule_turns_the_robot_its_way(droplets):
    # alignment: neighbours at mid range ahead all heading 90 degrees left -> turn left
    assert _turn(droplets, [(0.2, 0.0, np.pi / 2), (0.2, 0.3, np.pi / 2)], cohesion_weight=0, separation_weight=0) > 0.1
    # cohesion: a neighbour far off to the right, heading as the robot does -> turn right
    assert _turn(droplets, [(0.3, -np.pi / 2, 0.0)], align_weight=0, separation_weight=0) < -0.1
    # separation: a neighbour 5 cm away ahead-left (inside 3 Droplet diameters) -> turn right, away from it
    assert _turn(droplets, [(0.05, 0.5, 0.0)], align_weight=0, cohesion_weight=0) < -0.1
    # and closer than separation the push outweighs the default cohesion pull
    assert _turn(droplets, [(0.05, 0.5, 0.0)]) < -0.1
    # no neighbour: straight on at full speed
    action = make_scripted("reynolds_flocking", droplets).act_batch(_obs(droplets, []))[0]
    assert action[0] == 1.0 and action[1] == 0.0


def test_reads_only_the_observation_and_not_its_row_order(droplets):
    """The same rows in another order give the same action (row order carries no ground truth)."""
    rows = [(0.12, 0.4, 0.3), (0.3, -1.2, -0.2), (0.07, 2.5, 1.0), (0.4, -2.8, 0.1)]
    a = _turn(droplets, rows)
    b = _turn(droplets, rows[::-1])
    assert a == pytest.approx(b, abs=1e-12)
    assert a != 0.0


def test_runs_without_range_on_the_rone():
    """The r-one measures no range: cohesion uses the bearings alone and separation is off (bumps remain)."""
    result = evaluate("flocking", {"platform": "rone", "n_robots": 6, "sensing": "full", "max_cycles": 30},
                      lambda e: make_scripted("reynolds_flocking", e), [0])
    assert np.isfinite(result["polarisation"]).all()


@pytest.mark.slow
def test_flocks_better_than_orientation_flocking_in_the_gif_scene():
    """Seeds 10-14 of the GIF's scene (held out from the choice of the default weights; ~1 min). Over seeds 0-29 (0-9 picked the default weights, 10-29 held out) the mean
    polarisation was 0.616 vs 0.574 (+0.042) and cohesion 0.732 vs 0.625 (+0.107); the test asks for half of
    each difference on the mean of five seeds."""
    assert SHOWCASE["flocking"]["policy"] == ReynoldsFlocking.name
    seeds = range(10, 15)
    ours = evaluate("flocking", GIF_SCENE, lambda env: make_scripted(ReynoldsFlocking.name, env), seeds)
    alg5 = evaluate("flocking", GIF_SCENE, lambda env: make_scripted(OrientationFlocking.name, env), seeds)
    assert ours["polarisation"].mean() > alg5["polarisation"].mean() + 0.02
    assert ours["cohesion"].mean() > alg5["cohesion"].mean() + 0.05
