"""train.py and its config handling: validation errors, overrides, a tiny end-to-end run, eval-only."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest
import yaml

import train
from swarm_envs.agents.config import DEFAULTS, ConfigError, apply_overrides, load_config

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = sorted((ROOT / "configs").glob("*.yaml"))
TINY = [
    "env.sensing=ideal",
    "env.n_robots=4",
    "env.max_cycles=20",
    "train.total_timesteps=1024",
    "train.n_envs=1",
    "train.checkpoint_freq=512",
    "train.progress_bar=false",
    "agent.n_steps=64",
    "agent.batch_size=128",
    "agent.n_epochs=1",
    "eval.n_seeds=3",
]


@pytest.mark.parametrize("path", CONFIGS, ids=[p.name for p in CONFIGS])
def test_shipped_configs_validate(path):
    cfg = load_config(path)
    assert cfg["eval"]["n_seeds"] >= 20
    assert cfg["env"].get("sensing", "full") == "full"


def test_default_configs_exist():
    names = {p.name for p in CONFIGS}
    assert {"aggregation.yaml", "flocking.yaml", "centroid_seeking.yaml"} <= names


@pytest.mark.parametrize(
    "text, message",
    [
        ("task: aggregation\nbogus: 1\n", "unknown config key 'bogus'"),
        ("task: aggregation\ntrain:\n  total_timestep: 5\n", "unknown config key 'train.total_timestep'"),
        ("task: aggregation\ntrain:\n  total_timesteps: many\n", "'train.total_timesteps' must be of type int"),
        ("task: aggregation\ntrain:\n  n_envs: 0\n", "'train.n_envs' must be an integer >= 1"),
        ("task: aggregation\nagent:\n  gamma: 1.5\n", "'agent.gamma' must be in [0, 1]"),
        ("task: aggregation\nagent:\n  activation: sigmoid\n", "'agent.activation'='sigmoid' not allowed"),
        ("task: aggregation\nenv:\n  n_robot: 5\n", "unknown env key(s) ['env.n_robot']"),
        ("task: aggregation\nenv:\n  platform: roomba\n", "bad env settings: unknown platform 'roomba'"),
        ("task: herding\n", "task='herding' is not a task"),
        ("task: aggregation\nagent:\n  scripted: dance\n", "'agent.scripted'='dance' is not a scripted policy"),
        ("- a\n- b\n", "must hold a mapping"),
    ],
)
def test_bad_configs_fail_clearly(tmp_path, text, message):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError) as err:
        load_config(path)
    assert message in str(err.value)


def test_overrides():
    cfg = load_config(ROOT / "configs" / "aggregation.yaml", ["train.total_timesteps=2000", "env.sensing=ideal", "agent.net_arch=[8, 8]"])
    assert cfg["train"]["total_timesteps"] == 2000 and cfg["env"]["sensing"] == "ideal" and cfg["agent"]["net_arch"] == [8, 8]
    with pytest.raises(ConfigError, match="unknown config key 'train.steps'"):
        apply_overrides(DEFAULTS, ["train.steps=3"])
    with pytest.raises(ConfigError, match="key=value"):
        apply_overrides(DEFAULTS, ["train.total_timesteps"])
    with pytest.raises(ConfigError, match="sensing"):
        load_config(None, ["env.sensing=perfect"])


def test_cli_reports_config_errors(tmp_path, capsys):
    assert train.main(["--config", str(ROOT / "configs" / "aggregation.yaml"), "--set", "train.nope=1", "--output", str(tmp_path)]) == 2
    assert "unknown config key 'train.nope'" in capsys.readouterr().err


def test_train_end_to_end_then_eval_only(tmp_path):
    out = tmp_path / "run"
    args = ["--config", str(ROOT / "configs" / "aggregation.yaml"), "--output", str(out), "--render"]
    assert train.main(args + [x for o in TINY for x in ("--set", o)]) == 0
    with open(out / "results.csv") as fh:
        reader = csv.reader(fh)
        header = next(reader)
        rows = list(reader)
    assert header == ["policy", "metric", "mean", "ci_low", "ci_high"]
    assert {r[0] for r in rows} == {"ppo", "scripted", "random"}
    assert {"largest_cluster_fraction", "n_clusters", "mean_distance_to_centroid"} <= {r[1] for r in rows}
    for r in rows:
        assert float(r[3]) <= float(r[2]) <= float(r[4])
    for name in ("results.md", "results.png", "model.zip", "config.yaml", "episode.gif", "timing.json"):
        assert (out / name).exists(), name
    assert list((out / "checkpoints").glob("ppo_*_steps.zip"))
    saved = yaml.safe_load((out / "config.yaml").read_text())
    assert saved["train"]["total_timesteps"] == 1024 and saved["agent"]["scripted"] == "bearing_aggregation"
    assert "| largest_cluster_fraction |" in (out / "results.md").read_text()
    assert len(json.loads((out / "per_seed.json").read_text())["ppo"]["n_clusters"]) == 3

    # re-evaluate the checkpoint: deterministic PPO on the same seeds gives the same numbers
    out2 = tmp_path / "eval"
    assert train.main(["--config", str(ROOT / "configs" / "aggregation.yaml"), "--output", str(out2),
                       "--eval-only", str(out / "model.zip")] + [x for o in TINY for x in ("--set", o)]) == 0
    first = json.loads((out / "per_seed.json").read_text())
    second = json.loads((out2 / "per_seed.json").read_text())
    assert first["ppo"] == second["ppo"] and first["scripted"] == second["scripted"]
    assert not (out2 / "model.zip").exists()


def test_empty_sections_take_defaults(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text("task: flocking\nenv:\ntrain:\n  n_envs: 3\n")
    cfg = load_config(path)
    assert cfg["env"] == {} and cfg["train"]["n_envs"] == 3
    assert cfg["train"]["total_timesteps"] == DEFAULTS["train"]["total_timesteps"]
