"""train.py (agents.train) and its config handling: validation errors, overrides, a tiny end-to-end run with its
learning curve, eval-only into its own directory, one-line errors on bad output directories and checkpoints."""

from __future__ import annotations

import csv
import json
import os
import zipfile
from pathlib import Path

import pytest
import yaml

from swarm_envs.agents import train, training_log
from swarm_envs.agents.config import DEFAULTS, ConfigError, apply_overrides, load_config

ROOT = Path(__file__).resolve().parents[2]
CONFIGS = sorted((ROOT / "configs").glob("*.yaml"))
AGG = str(ROOT / "configs" / "aggregation.yaml")
TINY = [
    "env.sensing=ideal",
    "env.n_robots=4",
    "env.max_cycles=20",
    "train.total_timesteps=1000",  # rollouts of 64 steps x 4 robots: PPO runs 1024
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
        ("task: aggregation\ntrain:\n  n_envs: 0\n", "'train.n_envs' must be an integer in [1, 100000]"),
        ("task: aggregation\nagent:\n  gamma: 1.5\n", "'agent.gamma' must be a finite number in [0, 1]"),
        ("task: aggregation\nagent:\n  activation: sigmoid\n", "'agent.activation'='sigmoid' not allowed"),
        ("task: aggregation\nenv:\n  n_robot: 5\n", "unknown env key(s) ['env.n_robot']"),
        ("task: aggregation\nenv:\n  platform: roomba\n", "bad env settings: unknown platform 'roomba'"),
        ("task: herding\n", "config key 'task': unknown task 'herding'"),
        ("task: aggregation\nagent:\n  scripted: dance\n", "unknown scripted policy 'dance'"),
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
    # a section given as a mapping updates it like a config file's section; an empty one changes nothing
    cfg = load_config(ROOT / "configs" / "aggregation.yaml", ["train={}", "agent={n_epochs: 3}"])
    base = load_config(ROOT / "configs" / "aggregation.yaml")
    assert cfg["train"] == base["train"] and cfg["agent"] == {**base["agent"], "n_epochs": 3}
    with pytest.raises(ConfigError, match="unknown config key 'train.steps'"):
        apply_overrides(DEFAULTS, ["train={steps: 3}"])


def test_cli_reports_config_errors(tmp_path, capsys):
    assert train.main(["--config", AGG, "--set", "train.nope=1", "--output", str(tmp_path)]) == 2
    assert "unknown config key 'train.nope'" in capsys.readouterr().err


def _tiny(*extra: str) -> list[str]:
    return [x for o in (*TINY, *extra) for x in ("--set", o)]



@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    """One tiny training run (with the progress bar on), shared by the tests below: (out dir, stdout, stderr)."""
    import contextlib
    import io

    out = tmp_path_factory.mktemp("train") / "run"
    stdout, stderr = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
        code = train.main(["--config", AGG, "--output", str(out), "--render"] + _tiny("train.progress_bar=true"))
    assert code == 0, stderr.getvalue()
    return out, stdout.getvalue(), stderr.getvalue()


def _read_csv(path: Path) -> tuple[list[str], list[list[str]]]:
    with open(path) as fh:
        reader = csv.reader(fh)
        return next(reader), list(reader)


def test_planned_timesteps_rounds_up_to_whole_rollouts():
    assert train.planned_timesteps(200_000, 128, 20) == 202_240  # the default config
    assert train.planned_timesteps(1000, 64, 4) == 1024
    assert train.planned_timesteps(1024, 64, 4) == 1024


def test_train_end_to_end(trained):
    out, stdout, stderr = trained
    header, rows = _read_csv(out / "results.csv")
    assert header == ["policy", "metric", "mean", "ci_low", "ci_high", "n"]
    assert {r[0] for r in rows} == {"ppo", "scripted", "random"}
    assert {"largest_cluster_fraction", "n_clusters", "mean_distance_to_centroid"} <= {r[1] for r in rows}
    for r in rows:
        assert float(r[3]) <= float(r[2]) <= float(r[4]) and int(r[5]) == 3
        if r[1] == "largest_cluster_fraction":
            assert 0.0 <= float(r[3]) and float(r[4]) <= 1.0
    for name in ("results.md", "results.png", "model.zip", "config.yaml", "episode.gif", "timing.json",
                 "progress.csv", "learning_curve.png"):
        assert (out / name).exists(), name
    assert list((out / "checkpoints").glob("ppo_*_steps.zip"))
    saved = yaml.safe_load((out / "config.yaml").read_text())
    assert saved["train"]["total_timesteps"] == 1000 and saved["agent"]["scripted"] == "swarm_envs.agents.scripted:BearingAggregation"
    md = (out / "results.md").read_text()
    assert "| largest_cluster_fraction |" in md and "n=3 seeds" in md and "bootstrap" in md
    assert len(json.loads((out / "per_seed.json").read_text())["ppo"]["n_clusters"]) == 3
    assert json.loads((out / "timing.json").read_text())["robot_steps"] == 1024


def test_learning_curve_csv_and_progress(trained):
    out, stdout, stderr = trained
    header, rows = _read_csv(out / "progress.csv")
    for key in ("time/total_timesteps", "rollout/ep_rew_mean", "rollout/ep_len_mean", "time/fps", training_log.RATE_KEY, "train/loss",
                "train/value_loss"):
        assert key in header, key
    assert all(float(r[header.index(training_log.RATE_KEY)]) > 0 for r in rows)
    steps = [int(r[header.index("time/total_timesteps")]) for r in rows]
    assert steps == [256, 512, 768, 1024]  # one row per rollout of 64 steps x 4 robots, up to the real total
    lengths = {float(r[header.index("rollout/ep_len_mean")]) for r in rows}
    assert lengths == {20.0}  # max_cycles=20 episodes
    assert "the budget 1000 rounded up to 4 whole rollouts" in stdout
    assert "PPO 1024/1024 robot-steps (100%)" in stdout and "ep_rew_mean" in stdout and "robot-steps/s" in stdout
    assert " fps " not in stdout  # SB3's time/fps counts the compile: the lines show the rate of rate_callback
    # the progress bar's total is what really runs, and it ends there
    assert "1024/1024" in stderr and "/1000 " not in stderr


def test_tensorboard_events_exactly_when_tensorboard_is_installed(trained):
    import importlib.util

    out, _, _ = trained
    events = list((out / "tensorboard").glob("events.out.tfevents.*"))
    assert bool(events) == (importlib.util.find_spec("tensorboard") is not None)


def test_eval_only_writes_its_own_directory(trained):
    out, _, _ = trained
    before = {name: (out / name).read_bytes() for name in ("results.csv", "results.md", "per_seed.json", "config.yaml")}
    assert train.main(["--config", AGG, "--eval-only", str(out / "model.zip")] + _tiny()) == 0
    evals = sorted(out.glob("eval-*"))
    assert len(evals) == 1 and (evals[0] / "results.csv").exists()
    assert {name: (out / name).read_bytes() for name in before} == before  # the training run's results are untouched
    # deterministic PPO on the same seeds gives the same numbers as at the end of training
    first = json.loads((out / "per_seed.json").read_text())
    second = json.loads((evals[0] / "per_seed.json").read_text())
    assert first["ppo"] == second["ppo"] and first["scripted"] == second["scripted"]
    assert not (evals[0] / "model.zip").exists()
    # a second eval-only (same second or not) gets another directory
    assert train.main(["--config", AGG, "--eval-only", str(out / "checkpoints" / "ppo_512_steps.zip")] + _tiny("eval.n_seeds=1")) == 0
    assert len(sorted(out.glob("eval-*"))) == 2
    assert {name: (out / name).read_bytes() for name in before} == before


def test_eval_only_refuses_to_overwrite_without_force(trained, tmp_path, capsys):
    out, _, _ = trained
    target = tmp_path / "copy"
    target.mkdir()
    (target / "results.csv").write_text("keep me\n")
    args = ["--config", AGG, "--eval-only", str(out / "model.zip"), "--output", str(target)] + _tiny("eval.n_seeds=1")
    assert train.main(args) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "already holds results (results.csv)" in err and "--force" in err
    assert (target / "results.csv").read_text() == "keep me\n"
    assert train.main(args + ["--force"]) == 0
    assert (target / "results.csv").read_text().startswith("policy,metric,mean,ci_low,ci_high,n")
    md = (target / "results.md").read_text()
    assert "(n=1)" in md and "one seed: no confidence interval" in md


def _one_line_error(capsys, *needles: str) -> str:
    err = capsys.readouterr().err
    assert err.endswith("\n") and err.count("\n") == 1, err
    assert "Traceback" not in err
    for needle in needles:
        assert needle in err, (needle, err)
    return err


def test_output_dir_that_is_a_file_or_below_a_file(tmp_path, capsys):
    afile = tmp_path / "afile"
    afile.write_text("x")
    assert train.main(["--config", AGG, "--output", str(afile)] + _tiny()) == 2
    _one_line_error(capsys, "error: output directory", str(afile), "is a file")
    assert train.main(["--config", AGG, "--output", str(afile / "sub")] + _tiny()) == 2
    _one_line_error(capsys, "error: output directory", str(afile / "sub"), "not writable")
    assert afile.read_text() == "x"


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() == 0, reason="root may write into any directory")
def test_output_dir_not_writable(tmp_path, capsys):
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o500)
    try:
        assert train.main(["--config", AGG, "--output", str(locked / "run")] + _tiny()) == 2
    finally:
        locked.chmod(0o700)
    _one_line_error(capsys, "error: output directory", str(locked / "run"), "not writable")


