"""The public task API: a user's task (examples/custom_task.py) registered and used like the suite's own, the
registry's rules, task declarations, and the suite's tasks written only with the public API."""

from __future__ import annotations

import ast
import importlib
import sys
import warnings
from pathlib import Path

import numpy as np
import pettingzoo
import pytest

import swarm_envs
from swarm_envs.adapters.env import SwarmEnv
from swarm_envs.registry import spec, task_class
from swarm_envs.tasks.settings import SettingsError
from swarm_envs.tasks.task import Int, Real, Task
from tests.conftest import parallel_api_check

ROOT = Path(__file__).resolve().parents[2]
DISPERSION = "swarm_examples/Dispersion-v0"


@pytest.fixture(scope="module")
def example():
    """The example module, imported as a user would (from the repository root)."""
    sys.path.insert(0, str(ROOT))
    try:
        yield importlib.import_module("examples.custom_task")
    finally:
        sys.path.remove(str(ROOT))


def test_example_registers_and_every_maker_takes_the_id(example):
    assert DISPERSION in swarm_envs.list_envs() and task_class(DISPERSION) is example.Dispersion
    env = swarm_envs.make(DISPERSION, n_robots=5)
    assert isinstance(env, SwarmEnv) and env.arena.size == 1.5 and env.config["link_range"] == 0.4
    assert env.metadata["name"] == "dispersion"
    assert isinstance(pettingzoo.make("parallel", DISPERSION, n_robots=3), SwarmEnv)
    assert pettingzoo.make("aec", DISPERSION, n_robots=3).possible_agents == ["robot_0", "robot_1", "robot_2"]
    vec = swarm_envs.make_vec(DISPERSION, 2, n_robots=4)
    _, infos = vec.reset(seed=0)
    assert set(infos["metrics"]) == {"mean_spacing", "connected_fraction"} and infos["metrics"]["mean_spacing"].shape == (2,)
    # the class itself works where an id does
    assert swarm_envs.make(example.Dispersion, n_robots=3).n_agents == 3
    assert swarm_envs.make_vec(example.Dispersion, 2, n_robots=3).num_envs == 2


def test_example_task_settings_are_checked(example):
    with pytest.raises(SettingsError, match="link_range must be a finite number m > 0") as err:
        swarm_envs.make(DISPERSION, link_range=-1.0)
    assert err.value.key == "link_range"
    with pytest.raises(TypeError, match=r"unknown keyword argument\(s\) \['link_rnage'\]"):
        swarm_envs.make(DISPERSION, link_rnage=1.0)


def test_example_passes_the_parallel_api_test(example):
    parallel_api_check(swarm_envs.make(DISPERSION, n_robots=5, max_cycles=40), num_cycles=40)


@pytest.mark.parametrize("sensing", ["ideal", "full"])
def test_example_copies_equal_single_envs_bit_for_bit(example, sensing):
    seeds, steps = [7, 2, 9], 40
    kwargs = dict(n_robots=5, sensing=sensing, max_cycles=steps)
    vec = swarm_envs.make_vec(DISPERSION, len(seeds), **kwargs)
    actions = np.random.default_rng(3).uniform(-1, 1, (steps, len(seeds), 5, 2))
    obs, _ = vec.reset(seed=seeds)
    trajectory = []
    for t in range(steps):
        obs, rewards, _, _, infos = vec.step(actions[t])
        trajectory.append((obs, rewards, infos))
    for b, seed in enumerate(seeds):
        env = swarm_envs.make(DISPERSION, **kwargs)
        env.reset(seed=seed)
        for t in range(steps):
            single, rewards, _, _, infos = env.step({a: actions[t, b, i] for i, a in enumerate(env.possible_agents)})
            v_obs, v_rew, v_infos = trajectory[t]
            for i, agent in enumerate(env.possible_agents):
                for key, value in single[agent].items():
                    np.testing.assert_array_equal(v_obs[key][b, i], value)
                assert v_rew[b, i] == np.float32(rewards[agent])
            for name, value in infos["robot_0"]["metrics"].items():
                assert v_infos["metrics"][name][b] == value


def test_example_trains_with_train_py(example, tmp_path, monkeypatch):
    from swarm_envs.agents.train import main

    monkeypatch.chdir(ROOT)  # the config's imports are looked up from the current directory
    out = tmp_path / "run"
    code = main(["--config", "examples/custom_task.yaml", "--output", str(out), "--set", "train.total_timesteps=640",
                 "--set", "train.n_envs=2", "--set", "eval.n_seeds=2", "--set", "env.max_cycles=20", "--set", "env.sensing=ideal",
                 "--set", "train.progress_bar=false", "--set", "agent.batch_size=64", "--set", "agent.n_steps=16"])
    assert code == 0
    results = (out / "results.csv").read_text()
    assert "ppo,mean_spacing" in results and "random,mean_spacing" in results and "scripted" not in results


def test_benchmark_command_takes_a_user_task(example, capsys, unregistered):
    from swarm_envs.agents.benchmark import main

    unregistered(DISPERSION)  # registered by examples.custom_task; --import registers it from module custom_task

    assert main(["--import", str(ROOT / "examples" / "custom_task.py"), "--task", DISPERSION,
                 "--episodes", "1", "--max-cycles", "5", "--n-robots", "3", "--sensing", "ideal"]) == 0
    out = capsys.readouterr().out
    assert DISPERSION in out and "random_walk" in out and "mean_spacing" in out


