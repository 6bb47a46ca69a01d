"""train.py never changes a run on disk by a failed or interrupted command: the whole config and every
``--set`` are checked before anything is written, a directory holding a run is refused without ``--force``,
files are staged beside the output and moved in at the end, and every failure (a full disk included) is one
line naming the key or the path, exit code 2."""

from __future__ import annotations

import errno
import os
from pathlib import Path

import pytest

from swarm_envs.agents import train

ROOT = Path(__file__).resolve().parents[1]
AGG = str(ROOT / "configs" / "aggregation.yaml")
TINY = [
    "env.sensing=ideal",
    "env.n_robots=4",
    "env.max_cycles=20",
    "train.total_timesteps=256",
    "train.n_envs=1",
    "train.checkpoint_freq=0",
    "train.progress_bar=false",
    "agent.n_steps=64",
    "agent.batch_size=128",
    "agent.n_epochs=1",
    "eval.n_seeds=1",
]


def _sets(*overrides: str) -> list[str]:
    return [x for o in (*TINY, *overrides) for x in ("--set", o)]


def _one_line(capsys, *needles: str) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    for needle in needles:
        assert needle in err, (needle, err)
    return err


def _snapshot(folder: Path) -> dict[str, tuple[bytes, int]]:
    """Every file under ``folder``: (bytes, mtime in ns)."""
    return {str(p.relative_to(folder)): (p.read_bytes(), p.stat().st_mtime_ns) for p in sorted(folder.rglob("*")) if p.is_file()}


def _old_run(out: Path) -> dict[str, tuple[bytes, int]]:
    out.mkdir(parents=True)
    for name, data in {"config.yaml": "seed: 1\n", "model.zip": "old model", "results.csv": "policy,metric\nold,1\n",
                       "episode.gif": "old gif", "notes.txt": "mine\n"}.items():
        (out / name).write_text(data)
    (out / "eval-20250101-000000").mkdir()
    (out / "eval-20250101-000000" / "results.csv").write_text("old eval\n")
    return _snapshot(out)


BINARY = b"\x89PNG\r\n\x1a\n\x00\x00\xff\xfe\x00"


@pytest.mark.parametrize(
    "config, overrides, key",
    [
        (None, ["seed=4294967296"], "'seed' must be an integer in [0, 4294967295]"),
        (None, ["agent.learning_rate=.inf"], "'agent.learning_rate' must be a finite number"),
        (None, ["agent.reward_scale=.inf"], "'agent.reward_scale'"),
        (None, ["agent.log_std_init=.nan"], "'agent.log_std_init'"),
        (None, ["agent.n_steps=1000000000"], "'agent.n_steps'"),
        (None, ["agent.n_steps=1000000", "train.n_envs=16"], "'agent.n_steps': the PPO rollout"),
        (None, ["train.torch_threads=1000000"], "'train.torch_threads'"),
        (None, ["agent.scripted_kwargs.bogus=1"], "takes no keyword argument(s) ['bogus']"),
        (None, ["train=5"], "config key 'train' must be a mapping"),
        (None, ["agent=null"], "config key 'agent' must be a mapping"),
        (None, ["env=[1, 2]"], "config key 'env' must be a mapping"),
        (None, ["agent.net_arch=[1000000]"], "'agent.net_arch'"),
        (None, ["train.n_envs=100000"], "'train.n_envs'"),
        (None, ["env.n_robots=14", "env.arena_size=0.27"], "at most 12 fit"),
        ("task: [flocking]\n", [], "config key 'task'"),
        ("task: flocking\nenv: {1: a, foo: b}\n", [], "config key 'env' has a key 1 that is not a string"),
        ("task: flocking\n3: 4\n", [], "unknown config key '3'"),
        (BINARY, [], "is not a text (UTF-8 YAML) file"),
        ("task: flocking\nenv: {a: [}\n", [], "is not valid YAML"),
    ],
)
@pytest.mark.parametrize("eval_only", [False, True], ids=["train", "eval-only"])
def test_bad_config_is_one_line_and_writes_nothing(tmp_path, capsys, config, overrides, key, eval_only):
    path = AGG
    if config is not None:
        path = tmp_path / "bad.yaml"
        path.write_bytes(config) if isinstance(config, bytes) else path.write_text(config)
    out = tmp_path / "out"
    before = sorted(tmp_path.iterdir())
    args = ["--config", str(path), "--output", str(out)] + _sets(*overrides)
    if eval_only:  # the config is checked before the checkpoint (which does not exist) is even looked at
        args += ["--eval-only", str(tmp_path / "missing.zip")]
    assert train.main(args) == 2
    err = _one_line(capsys, "config error: ", key)
    assert "missing.zip" not in err
    assert sorted(tmp_path.iterdir()) == before  # nothing written


