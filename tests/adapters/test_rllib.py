"""RLlib: one PPO iteration with 2 env runners on the default Dict observation (examples/rllib_ppo.py)."""

import importlib.util
import math
from pathlib import Path

import pytest

pytest.importorskip("ray.rllib", reason="ray[rllib] is not installed: pip install -e '.[rllib]'")

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "rllib_ppo.py"
N_ROBOTS = 3
BATCH = 60  # env steps per iteration


def load_example():
    spec = importlib.util.spec_from_file_location("rllib_ppo", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_env_creator_keeps_the_dict_observation():
    example = load_example()
    env = example.env_creator({"task": "swarm_envs/Flocking-v0", "n_robots": N_ROBOTS, "sensing": "ideal", "flatten": False})
    obs, infos = env.reset(seed=0)
    assert set(obs) == {f"robot_{i}" for i in range(N_ROBOTS)}
    assert isinstance(obs["robot_0"], dict) and "range_bearing" in obs["robot_0"]


def test_one_ppo_iteration_with_two_env_runners():
    example = load_example()
    history = example.main(
        ["--task", "swarm_envs/Aggregation-v0", "--n-robots", str(N_ROBOTS), "--max-cycles", "20", "--num-env-runners", "2",
         "--iterations", "1", "--batch", str(BATCH), "--minibatch", "30", "--epochs", "1"]
    )
    assert len(history) == 1
    row = history[0]
    # every robot of every sampled env step reached the learner (sampling may overshoot the batch)
    assert row["agent_steps"] >= BATCH * N_ROBOTS
    assert row["agent_steps"] % N_ROBOTS == 0
    assert math.isfinite(row["episode_return_mean"])


def test_env_runners_import_a_task_of_your_own(unregistered):
    """``--import`` reaches every env runner (a separate process), which registers the id before making the env."""
    import sys

    unregistered("swarm_examples/Dispersion-v0")
    sys.modules.pop("custom_task", None)
    try:
        history = load_example().main(
            ["--import", str(EXAMPLE.parent / "custom_task.py"), "--task", "swarm_examples/Dispersion-v0", "--n-robots", "3",
             "--max-cycles", "10", "--num-env-runners", "1", "--iterations", "1", "--batch", "20", "--minibatch", "10", "--epochs", "1",
             "--torch-threads", "1"]
        )
    finally:
        sys.modules.pop("custom_task", None)
    assert len(history) == 1 and history[0]["agent_steps"] >= 20 * 3