# -- the registry ---------------------------------------------------------------------------------------
@pytest.fixture(autouse=True)
def _forget_test_ids(forget_registered_ids):
    """Ids registered by a test are removed after it (conftest's ``forget_registered_ids``)."""


class _Still(Task):
    METRICS = {"spread": "mean"}
    HEADLINE = ("spread", -1)

    def rewards(self, state, first):
        spread = self.agents_of(state.positions).std(axis=(1, 2))
        return np.zeros((self.n_copies, self.n_agents)), {}, {"spread": spread}


def test_register_checks_ids_and_entry_points():
    for bad in ("NoVersion", "ns/Name-v", "ns/Name-v01", "a/b/Name-v0", "", 5):
        with pytest.raises(ValueError, match="env id must look like"):
            swarm_envs.register(bad, _Still)
    for bad in (int, object(), "no_colon_here", ":Cls", "module:"):
        with pytest.raises((TypeError, ValueError)):
            swarm_envs.register("tests/Bad-v0", bad)
    assert "tests/Bad-v0" not in swarm_envs.list_envs()


def test_register_string_entry_point_is_imported_lazily_and_errors_name_it():
    swarm_envs.register("tests/Lazy-v0", "tests_missing_module_xyz:Task")  # not imported yet: no error
    with pytest.raises(ImportError, match="tests/Lazy-v0: cannot import the entry point's module 'tests_missing_module_xyz'"):
        swarm_envs.make("tests/Lazy-v0")
    with pytest.warns(UserWarning, match="re-registering 'tests/Lazy-v0'"):
        swarm_envs.register("tests/Lazy-v0", "swarm_envs.tasks.flocking_v0:NoSuchClass")
    with pytest.raises(ImportError, match="has no 'NoSuchClass'"):
        swarm_envs.make("tests/Lazy-v0")
    with pytest.warns(UserWarning, match="re-registering 'tests/Lazy-v0'"):
        swarm_envs.register("tests/Lazy-v0", "swarm_envs.tasks.flocking_v0:FlockingTask", kwargs={"n_robots": 3})
    env = swarm_envs.make("tests/Lazy-v0", sensing="ideal")
    assert env.n_agents == 3 and env.config["collision_penalty"] == 0.1  # the id's defaults, then the caller's


def test_reregistering_warns_only_when_the_entry_changes():
    swarm_envs.register("tests/Still-v0", _Still)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        swarm_envs.register("tests/Still-v0", _Still)  # the same: silent
    with pytest.warns(UserWarning, match="re-registering 'tests/Still-v0'"):
        swarm_envs.register("tests/Still-v0", _Still, kwargs={"n_robots": 2})
    assert spec("tests/Still-v0").kwargs["n_robots"] == 2


def test_unknown_id_names_close_matches():
    with pytest.raises(ValueError, match=r"unknown environment id 'swarm_envs/Flocking-v1'; did you mean \['swarm_envs/Flocking-v0'\]"):
        swarm_envs.make("swarm_envs/Flocking-v1")


# -- task declarations ------------------------------------------------------------------------------------
def test_task_declarations_are_checked_when_the_class_is_made():
    with pytest.raises(TypeError, match="the new setting 'speed_limit' needs a rule"):
        type("Bad", (Task,), {"SETTINGS": {"speed_limit": 0.5}})
    with pytest.raises(TypeError, match="breaks its own rule"):
        type("Bad", (Task,), {"SETTINGS": {"n_robots": 0}})
    with pytest.raises(TypeError, match="HEADLINE must be"):
        type("Bad", (Task,), {"METRICS": {"a": "final"}, "HEADLINE": ("b", 1)})
    with pytest.raises(TypeError, match="reductions must be one of"):
        type("Bad", (Task,), {"METRICS": {"a": "median"}})
    # settings are inherited and can be extended
    base = type("Base", (Task,), {"SETTINGS": {"gain": Real(1.0, low=0.0)}})
    child = type("Child", (base,), {"SETTINGS": {"count": Int(2, low=1, high=9), "n_robots": 4}})
    assert child.TASK_DEFAULTS == {"gain": 1.0, "count": 2, "n_robots": 4}


def test_a_task_without_rewards_says_so():
    env = swarm_envs.make(type("NoRewards", (Task,), {}), n_robots=2, sensing="ideal")
    with pytest.raises(NotImplementedError, match="NoRewards must implement rewards"):
        env.reset(seed=0)
    with pytest.raises(TypeError, match="needs a swarm_envs.tasks.task.Task subclass"):
        SwarmEnv(n_robots=2)


# -- the suite's own tasks use only the public API --------------------------------------------------------
PUBLIC = {"swarm_envs", "swarm_envs.tasks.task", "swarm_envs.adapters.env", "swarm_envs.tasks.factories", "swarm_envs.sim.platforms"}
TASK_MODULES = [
    "aggregation_v0", "flocking_v0", "centroid_seeking_v0", "sorted_following_v0", "parity_clustering_v0", "mid_angle_navigation_v0",
]


@pytest.mark.parametrize("name", TASK_MODULES + ["../../examples/custom_task"])
def test_task_modules_import_only_the_public_api(name):
    path = (ROOT / "swarm_envs" / "tasks" / f"{name}.py").resolve()
    imported = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module:
            imported.add(node.module)
        elif isinstance(node, ast.Import):
            imported.update(alias.name for alias in node.names)
    ours = {m for m in imported if m == "swarm_envs" or m.startswith("swarm_envs.")}
    assert ours <= PUBLIC, f"{path.name} imports private modules {sorted(ours - PUBLIC)}"