def test_rerun_into_a_used_directory_refuses_before_touching_anything(tmp_path, capsys):
    out = tmp_path / "run"
    before = _old_run(out)
    assert train.main(["--config", AGG, "--output", str(out)] + _sets("seed=4294967296")) == 2
    _one_line(capsys, "config key 'seed'")
    assert train.main(["--config", AGG, "--output", str(out)] + _sets()) == 2
    _one_line(capsys, f"error: output directory '{out}' already holds a run", "--force")
    assert _snapshot(out) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]  # no staging directory left


def test_force_replaces_the_old_run_as_a_whole(tmp_path, capsys):
    out = tmp_path / "run"
    _old_run(out)
    assert train.main(["--config", AGG, "--output", str(out), "--force"] + _sets()) == 0
    names = sorted(p.name for p in out.iterdir())
    assert "episode.gif" not in names and "eval-20250101-000000" not in names  # nothing of the old run survives
    assert (out / "notes.txt").read_text() == "mine\n"  # a file that is not part of a run stays
    assert (out / "model.zip").read_bytes() != b"old model" and (out / "results.csv").read_text().startswith("policy,metric,mean")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]


def test_disk_full_while_saving_the_model(tmp_path, capsys, monkeypatch):
    from stable_baselines3 import PPO

    def full_disk(self, path, *args, **kwargs):
        Path(path).write_bytes(b"PK\x03\x04 truncated")  # a partial file, as a full disk leaves
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(PPO, "save", full_disk)
    out = tmp_path / "run"
    before = _old_run(out)
    assert train.main(["--config", AGG, "--output", str(out), "--force"] + _sets()) == 2
    _one_line(capsys, f"error: could not write '{out / 'model.zip'}': No space left on device")
    assert _snapshot(out) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]  # the staging directory (no model) is removed


def test_disk_full_while_writing_results_keeps_the_old_run_and_the_new_model(tmp_path, capsys, monkeypatch):
    def full_disk(rows, path):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))

    monkeypatch.setattr(train, "write_csv", full_disk)
    out = tmp_path / "run"
    before = _old_run(out)
    assert train.main(["--config", AGG, "--output", str(out), "--force"] + _sets()) == 2
    err = _one_line(capsys, f"error: could not write '{out / 'results.csv'}': No space left on device", "the trained model is kept in")
    assert _snapshot(out) == before
    kept = [p for p in tmp_path.iterdir() if p.name != "run"]
    assert len(kept) == 1 and str(kept[0]) in err and (kept[0] / "model.zip").is_file()
    assert not list(kept[0].glob(".tmp-*"))  # no half-written file


def test_output_inside_the_evaluated_run_is_refused(tmp_path, capsys):
    out = tmp_path / "run"
    out.mkdir()
    (out / "model.zip").write_text("x")
    assert train.main(["--config", AGG, "--eval-only", str(out / "model.zip"), "--output", str(out), "--force"] + _sets()) == 2
    _one_line(capsys, "holds the checkpoint being evaluated")
    assert (out / "model.zip").read_text() == "x"


def _staged(out: Path, text: str) -> train.Staging:
    stage = train.Staging(out)
    (stage.path / "config.yaml").write_text(text)
    (stage.path / "model.zip").write_text(f"model of {text}")
    return stage


