"""train.py never changes a run on disk by a failed or interrupted command: the whole config and every
``--set`` are checked before anything is written, a directory holding a run is refused without ``--force``,
files are staged beside the output and moved in at the end, and every failure (a full disk included) is one
line naming the key or the path, exit code 2."""

from __future__ import annotations

import errno
import os
from pathlib import Path

import pytest

from swarm_envs.agents import staging, train

ROOT = Path(__file__).resolve().parents[2]
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


def _staged(out: Path, text: str) -> staging.Staging:
    stage = staging.Staging(out)
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
        from swarm_envs.tasks.task import Task

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
    _one_line(capsys, f"error: the evaluation check before training failed (a 3-step episode of 'ppo' on {task})",
              "metric 'ghost' declared in Ghost.METRICS is missing from the returned metrics ['spread']")
    assert seconds < 60, seconds
    assert sorted(tmp_path.iterdir()) == []  # nothing written, no staging directory left


def test_the_evaluation_names_a_declared_metric_the_env_does_not_report(forget_registered_ids):
    from swarm_envs.agents.evaluation import evaluate, make_env, random_factory, run_episode

    task = _GhostMetric.register()
    with pytest.raises(ValueError, match=r"metric 'ghost' declared in Ghost.METRICS is missing from the returned metrics \['spread'\]"):
        evaluate(task, {"n_robots": 3, "sensing": "ideal", "max_cycles": 2}, random_factory, [0])
    env = make_env(task, n_robots=3, sensing="ideal", max_cycles=2)
    with pytest.raises(ValueError, match="'ghost'"):
        run_episode(env, random_factory(env), 0, task)


# -- staging directories that a killed run leaves ---------------------------------------------------------
def _dead_pid() -> int:
    import subprocess
    import sys

    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def _leftover(parent: Path, name: str, age_s: float = 0.0, model: bool = False) -> Path:
    path = parent / name
    path.mkdir(parents=True)
    (path / "config.yaml").write_text("seed: 0\n")
    if model:
        (path / "model.zip").write_text("model")
    if age_s:
        for p in (path / "config.yaml", path / "model.zip", path):
            if p.exists():
                os.utime(p, (p.stat().st_atime, p.stat().st_mtime - age_s))
    return path


def test_staging_directories_carry_their_process_id(tmp_path):
    import re

    stage = staging.Staging(tmp_path / "run")
    assert re.fullmatch(rf"\.run\.{os.getpid()}-[a-z0-9_]{{8}}\.partial", stage.path.name), stage.path.name
    (found,) = staging.staging_dirs(tmp_path / "run")
    assert found.path == stage.path and found.pid == os.getpid() and found.owner_running and not found.has_model


def test_a_run_reports_the_staging_directories_left_for_its_output(tmp_path, capsys, monkeypatch):
    """At its start, a run names each staging directory of its output that a killed run left (path, age,
    whether it holds a model) and how to list or remove them; one another process is writing is named as such."""
    import subprocess
    import sys

    dead = _leftover(tmp_path, f".run.{_dead_pid()}-abcdefgh.partial", age_s=7200, model=True)
    old = _leftover(tmp_path, ".run.zyxwvuts.partial", age_s=3 * 86400)  # a name without a process id
    _leftover(tmp_path, f".other.{_dead_pid()}-abcdefgh.partial")  # another output's: not reported
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        live = _leftover(tmp_path, f".run.{sleeper.pid}-abcdefgh.partial")

        def stop(self, out):
            raise staging.TrainError("stopped before writing")

        monkeypatch.setattr(staging.Staging, "__init__", stop)
        assert train.main(["--config", AGG, "--output", str(tmp_path / "run")] + _sets()) == 2
    finally:
        sleeper.kill()
        sleeper.wait()
    lines = capsys.readouterr().err.splitlines()
    assert lines[-1] == "error: stopped before writing"
    notes = lines[:-1]
    assert len(notes) == 3, notes
    assert notes[0].startswith(f"note: staging directory left by an earlier run of {tmp_path / 'run'}: {old} (3.0 days old)")
    assert notes[1].startswith(f"note: staging directory left by an earlier run of {tmp_path / 'run'}: {dead} (2.0 h old, holds a trained model)")
    assert notes[1].endswith(f"list or remove such directories with: python train.py --list-partial / --clean-partial {tmp_path / 'run'}")
    assert notes[2] == f"note: process {sleeper.pid} is also writing a run for {tmp_path / 'run'}: {live} (0 s old, in use by process {sleeper.pid})"


def test_list_and_clean_partial(tmp_path, capsys):
    """--list-partial DIR lists the staging directories of the output DIR and of the outputs in DIR;
    --clean-partial DIR removes those whose process no longer runs (a name without a process id: an hour
    after its last write) and keeps the others; neither touches anything else."""
    runs = tmp_path / "runs"
    (runs / "a").mkdir(parents=True)
    (runs / "a" / "model.zip").write_text("a finished run")
    dead = _leftover(runs, f".a.{_dead_pid()}-abcdefgh.partial", age_s=600, model=True)
    old = _leftover(runs, ".b.zyxwvuts.partial", age_s=7200)
    recent = _leftover(runs, ".b.qwertyui.partial", age_s=300)  # no process id, written 5 min ago: may be in use
    mine = staging.Staging(runs / "c").path  # this process's
    beside = _leftover(tmp_path, f".runs.{_dead_pid()}-abcdefgh.partial")  # of the output "runs" itself
    other = _leftover(runs, "not-staging.partial")

    assert train.main(["--list-partial", str(runs)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[-1] == f"5 staging directories, 3 not in use; remove those with: python train.py --clean-partial {runs}"
    assert out[0].startswith(f"{old} (2.0 h old)") and f"{dead} (10 min old, holds a trained model)" in out
    assert f"{recent} (5 min old, written less than an hour ago: may be in use)" in out
    assert any(line.startswith(f"{mine} (") and line.endswith(f"in use by process {os.getpid()})") for line in out)
    assert any(line.startswith(f"{beside} (") for line in out)

    assert train.main(["--clean-partial", str(runs)]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[-1] == "removed 3 of 5 staging directories"
    assert not dead.exists() and not old.exists() and not beside.exists()
    assert recent.is_dir() and mine.is_dir() and other.is_dir() and (runs / "a" / "model.zip").is_file()
    assert f"kept {mine} (" in out

    assert train.main(["--list-partial", str(tmp_path / "nothing")]) == 0
    assert capsys.readouterr().out == f"no staging directories for {tmp_path / 'nothing'}\n"


@pytest.mark.parametrize("argv, message", [
    (["--clean-partial", "x", "--force"], "--clean-partial takes no other option, got --force"),
    (["--list-partial", "x", "--set", "seed=1"], "--list-partial takes no other option, got --set"),
    (["--list-partial", " "], "--list-partial needs an output directory"),
    (["--config", AGG, "--clean-partial", "x"], "not allowed with argument --config"),
    ([], "one of the arguments --config --list-partial --clean-partial is required"),
])
def test_partial_options_are_one_line_usage_errors(argv, message, capsys):
    with pytest.raises(SystemExit) as exit_:
        train.main(argv)
    assert exit_.value.code == 2
    _one_line(capsys, "train.py: error: ", message)
