"""examples/custom_task_obstacle.py: a task with a wall runs through make, make_vec and swarm-demo."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import swarm_envs
from swarm_envs.tasks.settings import SettingsError
from tests.conftest import parallel_api_check

ROOT = Path(__file__).resolve().parents[2]
ENV_ID = "swarm_examples/GatherBeyondWall-v0"


@pytest.fixture(autouse=True)
def _registered(monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))
    import examples.custom_task_obstacle  # noqa: F401  (registers the id)


def test_parallel_env_passes_the_api_test_and_starts_left_of_the_wall():
    env = swarm_envs.make(ENV_ID, n_robots=8, max_cycles=30)
    parallel_api_check(env, num_cycles=30)
    env.reset(seed=3)
    task = env.task
    positions = np.asarray(env.world.positions).reshape(-1, 2)  # (n_world, 2) m of the one copy
    wall = task.obstacle_segments
    assert wall.shape == (1, 2, 2) and np.all(wall[0, :, 0] == 0.0)
    assert np.all(positions[:, 0] < -task.platform.radius), "every robot starts left of the wall"
    _, _, _, _, infos = env.step({a: np.zeros(2, dtype=np.float32) for a in env.agents})
    metrics = infos["robot_0"]["metrics"]
    assert metrics["fraction_across"] == 0.0 and 0.0 < metrics["mean_goal_distance"] < task.arena.size


def test_vector_copy_equals_single_env():
    vec = swarm_envs.make_vec(ENV_ID, 3, n_robots=8)
    obs, _ = vec.reset(seed=5)
    env = swarm_envs.make(ENV_ID, n_robots=8)
    single, _ = env.reset(seed=6)  # copy b of make_vec is seeded with seed + b
    rng = np.random.default_rng(0)
    for _ in range(10):
        actions = rng.uniform(-1, 1, (3, 8, 2)).astype(np.float32)
        obs, rewards, _, _, _ = vec.step(actions)
        single, single_rewards, _, _, _ = env.step({a: actions[1, i] for i, a in enumerate(env.agents)})
        np.testing.assert_array_equal(rewards[1], np.asarray([single_rewards[a] for a in env.agents], dtype=rewards.dtype))
        np.testing.assert_array_equal(obs["range_bearing"][1], np.stack([single[a]["range_bearing"] for a in env.agents]))


def test_a_gap_as_wide_as_the_arena_is_refused():
    with pytest.raises(SettingsError, match="gap"):
        swarm_envs.make(ENV_ID, gap=5.0)


def test_swarm_demo_renders_the_task_to_a_gif(tmp_path):
    out = tmp_path / "wall.gif"
    env = dict(os.environ, SDL_VIDEODRIVER="dummy", MPLBACKEND="Agg", PYTHONPATH=os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])))
    result = subprocess.run([sys.executable, "-m", "swarm_envs.demo", "--import", str(ROOT / "examples" / "custom_task_obstacle.py"),
                             "--task", ENV_ID, "--policy", "random", "--steps", "10", "--out", str(out)],
                            cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr[-2000:]
    from PIL import Image

    with Image.open(out) as gif:
        assert gif.n_frames == 11