def test_two_runs_into_one_new_output_both_stay_on_disk(tmp_path):
    """Two runs that both passed the output check (it was empty then) publish one after the other: the first
    takes the output, the second keeps its run under the next free name; neither is deleted."""
    out = tmp_path / "run"
    first, second = _staged(out, "first"), _staged(out, "second")
    assert first.publish() == out
    assert second.publish() == tmp_path / "run.2"
    assert (out / "config.yaml").read_text() == "first" and (out / "model.zip").read_text() == "model of first"
    assert (tmp_path / "run.2" / "config.yaml").read_text() == "second"
    assert not first.path.name.endswith(".partial") and not list(tmp_path.glob(".*.partial"))


def test_a_run_into_an_existing_directory_claims_it_once(tmp_path):
    """An existing directory without a run (files of the user's) is claimed by the first run to finish."""
    out = tmp_path / "run"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    first, second, third = _staged(out, "first"), _staged(out, "second"), _staged(out, "third")
    assert first.publish() == out
    assert second.publish() == tmp_path / "run.2"
    assert third.publish() == tmp_path / "run.3"
    assert (out / "notes.txt").read_text() == "mine" and (out / "config.yaml").read_text() == "first"
    assert (out / "model.zip").read_text() == "model of first"


def test_force_still_replaces_at_publish(tmp_path):
    out = tmp_path / "run"
    _staged(out, "first").publish()
    assert _staged(out, "second").publish(replace=True) == out
    assert (out / "config.yaml").read_text() == "second" and not (tmp_path / "run.2").exists()


# -- a task that cannot be evaluated fails before training ------------------------------------------------
class _GhostMetric:
    """A user's task whose METRICS declares a metric ('ghost') that its rewards() never returns."""

    @staticmethod
    def register() -> str:
        import numpy as np

        import swarm_envs
        from swarm_envs.task import Task

        class Ghost(Task):
            METRICS = {"spread": "mean", "ghost": "final"}
            HEADLINE = ("ghost", 1)

            def rewards(self, state, first):
                spread = self.agents_of(state.positions).std(axis=(1, 2))
                return np.zeros((self.n_copies, self.n_agents)), {}, {"spread": spread}

        swarm_envs.register("tests/Ghost-v0", Ghost)
        return "tests/Ghost-v0"


def test_a_task_that_cannot_be_evaluated_fails_before_training(tmp_path, capsys, forget_registered_ids):
    """One short evaluation episode per policy runs before training, through the final evaluation and its
    table: a declared metric the env never reports fails in seconds (the budget here would take hours),
    with one line naming the metric, and writes nothing."""
    import time

    task = _GhostMetric.register()
    t0 = time.perf_counter()
    code = train.main(["--config", AGG, "--output", str(tmp_path / "run")]
                      + _sets(f"task={task}", "agent.scripted=null", "train.total_timesteps=100000000"))
    seconds = time.perf_counter() - t0
    assert code == 2
    _one_line(capsys, "error: the evaluation check before training failed (a 3-step episode of 'ppo')",
              f"task {task} declares the metric(s) 'ghost' in METRICS, but its env reports only 'spread'")
    assert seconds < 60, seconds
    assert sorted(tmp_path.iterdir()) == []  # nothing written, no staging directory left


def test_the_evaluation_names_a_declared_metric_the_env_does_not_report(forget_registered_ids):
    from swarm_envs.agents.evaluation import evaluate, make_env, random_factory, run_episode

    task = _GhostMetric.register()
    with pytest.raises(ValueError, match=r"declares the metric\(s\) 'ghost' in METRICS, but its env reports only 'spread'"):
        evaluate(task, {"n_robots": 3, "sensing": "ideal", "max_cycles": 2}, random_factory, [0])
    env = make_env(task, n_robots=3, sensing="ideal", max_cycles=2)
    with pytest.raises(ValueError, match="'ghost'"):
        run_episode(env, random_factory(env), 0, task)
