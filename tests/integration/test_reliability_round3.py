"""Hostile input: numpy booleans as flags, env ids that are not ids, the abstract ``Task`` itself,
TorchRL devices and actions, empty command-line names and unwritable paths, and config files with a key
given twice, no content, or an integer where a float is meant. Each is one line naming what is wrong."""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np
import pytest

import swarm_envs
from swarm_envs.agents.config import ConfigError, load_config
from swarm_envs.tasks.settings import SettingsError
from swarm_envs.tasks.task import Task

TINY_DEMO = ["--sensing", "ideal", "--n-robots", "2", "--steps", "1", "--pixels", "160", "--policy", "random"]


@pytest.fixture(autouse=True)
def _forget_test_ids(forget_registered_ids):
    """Ids registered by a test are removed after it (conftest's ``forget_registered_ids``)."""


def _one_line_exit(capsys, main, argv: list[str], *words: str) -> str:
    """``main(argv)`` exits with code 2 and one stderr line holding ``words``."""
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    err = capsys.readouterr().err
    assert exit_info.value.code == 2, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    for word in words:
        assert word in err, err
    return err


class _Still(Task):
    METRICS = {"spread": "mean"}

    def rewards(self, state, first):
        return np.zeros((self.n_copies, self.n_agents)), {}, {"spread": np.zeros(self.n_copies)}


# -- 1. numpy booleans ------------------------------------------------------------------------------------
def test_numpy_bools_are_accepted_by_boolean_flags_and_numbers_are_not():
    env = swarm_envs.make("swarm_envs/Aggregation-v0", motion_noise=np.bool_(False), observe_ids=np.bool_(True), n_robots=2, sensing="ideal")
    assert env.config["motion_noise"] is False and env.config["observe_ids"] is True
    vec = swarm_envs.make_vec("swarm_envs/Aggregation-v0", 1, agents_as_envs=np.bool_(True), n_robots=2, sensing="ideal")
    assert vec.num_envs == 2  # every robot a sub-env
    for number in (0, 1, 1.0, np.int64(1)):
        with pytest.raises(SettingsError, match="motion_noise must be True or False") as err:
            swarm_envs.make("swarm_envs/Aggregation-v0", motion_noise=number)
        assert err.value.key == "motion_noise"
    with pytest.raises(TypeError, match="agents_as_envs must be True or False"):
        swarm_envs.make_vec("swarm_envs/Aggregation-v0", 1, agents_as_envs=1)


# -- 2. env ids -----------------------------------------------------------------------------------------
def test_register_refuses_a_trailing_newline_a_path_and_a_letter_case_twin():
    for bad in ("a/B-v0\n", "../x-v0", "./B-v0", ".hidden/B-v0", "a/B-v0 ", "a b/C-v0", "a/B\t-v0", "a\\b/C-v0"):
        with pytest.raises(ValueError, match="env id must look like") as err:
            swarm_envs.register(bad, _Still)
        assert "\n" not in str(err.value)
    with pytest.raises(ValueError, match=r"'swarm_envs/aggregation-v0' differs from the registered id 'swarm_envs/Aggregation-v0' only in letter case"):
        swarm_envs.register("swarm_envs/aggregation-v0", _Still)
    assert not {"a/B-v0\n", "../x-v0", "swarm_envs/aggregation-v0"} & set(swarm_envs.list_envs())
    # valid ids still register, and the same id again keeps its own behaviour (silent when unchanged)
    swarm_envs.register("my-lab.v2/Still_1.x-v3", _Still)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        swarm_envs.register("my-lab.v2/Still_1.x-v3", _Still)
    with pytest.raises(ValueError, match="only in letter case"):
        swarm_envs.register("My-Lab.v2/Still_1.x-v3", _Still)


