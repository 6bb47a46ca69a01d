"""PettingZoo API conformance of every registered environment, via the registry."""

import numpy as np
import pettingzoo
import pytest
import swarm_envs
from tests.conftest import aec_api_check, parallel_api_check

SENSING = ["ideal", "full"]


@pytest.mark.parametrize("env_id", swarm_envs.list_envs())
@pytest.mark.parametrize("platform", sorted(swarm_envs.PLATFORMS))
@pytest.mark.parametrize("sensing", SENSING)
def test_parallel_api(env_id, platform, sensing):
    for n in (1, 4):
        env = pettingzoo.make("parallel", env_id, n_robots=n, platform=platform, sensing=sensing, max_cycles=30)
        parallel_api_check(env, num_cycles=40)


@pytest.mark.parametrize("env_id", swarm_envs.list_envs())
@pytest.mark.parametrize("sensing", SENSING)
def test_aec_api(env_id, sensing):
    env = pettingzoo.make("aec", env_id, n_robots=3, sensing=sensing, max_cycles=20)
    aec_api_check(env, num_cycles=30)


@pytest.mark.parametrize("env_id", swarm_envs.list_envs())
def test_flatten_and_messages_layout(env_id):
    env = swarm_envs.make(env_id, n_robots=3, sensing="ideal", flatten=True, message_bits=4, max_cycles=10)
    parallel_api_check(env, num_cycles=15)
    obs, _ = env.reset(seed=0)
    agent = env.agents[0]
    space = env.observation_space(agent)
    assert space.shape == obs[agent].shape and space.contains(obs[agent])
    parts = env.layout.unflatten(obs[agent])
    assert parts["messages"].shape == (8, 2 + 4)
    assert parts["proprio"].shape == (8 + 2 + 4,)
    assert env.action_space(agent).shape == (6,)


def test_task_module_factories():
    """Each task module's PettingZoo factories (the registry itself: tests/test_registry.py)."""
    import swarm_envs.tasks.aggregation_v0, swarm_envs.tasks.centroid_seeking_v0, swarm_envs.tasks.flocking_v0  # noqa: E401,F401
    import swarm_envs.tasks.mid_angle_navigation_v0, swarm_envs.tasks.parity_clustering_v0, swarm_envs.tasks.sorted_following_v0  # noqa: E401,F401

    for module in (
        swarm_envs.tasks.aggregation_v0, swarm_envs.tasks.flocking_v0, swarm_envs.tasks.centroid_seeking_v0,
        swarm_envs.tasks.sorted_following_v0, swarm_envs.tasks.parity_clustering_v0, swarm_envs.tasks.mid_angle_navigation_v0,
    ):
        assert isinstance(module.parallel_env(sensing="ideal"), module.raw_env)
        aec = module.env(sensing="ideal")
        assert isinstance(aec, pettingzoo.AECEnv)


@pytest.mark.parametrize("env_id", swarm_envs.list_envs())
def test_rgb_array_render_headless(env_id):
    env = swarm_envs.make(env_id, n_robots=5, sensing="ideal", render_mode="rgb_array")
    env.reset(seed=1)
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.shape == (480, 480, 3)
    # robots are drawn: the frame is not a blank background
    assert len(np.unique(frame.reshape(-1, 3), axis=0)) > 3
    move = np.r_[1.0, 0.5, -np.ones(env.layout.message_bits)].astype(np.float32)  # forward and turning, bits silent
    env.step({a: move for a in env.agents})
    frame2 = env.render()
    assert not np.array_equal(frame, frame2), "moving robots must change the picture"
    env.close()


def test_ground_truth_only_in_infos():
    env = swarm_envs.make("swarm_envs/Aggregation-v0", n_robots=4, sensing="ideal")
    obs, infos = env.reset(seed=0)
    for agent, info in infos.items():
        gt = info["ground_truth"]
        assert set(gt) == {"position", "heading", "velocity"}
        assert np.shape(gt["position"]) == (2,) and np.shape(gt["velocity"]) == (2,)
        assert isinstance(obs[agent], dict) and "ground_truth" not in obs[agent]


def test_human_render_mode_opens_a_window(monkeypatch):
    """render_mode="human" draws into a pygame display window (SDL's dummy video driver here)."""
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    env = swarm_envs.make("swarm_envs/Flocking-v0", n_robots=3, sensing="ideal", render_mode="human")
    env.reset(seed=0)
    import pygame

    assert pygame.display.get_surface() is not None
    assert env.render() is None
    env.close()
    assert not pygame.display.get_init()


def test_demo_writes_a_gif(tmp_path):
    import imageio.v2 as imageio

    from swarm_envs.demo import main

    out = tmp_path / "demo.gif"
    assert main(["--task", "aggregation", "--steps", "5", "--out", str(out), "--n-robots", "4"]) == 0
    frames = imageio.mimread(out)
    assert len(frames) == 6 and frames[0].shape[:2] == (480, 480)
