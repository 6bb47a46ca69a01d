"""Ctrl-C during ``python train.py``: the current model and the resolved config are saved, and the command
exits with code 130 and a one-line message (no traceback, also with worker processes, and also while the
modules load). Runs train.py in a subprocess and sends SIGINT. An interrupted command never changes a run
on disk: into a new output directory the partial run is published; with ``--force`` over an old run, the
old run stays as it was and the partial run stays in its staging directory, which the message names."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from swarm_envs.agents.config import load_config

ROOT = Path(__file__).resolve().parents[2]
TINY = [
    "env.sensing=ideal",
    "env.n_robots=4",
    "env.max_cycles=20",
    "train.total_timesteps=10000000",  # far more than the test waits for
    "train.n_envs=2",
    "train.checkpoint_freq=0",
    "train.progress_bar=false",
    "agent.n_steps=64",
    "agent.batch_size=128",
    "agent.n_epochs=1",
]


def _rows(path: Path) -> int:
    try:
        return len(path.read_text().splitlines())
    except FileNotFoundError:
        return 0


def _own_group_default_sigint() -> None:
    """In the child: its own process group (so Ctrl-C can reach it and its workers together) and SIGINT's
    default action."""
    os.setpgrp()
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _interrupt_lines(proc: subprocess.Popen, stdout: str, stderr: str) -> list[str]:
    """The interrupted command's stderr lines, after checking it exited with 130 and said one line."""
    assert proc.returncode == 130, (stdout, stderr)
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in stderr, stderr
    return lines


def _old_run(out: Path) -> dict[str, bytes]:
    """A fake earlier run in ``out`` (with a user's file beside it); returns its files' bytes."""
    out.mkdir(parents=True)
    files = {"config.yaml": b"seed: 1\n", "model.zip": b"old model", "results.csv": b"policy,metric\nold,1\n",
             "progress.csv": b"old\n", "notes.txt": b"mine\n"}
    for name, data in files.items():
        (out / name).write_bytes(data)
    return files


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to a child process is POSIX")
@pytest.mark.parametrize("n_workers, over_old_run", [(1, False), pytest.param(2, True, marks=pytest.mark.slow)])  # slow: .ci/run's slow step
def test_ctrl_c_saves_model_and_config(tmp_path, n_workers, over_old_run):
    from stable_baselines3 import PPO

    out = tmp_path / "run"
    old = _old_run(out) if over_old_run else {}
    cmd = [sys.executable, str(ROOT / "train.py"), "--config", str(ROOT / "configs" / "aggregation.yaml"), "--output", str(out), "--force"]
    cmd += [x for o in TINY + [f"train.n_workers={n_workers}"] for x in ("--set", o)]
    env = {**os.environ, "PYTHONUNBUFFERED": "1", "PYTHONPATH": str(ROOT)}
    # a shell starts background jobs with SIGINT ignored, and children inherit that: give the child the default
    proc = subprocess.Popen(cmd, cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=_own_group_default_sigint)
    try:
        deadline = time.monotonic() + 180
        # training has started once PPO has logged two iterations (header + 2 rows of progress.csv), in the
        # staging directory beside the output
        while max([_rows(p) for p in tmp_path.glob(".run.*.partial/progress.csv")] or [0]) < 3:
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < deadline, "training did not start within 180 s"
            time.sleep(0.2)
        assert {name: (out / name).read_bytes() for name in old} == old  # the old run is untouched meanwhile
        # Ctrl-C in a terminal reaches the whole foreground process group: the trainer and its workers
        os.killpg(proc.pid, signal.SIGINT) if n_workers > 1 else proc.send_signal(signal.SIGINT)
        stdout, stderr = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    lines = _interrupt_lines(proc, stdout, stderr)
    assert lines[0].startswith("interrupted by Ctrl-C after ")
    if over_old_run:  # the finished run is kept as it was; the partial one waits in its staging directory
        assert {name: (out / name).read_bytes() for name in old} == old
        (saved,) = tmp_path.glob(".run.*.partial")
        assert f"the run in {out} is kept" in lines[0] and str(saved) in lines[0]
    else:
        saved = out
        assert str(out / "model.zip") in lines[0] and str(out / "config.yaml") in lines[0]
        assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]  # no staging directory left
    model = PPO.load(saved / "model.zip", device="cpu")
    assert 512 <= model.num_timesteps < 10_000_000
    cfg = load_config(saved / "config.yaml")  # the resolved config is a valid config again
    assert cfg["train"]["total_timesteps"] == 10_000_000 and cfg["agent"]["scripted"] == "swarm_envs.agents.scripted:BearingAggregation"
    assert json.loads((saved / "timing.json").read_text())["interrupted"] is True
    assert not (saved / "results.csv").exists()