# -- 3. the abstract Task -------------------------------------------------------------------------------
def test_the_abstract_task_class_itself_is_refused_when_made():
    makers = [lambda: swarm_envs.make_vec(Task, 2), lambda: swarm_envs.make(Task), lambda: swarm_envs.make(swarm_envs.SwarmEnv),
              lambda: swarm_envs.register("tests/Abstract-v0", Task)]
    try:
        import torchrl  # noqa: F401
    except ImportError:
        pass
    else:
        makers.append(lambda: swarm_envs.make_torchrl(Task, 2))
    for make in makers:
        with pytest.raises(TypeError, match="needs a subclass of swarm_envs.Task that implements its hooks") as err:
            make()
        assert "\n" not in str(err.value)
    assert swarm_envs.make_vec(_Still, 2, n_robots=2, sensing="ideal").num_envs == 2  # a subclass still works


# -- 4. TorchRL -----------------------------------------------------------------------------------------
def _torchrl_env(**kwargs):
    return swarm_envs.make_torchrl("swarm_envs/Aggregation-v0", 2, n_robots=2, sensing="ideal", max_cycles=3, **kwargs)


@pytest.mark.parametrize("device, error, words", [
    ("gpu", ValueError, "device='gpu' is not a torch device"),
    ("", ValueError, "device='' is not a torch device"),
    ("meta", ValueError, "device='meta' holds no data"),
    (3.5, TypeError, "device must be a torch.device or a device string"),
    ([0], TypeError, "got [0]"),
])
def test_torchrl_device_is_checked(device, error, words):
    pytest.importorskip("torchrl", reason="torchrl is not installed: pip install -e '.[torchrl]'")
    import torch

    with pytest.raises(error) as err:
        _torchrl_env(device=device)
    assert words in str(err.value) and "\n" not in str(err.value)
    if not torch.cuda.is_available():
        with pytest.raises(ValueError, match="device='cuda:0' is not available in this torch build"):
            _torchrl_env(device="cuda:0")
    for good in ("cpu", torch.device("cpu"), None):
        assert _torchrl_env(device=good).rollout(2).shape == (2, 2)


def test_torchrl_step_without_an_action_names_the_key():
    pytest.importorskip("torchrl", reason="torchrl is not installed: pip install -e '.[torchrl]'")
    from tensordict import TensorDict

    env = _torchrl_env()
    td = env.reset()
    for given in (td, TensorDict({}, batch_size=[2])):
        with pytest.raises(ValueError, match=r"\('agents', 'action'\)") as err:
            env.step(given.clone())
        assert "no such entry" in str(err.value) and "\n" not in str(err.value)
    assert env.step(env.rand_action(td))["next", "agents", "reward"].shape == (2, 2, 1)


# -- 5. command-line tools ------------------------------------------------------------------------------
@pytest.mark.parametrize("argv, words", [
    (["--task", ""], ("unknown task ''",)),
    (["--platform", ""], ("--platform", "invalid choice: ''")),
    (["--out", ""], ("--out ''", "names no file")),
])
def test_demo_refuses_an_empty_task_platform_or_path(argv, words, tmp_path, capsys):
    from swarm_envs.demo import main

    out = ["--out", str(tmp_path / "x.gif")] if "--out" not in argv else []
    _one_line_exit(capsys, main, [*argv, *TINY_DEMO, *out], *words)
    assert not (tmp_path / "x.gif").exists()


@pytest.mark.parametrize("value", ["", ",", "aggregation,", " , "])
def test_benchmark_refuses_an_empty_task_name(value, capsys):
    from swarm_envs.agents.benchmark import main

    _one_line_exit(capsys, main, ["--task", value, "--episodes", "1", "--max-cycles", "1", "--sensing", "ideal", "--n-robots", "2"],
                   f"--task {value!r} has an empty task name")


@pytest.mark.parametrize("argv, option", [(["--seed", "-1"], "--seed"), (["--seeds", "0"], "--seeds"), (["--max-cycles", "0"], "--max-cycles"),
                                          (["--seed", "1.5"], "--seed")])
