"""Hostile input that the settings rules and the config check must turn into one line naming what is wrong:
scripted-policy argument values, numbers too long to print or read, exact integer bounds, and the
command-line tools' numeric options."""

from __future__ import annotations

import sys
import textwrap

import pytest

import swarm_envs
from swarm_envs.agents import train as train_cli
from swarm_envs.agents.config import ConfigError, load_config
from swarm_envs.tasks.settings import SettingsError

HUGE = "9" * 5000  # past Python's 4300-digit limit for reading and printing integers


@pytest.mark.parametrize("value", ["fast", ".nan", "-5", "1e300", "[1, 2]", "null"])
def test_scripted_kwargs_values_are_checked_with_the_config(value):
    with pytest.raises(ConfigError, match="speed must be a finite number >= 0 and <= 1") as err:
        load_config(None, ["task=flocking", f"agent.scripted_kwargs.speed={value}"])
    assert "\n" not in str(err.value)


def test_a_controller_of_your_own_is_built_once_when_the_config_is_checked(tmp_path, monkeypatch):
    (tmp_path / "my_controller.py").write_text(textwrap.dedent("""
        from swarm_envs.agents.base import Policy

        class Mine(Policy):
            def __init__(self, platform, layout, rng=None, speed=0.5):
                super().__init__(platform, layout, rng)
                self.speed = float(speed)

            def act_batch(self, obs):
                raise NotImplementedError
    """))
    monkeypatch.syspath_prepend(str(tmp_path))
    assert load_config(None, ["agent.scripted=my_controller:Mine", "agent.scripted_kwargs.speed=0.3"])
    with pytest.raises(ConfigError, match=r"agent.scripted_kwargs.*ValueError: could not convert string to float: 'fast'"):
        load_config(None, ["agent.scripted=my_controller:Mine", "agent.scripted_kwargs.speed=fast"])
    sys.modules.pop("my_controller", None)


def test_train_py_refuses_a_bad_scripted_value_before_writing(tmp_path, capsys):
    out = tmp_path / "run"
    code = train_cli.main(["--config", "configs/flocking.yaml", "--output", str(out), "--set", "agent.scripted_kwargs.speed=fast"])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and "speed" in err and not out.exists()
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("override", [f"seed={HUGE}", f"agent.n_steps=-{HUGE}", f"env.n_robots={HUGE}"])
def test_a_number_too_long_to_read_is_one_line_naming_the_key(override, tmp_path, capsys):
    code = train_cli.main(["--config", "configs/aggregation.yaml", "--output", str(tmp_path / "run"), "--set", override])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert override.split("=")[0] in err and len(err) < 600, err


def test_a_config_file_with_a_number_too_long_to_read(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text(f"seed: {HUGE}\n")
    with pytest.raises(ConfigError, match="a value cannot be read"):
        load_config(path)


@pytest.mark.parametrize("key", ["n_robots", "max_cycles", "n_neighbours", "arena_size", "collision_penalty"])
def test_env_settings_show_a_huge_integer_without_failing(key):
    with pytest.raises(SettingsError) as err:
        swarm_envs.make("swarm_envs/Flocking-v0", **{key: 10**5000})
    assert err.value.key == key and "an integer of about 5001 digits" in str(err.value)


def test_integer_bounds_are_exact():
    cfg = load_config(None, ["eval.seed_start=9223372036854775807"])  # the bound itself, which a float rounds up
    assert cfg["eval"]["seed_start"] == 2**63 - 1
    with pytest.raises(ConfigError, match="eval.seed_start"):
        load_config(None, ["eval.seed_start=9223372036854775808"])


@pytest.mark.parametrize(
    "argv, option",
    [(["--n-robots", "10000000"], "--n-robots"), (["--n-robots", "0"], "--n-robots"), (["--episodes", "0"], "--episodes"),
     (["--max-cycles", "-1"], "--max-cycles"), (["--episodes", "nan"], "--episodes")],
)
def test_benchmark_options_are_checked_by_the_settings_rules(argv, option, capsys):
    from swarm_envs.agents.benchmark import main

    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    err = capsys.readouterr().err
    assert exit_info.value.code == 2 and len(err.strip().splitlines()) == 1 and option in err, err


def test_benchmark_settings_the_env_refuses_are_one_line(capsys):
    from swarm_envs.agents.benchmark import main

    with pytest.raises(SystemExit) as exit_info:
        main(["--task", "centroid_seeking", "--n-robots", "10000", "--episodes", "1"])  # + 4 anchors: above 10,000
    err = capsys.readouterr().err
    assert exit_info.value.code == 2 and len(err.strip().splitlines()) == 1 and "above the limit of 10000" in err, err


@pytest.mark.parametrize("argv", [["--pixels", "1000000"], ["--pixels", "100"], ["--frame-skip", "0"], ["--frame-skip", "10000000"]])
def test_demo_image_options_are_bounded(argv, capsys):
    from swarm_envs.demo import main

    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    err = capsys.readouterr().err
    assert exit_info.value.code == 2 and len(err.strip().splitlines()) == 1 and argv[0] in err, err