@pytest.mark.slow  # three train.py starts, each interrupted at a timed moment
@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to a child process is POSIX")
def test_ctrl_c_while_the_modules_load_is_one_line(tmp_path):
    """SIGINT at several moments of the start (imports of numpy, the package, torch): one line, exit 130."""
    cmd = [sys.executable, str(ROOT / "train.py"), "--config", str(ROOT / "configs" / "aggregation.yaml"), "--output", str(tmp_path / "run")]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    for delay in (0.3, 0.8, 1.5):
        proc = subprocess.Popen(cmd, cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                preexec_fn=_own_group_default_sigint)
        time.sleep(delay)
        proc.send_signal(signal.SIGINT)
        _, stderr = proc.communicate(timeout=120)
        assert proc.returncode == 130 and len(stderr.strip().splitlines()) == 1 and "Traceback" not in stderr, (delay, stderr)
        assert stderr.startswith("interrupted by Ctrl-C"), stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == []  # nothing written


def _ctrl_c_in_compiled_code(levels: int = 1):
    """The SystemError CPython raises when Ctrl-C arrives in a Python call made from compiled code (numba's
    ``_numba_unpickle``): one per C level between the handler and the caller, each caused by the one below."""
    if levels == 0:
        raise KeyboardInterrupt
    try:
        _ctrl_c_in_compiled_code(levels - 1)
    except (KeyboardInterrupt, SystemError) as inner:
        raise SystemError("CPUDispatcher(<function kernel>) returned a result with an exception set") from inner


def test_ctrl_c_surfacing_as_a_systemerror_is_an_interrupt(monkeypatch, capsys):
    from swarm_envs.agents import signals, train

    with pytest.raises(SystemError) as caught:
        _ctrl_c_in_compiled_code()
    assert signals.is_interrupt(caught.value) and signals.is_interrupt(KeyboardInterrupt())
    for levels in (2, 3, 4):  # as measured: up to four SystemErrors above the KeyboardInterrupt
        with pytest.raises(SystemError) as caught:
            _ctrl_c_in_compiled_code(levels)
        assert signals.is_interrupt(caught.value)
    try:  # a SystemError caused by another error is not Ctrl-C
        raise SystemError("a real bug") from ValueError("cause")
    except SystemError as err:
        assert not signals.is_interrupt(err)
    assert not signals.is_interrupt(SystemError("something else")) and not signals.is_interrupt(ValueError())
    monkeypatch.setattr(train, "_run", lambda args, state: _ctrl_c_in_compiled_code())
    assert train.main(["--config", str(ROOT / "configs" / "aggregation.yaml")]) == 130
    assert capsys.readouterr().err.startswith("interrupted by Ctrl-C before training started")

    def other_error(args, state):
        raise SystemError("a real bug")

    monkeypatch.setattr(train, "_run", other_error)  # not an interrupt: an unexpected error, still one line
    assert train.main(["--config", str(ROOT / "configs" / "aggregation.yaml")]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "unexpected SystemError during setup: a real bug" in err


class SignalInFinalizer:
    """An object whose finalizer sends this process SIGINT: the handler runs inside ``__del__``, where a
    raised KeyboardInterrupt is printed and dropped (as in pymunk's cffi finalizers)."""

    def __del__(self) -> None:
        os.kill(os.getpid(), signal.SIGINT)
        for _ in range(10_000):  # Python runs the handler between these bytecodes, inside __del__
            pass


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to this process is POSIX")
def test_the_first_ctrl_c_stops_training_and_is_never_dropped():
    """The first Ctrl-C only asks training to stop (the callback then ends SB3's learn), so it is not lost
    when it lands in a finalizer, where a KeyboardInterrupt is printed and dropped (pymunk frees its bodies
    in cffi finalizers); a second Ctrl-C raises; afterwards Ctrl-C is ignored until the save is done."""
    pytest.importorskip("stable_baselines3")
    from swarm_envs.agents.signals import CtrlC

    ctrl_c = CtrlC()
    stop = ctrl_c.callback()
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with ctrl_c.installed():
            SignalInFinalizer()  # dropped at once: the signal arrives in its finalizer
            assert ctrl_c.requested and stop._on_step() is False
            with pytest.raises(KeyboardInterrupt):
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(1.0)
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGINT, previous)