def test_validate_behaviours_refuses_a_negative_seed_and_other_bad_numbers(argv, option, tmp_path, capsys):
    from swarm_envs.validate.__main__ import main

    small = ["--only", "flocking", "--seeds", "1", "--max-cycles", "1", "--out", str(tmp_path)]
    _one_line_exit(capsys, main, ["behaviours", *small, *argv], option, argv[1])
    assert list(tmp_path.iterdir()) == []


def test_demo_refuses_an_out_path_it_cannot_write_before_running(tmp_path, capsys):
    from swarm_envs.demo import main

    too_long = tmp_path / ("x" * 300 + ".gif")  # the folder is writable, the name is not (ENAMETOOLONG)
    bad = [too_long] + ([Path("/proc/x.gif")] if os.path.isdir("/proc") else [])  # /proc passes a directory check as root
    for path in bad:
        _one_line_exit(capsys, main, ["--task", "aggregation", *TINY_DEMO, "--out", str(path)], f"--out '{path}'")
    assert list(tmp_path.iterdir()) == []
    good = tmp_path / "ok.gif"
    assert main(["--task", "aggregation", *TINY_DEMO, "--out", str(good)]) == 0 and good.stat().st_size > 0


# -- 6. the training config -----------------------------------------------------------------------------
@pytest.mark.parametrize("text, key, lines", [
    ("task: flocking\nseed: 1\nseed: 2\n", "'seed'", "lines 2 and 3"),
    ("task: flocking\nagent:\n  gamma: 0.9\n  n_epochs: 3\n  gamma: 0.8\n", "'gamma'", "lines 3 and 5"),
    ("task: flocking\nenv: {n_robots: 3, n_robots: 4}\n", "'n_robots'", "lines 2 and 2"),
])
def test_config_refuses_a_key_given_twice(text, key, lines, tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError) as err:
        load_config(path)
    message = str(err.value)
    assert f"the key {key} is given twice ({lines})" in message and "\n" not in message, message
    with pytest.raises(ConfigError, match=r"config key 'env': the value names the key 'n_robots' twice"):
        load_config(None, ["env={n_robots: 3, n_robots: 4}"])
    # a key merged in with << may still be overridden
    agent = load_config(None, ["agent={<<: {gamma: 0.5, n_epochs: 2}, gamma: 0.9}"])["agent"]
    assert agent["gamma"] == 0.9 and agent["n_epochs"] == 2


@pytest.mark.parametrize("text", ["", "\n\n", "# a config\n# only comments\n", "{}\n"])
def test_config_file_that_names_no_task_is_refused(text, tmp_path):
    path = tmp_path / "empty.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError, match="names no task") as err:
        load_config(path)
    assert "\n" not in str(err.value)
    path.write_text("# comment\ntask: flocking\n")
    assert load_config(path)["task"] == "flocking"


def test_config_takes_an_integer_where_a_float_is_meant_and_checks_its_bounds(tmp_path):
    with pytest.raises(ConfigError) as err:
        load_config(None, ["agent.learning_rate=0"])
    assert "'agent.learning_rate' must be a finite number in (0, 1]" in str(err.value) and "got 0" in str(err.value)
    with pytest.raises(ConfigError, match=r"'agent.gamma' must be a finite number in \[0, 1\] \(a discount factor\), got 2"):
        load_config(None, ["agent.gamma=2"])
    cfg = load_config(None, ["agent.learning_rate=1", "agent.gamma=1"])
    assert cfg["agent"]["learning_rate"] == 1.0 and type(cfg["agent"]["learning_rate"]) is float
    assert type(cfg["agent"]["gamma"]) is float
    path = tmp_path / "c.yaml"
    path.write_text("task: flocking\nagent:\n  clip_range: 1\n")
    assert type(load_config(path)["agent"]["clip_range"]) is float
    with pytest.raises(ConfigError, match="'agent.n_steps' must be an integer"):  # integer keys keep their wording
        load_config(None, ["agent.n_steps=0"])