@pytest.mark.skipif(not Path("/sys/kernel").is_dir(), reason="needs Linux sysfs (not writable even by root)")
def test_output_dir_on_a_read_only_filesystem(capsys):
    assert train.main(["--config", AGG, "--output", "/sys/kernel/swarm_envs_run"] + _tiny()) == 2
    _one_line_error(capsys, "error: output directory '/sys/kernel/swarm_envs_run' is not writable")


def test_eval_only_missing_checkpoint(tmp_path, capsys):
    missing = tmp_path / "nope.zip"
    assert train.main(["--config", AGG, "--eval-only", str(missing)] + _tiny()) == 2
    err = _one_line_error(capsys, f"error: checkpoint '{missing}' not found")
    assert "nope.zip.zip" not in err
    assert not list(tmp_path.iterdir())  # no eval directory left behind


@pytest.mark.parametrize("kind, problem", [
    ("truncated_end", "not a zip archive"),  # the zip directory at the end is gone
    ("truncated_half", "cannot be loaded as a PPO model"),  # SB3's zip holds zips (torch files): one may still be found
    ("text", "not a zip archive"),
    ("other_zip", "cannot be loaded as a PPO model"),
])
def test_eval_only_bad_checkpoint_files(trained, tmp_path, capsys, kind, problem):
    out, _, _ = trained
    bad = tmp_path / f"{kind}.zip"
    data = (out / "model.zip").read_bytes()
    if kind == "truncated_end":
        bad.write_bytes(data[:-10])
    elif kind == "truncated_half":
        bad.write_bytes(data[: len(data) // 2])
    elif kind == "text":
        bad.write_text("not a model\n")
    else:
        with zipfile.ZipFile(bad, "w") as zf:
            zf.writestr("hello.txt", "a zip, but not an SB3 model")
    assert train.main(["--config", AGG, "--eval-only", str(bad)] + _tiny()) == 2
    _one_line_error(capsys, f"error: checkpoint '{bad}'", problem)
    assert not list(tmp_path.glob("eval-*"))


def test_eval_only_checkpoint_for_another_observation_size(trained, capsys):
    out, _, _ = trained
    # 4 message bits add 4 action entries and message-bit observations: not the env the model was trained on
    assert train.main(["--config", AGG, "--eval-only", str(out / "model.zip")] + _tiny("env.message_bits=4")) == 2
    _one_line_error(capsys, f"error: checkpoint '{out / 'model.zip'}' expects observations of size 107",
                    "gives 143", "config.yaml")


def test_empty_sections_take_defaults(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text("task: flocking\nenv:\ntrain:\n  n_envs: 3\n")
    cfg = load_config(path)
    assert cfg["env"] == {} and cfg["train"]["n_envs"] == 3
    assert cfg["train"]["total_timesteps"] == DEFAULTS["train"]["total_timesteps"]


# -- --eval-only checks the model's run against the config ------------------------------------------------
FLOCKING = str(ROOT / "configs" / "flocking.yaml")


def _fake_run(trained_out: Path, folder: Path, **changes: dict) -> Path:
    """A copy of the trained model in ``folder`` beside its run's config.yaml with ``changes`` per section."""
    folder.mkdir()
    cfg = yaml.safe_load((trained_out / "config.yaml").read_text())
    for section, values in changes.items():
        cfg[section] = {**cfg[section], **values}
    (folder / "config.yaml").write_text(yaml.safe_dump(cfg))
    (folder / "model.zip").write_bytes((trained_out / "model.zip").read_bytes())
    return folder / "model.zip"


def test_eval_only_refuses_a_model_of_another_task(trained, tmp_path, capsys):
    """An aggregation model under flocking.yaml (same observation and action sizes): refused, naming both
    tasks and both configs; also for a checkpoint (its run config is beside checkpoints/)."""
    out, _, _ = trained
    for model in (out / "model.zip", out / "checkpoints" / "ppo_512_steps.zip"):
        assert train.main(["--config", FLOCKING, "--eval-only", str(model), "--output", str(tmp_path / "e")] + _tiny()) == 2
        _one_line_error(capsys, f"error: checkpoint '{model}' was trained on swarm_envs/Aggregation-v0 (its run config "
                                f"{out / 'config.yaml'}) but {FLOCKING} evaluates swarm_envs/Flocking-v0")
    assert not (tmp_path / "e").exists()


@pytest.mark.parametrize("changes, needles", [
    ({"env": {"platform": "droplet"}}, ["was trained on the droplet platform", "uses the epuck"]),
    # 10 x 7 neighbour rows + 2 x 13 message rows = 10 x 8 + 2 x 8: the same size, another layout
    ({"env": {"n_neighbours": 7, "n_messages": 13}}, ["was trained with observations messages 13x2", "range_bearing 7x7",
                                                      "gives observations messages 8x2", "range_bearing 8x7"]),
    ({"agent": {"action_repeat": 2}}, ["as the policy variant ppo+repeat2, agent.action_repeat=2 (its", "evaluates ppo, agent.action_repeat=1;"]),
])
def test_eval_only_refuses_a_model_whose_run_differs(trained, tmp_path, capsys, changes, needles):
    out, _, _ = trained
    model = _fake_run(out, tmp_path / "run", **changes)
    assert train.main(["--config", AGG, "--eval-only", str(model)] + _tiny()) == 2
    _one_line_error(capsys, f"error: checkpoint '{model}'", f"(its run config {tmp_path / 'run' / 'config.yaml'}", AGG, *needles)
    assert sorted(p.name for p in (tmp_path / "run").iterdir()) == ["config.yaml", "model.zip"]


def test_eval_only_without_a_run_config_checks_the_sizes(trained, tmp_path, capsys):
    """A model saved elsewhere (no config.yaml beside it) is evaluated if its sizes fit the config's env."""
    out, _, _ = trained
    (tmp_path / "bare").mkdir()
    model = tmp_path / "bare" / "model.zip"
    model.write_bytes((out / "model.zip").read_bytes())
    assert train.main(["--config", FLOCKING, "--eval-only", str(model)] + _tiny("eval.n_seeds=1")) == 0
    (results,) = (tmp_path / "bare").glob("eval-*/results.csv")
    assert "ppo,polarisation," in results.read_text()


def test_training_rate_starts_after_the_first_step(monkeypatch):
    """The logged rate (training_log.RATE_KEY) counts from the end of the first env step, where a cold numba cache
    compiles: 30 s of reset + first step (4 robots), then 63 steps in 0.63 s, action_repeat 2."""
    from stable_baselines3.common.logger import Logger

    now = [0.0]
    monkeypatch.setattr(training_log.time, "perf_counter", lambda: now[0])

    class Model:
        num_timesteps = 0
        logger = Logger(folder=None, output_formats=[])

        def get_env(self):
            return None

    model = Model()
    cb = training_log.rate_callback(repeat=2)
    cb.init_callback(model)
    cb.on_training_start({}, {})
    now[0], model.num_timesteps = 30.0, 4  # reset and first step, compiling
    cb.on_step()
    for _ in range(63):
        now[0] += 0.01
        model.num_timesteps += 4
        cb.on_step()
    cb.on_rollout_end()
    rate = model.logger.name_to_value[training_log.RATE_KEY]
    assert rate == pytest.approx(252 * 2 / 0.63)  # robot-steps after the first step / seconds after it
    assert rate > 40 * (256 * 2 / now[0])  # SB3's time/fps definition (from the start of learn) gives ~17


def test_progress_bar_setting(monkeypatch, tmp_path):
    """train.progress_bar: "auto" (the default) draws bars only when stderr is a terminal; true/false as given."""
    from swarm_envs.agents.config import progress_bar_on

    assert DEFAULTS["train"]["progress_bar"] == "auto"

    class Stream:
        def __init__(self, tty):
            self.tty = tty

        def isatty(self):
            return self.tty

    monkeypatch.setattr("sys.stderr", Stream(False))
    assert progress_bar_on("auto") is False and progress_bar_on(True) is True
    monkeypatch.setattr("sys.stderr", Stream(True))
    assert progress_bar_on("auto") is True and progress_bar_on(False) is False
    monkeypatch.undo()
    for value in ("auto", "true", "false"):
        assert load_config(AGG, [f"train.progress_bar={value}"])["train"]["progress_bar"] in ("auto", True, False)
    for value in ("sometimes", "1", "0"):
        with pytest.raises(ConfigError, match="'train.progress_bar'"):
            load_config(AGG, [f"train.progress_bar={value}"])