# -- Ctrl-C after training: the trained model is published ------------------------------------------------
QUICK = [o for o in TINY if not o.startswith("train.total_timesteps")] + ["train.total_timesteps=256", "train.n_workers=1"]


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to a child process is POSIX")
def test_ctrl_c_at_the_start_of_evaluation_publishes_the_trained_model(tmp_path):
    """SIGINT as soon as train.py says it starts evaluating (its ``evaluating ...`` line; the evaluation then
    runs far longer than the signal takes to arrive): exit 130, one line, the trained model, config and
    learning curve published into --output, no results, no staging directory left."""
    from stable_baselines3 import PPO

    out = tmp_path / "run"
    # 20 seeds of 20000 steps per policy: minutes, unless Ctrl-C stops them
    overrides = QUICK + ["eval.max_cycles=20000", "eval.n_seeds=20"]
    cmd = [sys.executable, str(ROOT / "train.py"), "--config", str(ROOT / "configs" / "aggregation.yaml"), "--output", str(out)]
    cmd += [x for o in overrides for x in ("--set", o)]
    env = {**os.environ, "PYTHONUNBUFFERED": "1", "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen(cmd, cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=_own_group_default_sigint)
    try:
        seen = []
        for line in proc.stdout:  # blocks until the marker line (or the end of the output)
            seen.append(line)
            if line.startswith("evaluating "):
                proc.send_signal(signal.SIGINT)
                break
        assert seen and seen[-1].startswith("evaluating ppo, scripted, random on 20 seeds"), seen
        stdout, stderr = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    lines = _interrupt_lines(proc, stdout, stderr)
    assert lines[0].startswith(f"interrupted by Ctrl-C during evaluation: saved the trained model to {out / 'model.zip'} "
                               f"and the config to {out / 'config.yaml'}; no results"), lines[0]
    assert f"--eval-only {out / 'model.zip'}" in lines[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]  # published: no staging directory left
    assert {"config.yaml", "model.zip", "progress.csv", "learning_curve.png", "timing.json"} <= {p.name for p in out.iterdir()}
    assert not [name for name in train_results() if (out / name).exists()]
    timing = json.loads((out / "timing.json").read_text())
    assert timing["interrupted"] is True and "eval_s" not in timing
    assert PPO.load(out / "model.zip", device="cpu").num_timesteps == timing["robot_steps"] == 512  # one whole rollout


def train_results() -> tuple[str, ...]:
    from swarm_envs.agents.staging import RESULT_FILES

    return (*RESULT_FILES, "results.png")


def _quick_args(out: Path, *extra: str) -> list[str]:
    return ["--config", str(ROOT / "configs" / "aggregation.yaml"), "--output", str(out), *extra] + [
        x for o in QUICK + ["eval.n_seeds=2"] for x in ("--set", o)]


def test_ctrl_c_as_a_systemerror_during_evaluation_keeps_the_trained_model(tmp_path, monkeypatch, capsys):
    """Ctrl-C surfacing from numba-compiled code as a chain of SystemErrors during the evaluation: exit 130
    and the trained model published; over a finished run (--force) the finished run stays as it was and the
    trained model stays in the staging directory, which the line names."""
    from swarm_envs.agents import train

    real = train.evaluate

    def interrupted(task, env_kwargs, *args, **kwargs):
        if env_kwargs["max_cycles"] == train.CHECK_STEPS:  # the check before training runs as usual
            return real(task, env_kwargs, *args, **kwargs)
        _ctrl_c_in_compiled_code(3)

    monkeypatch.setattr(train, "evaluate", interrupted)
    out = tmp_path / "run"
    assert train.main(_quick_args(out)) == 130
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"interrupted by Ctrl-C during evaluation: saved the trained model to {out / 'model.zip'}")
    assert (out / "model.zip").is_file() and not (out / "results.csv").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]

    old = tmp_path / "old"
    files = _old_run(old)
    assert train.main(_quick_args(old, "--force")) == 130
    err = capsys.readouterr().err
    (staged,) = tmp_path.glob(".old.*.partial")
    assert err.count("\n") == 1 and f"the run in {old} is kept" in err and str(staged) in err and "(no results)" in err
    assert {name: (old / name).read_bytes() for name in files} == files
    assert (staged / "model.zip").is_file() and json.loads((staged / "timing.json").read_text())["interrupted"] is True


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to this process is POSIX")
def test_ctrl_c_is_honoured_at_the_next_evaluation_step(tmp_path, monkeypatch, capsys):
    """The first Ctrl-C during the evaluation only sets a flag, which the evaluated policies check at every
    step (so it is never dropped in a finalizer); during the check before training it stops the command
    with nothing saved. Ctrl-C is restored to its handler afterwards."""
    from swarm_envs.agents import train

    real = train.evaluate

    def ctrl_c_in(check: bool):
        def evaluate(task, env_kwargs, *args, **kwargs):
            if (env_kwargs["max_cycles"] == train.CHECK_STEPS) == check:
                os.kill(os.getpid(), signal.SIGINT)  # the handler runs at once and only sets the flag
            return real(task, env_kwargs, *args, **kwargs)

        return evaluate

    # Python's own Ctrl-C handler, whatever an earlier test or library left installed (the command installs
    # its handler over a handler, never where Ctrl-C is ignored)
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        monkeypatch.setattr(train, "evaluate", ctrl_c_in(check=False))
        out = tmp_path / "run"
        assert train.main(_quick_args(out)) == 130
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and err.startswith("interrupted by Ctrl-C during evaluation: saved the trained model to")
        assert (out / "model.zip").is_file() and sorted(p.name for p in tmp_path.iterdir()) == ["run"]
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler

        monkeypatch.setattr(train, "evaluate", ctrl_c_in(check=True))
        assert train.main(_quick_args(tmp_path / "second")) == 130
        err = capsys.readouterr().err
        assert err == "interrupted by Ctrl-C while setting up training; nothing saved\n"
        assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    finally:
        signal.signal(signal.SIGINT, before)


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to this process is POSIX")
def test_ctrl_c_during_the_checks_is_never_dropped(tmp_path, monkeypatch, capsys):
    """Ctrl-C while the command checks its config and output, landing in a finalizer (where a raised
    KeyboardInterrupt is printed and dropped; pymunk frees its bodies in cffi finalizers): the command stops
    before writing anything, with one line and exit code 130, and Ctrl-C is restored to its handler."""
    from swarm_envs.agents import train

    real = train.report_staging_dirs

    def checks_with_a_finalizer(*args, **kwargs):
        SignalInFinalizer()  # dropped at once: the signal arrives in its finalizer
        return real(*args, **kwargs)

    monkeypatch.setattr(train, "report_staging_dirs", checks_with_a_finalizer)
    before = signal.signal(signal.SIGINT, signal.default_int_handler)  # Python's own handler, as in a terminal
    try:
        assert train.main(_quick_args(tmp_path / "run")) == 130
        assert capsys.readouterr().err == "interrupted by Ctrl-C before training started; nothing saved\n"
        assert list(tmp_path.iterdir()) == []
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    finally:
        signal.signal(signal.SIGINT, before)


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to the own process is POSIX")
def test_ctrl_c_is_noted_not_raised_while_the_modules_load():
    """note_ctrl_c (swarm_envs.agents.launch): Ctrl-C is noted instead of raised (a KeyboardInterrupt inside a
    compiled module's initialisation can abort the interpreter), until the returned handler is set again;
    an ignored Ctrl-C stays ignored."""
    from swarm_envs.agents.launch import note_ctrl_c

    original = signal.signal(signal.SIGINT, signal.default_int_handler)  # as in a terminal (the suite may run with it ignored)
    try:
        pressed, previous = note_ctrl_c()
        try:
            assert previous is signal.default_int_handler
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.01)  # the handler runs between bytecodes
            assert pressed == [signal.SIGINT]
        finally:
            signal.signal(signal.SIGINT, signal.default_int_handler)
        with pytest.raises(KeyboardInterrupt):  # restored: Ctrl-C raises again
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.01)
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        assert note_ctrl_c() == ([], None) and signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGINT, original)
