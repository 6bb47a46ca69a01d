"""Train one policy shared by all robots of a swarm task (PPO or RecurrentPPO, with the variant the ``agent``
section chooses: :mod:`swarm_envs.agents.policies`), then compare it with the scripted baseline and a random
policy on the task metrics.

    python train.py --config configs/aggregation.yaml [--output DIR [--force]] [--render] [--set key=value ...]
    python train.py --config configs/aggregation.yaml --eval-only CHECKPOINT [--output DIR [--force]]
    python train.py --config configs/aggregation.yaml --baselines-only [--output DIR [--force]]
    python train.py --list-partial DIR | --clean-partial DIR

Training writes into DIR (``output_dir`` of the config unless ``--output``): ``config.yaml`` (resolved),
checkpoints ``checkpoints/ppo_<steps>_steps.zip`` and ``model.zip``, the learning curve ``progress.csv``
(one row per PPO iteration: ``time/total_timesteps``, ``rollout/ep_rew_mean`` (mean per-robot episode return,
unscaled), ``rollout/ep_len_mean``, ``time/fps``, ``train/*`` losses) and ``learning_curve.png``, TensorBoard
event files in ``tensorboard/`` when the ``tensorboard`` package is installed, ``results.csv`` (columns
``policy,metric,mean,ci_low,ci_high,n``; policies ``ppo``, ``scripted``, ``random``), ``results.md``,
``results.png``, ``per_seed.json``, ``timing.json`` and, with ``--render``, ``episode.gif``.

The budget ``train.total_timesteps`` counts robot-steps; PPO collects whole rollouts of
``n_steps x n_envs x n_robots`` robot-steps, so the run does the budget rounded *up* to whole rollouts
(200000 -> 202240 with the default config); the progress bar and the log show that real total.

No run on disk is changed by a failed or interrupted command:

- the whole config and every ``--set`` are checked first (one-line ``config error`` naming the key, exit
  code 2), and so are the output directory and the checkpoint, before anything is written;
- before training, each policy runs one short episode through the evaluation and its results table
  (:func:`check_evaluation`), so a task that cannot be evaluated fails in seconds, not after the budget;
- a directory that already holds a run (any of :data:`RUN_ENTRIES`, or an ``eval-*`` directory) is refused
  unless ``--force`` is given;
- a command writes its files into a hidden staging directory beside DIR (``.DIR.<pid>-<random>.partial``;
  the learning curve and TensorBoard events can be watched there) and moves them into DIR only when it ends;
  with ``--force`` the old run's files are replaced together at that moment (other files in DIR are kept);
  without it, a run that finds DIR taken by another run that finished first keeps its files in ``DIR.2``
  (``DIR.3``, ...) and says so.
  Each file is written under a temporary name and renamed when complete.
- a failure (a full disk included) is a one-line ``error`` naming the path, exit code 2, and leaves DIR as
  it was; a staging directory that already holds a trained model is kept (the message names it), any
  other is removed;
- a run killed before it could publish leaves its staging directory: a run names those of its output at
  its start, and ``--list-partial DIR`` / ``--clean-partial DIR`` list them / remove those whose process
  no longer runs (:func:`staging_dirs`).

``--eval-only`` writes into ``eval-<UTC timestamp>/`` beside the checkpoint (in the run directory when the
checkpoint is in ``checkpoints/``), or into ``--output``, with the same rules (never the checkpoint's own
directory). The checkpoint's run (its ``config.yaml``) must have trained the config's task, platform,
observation and action spaces and policy variant (:func:`check_run_config`).

Ctrl-C during training saves the current model (``model.zip``), the learning curve and the resolved
config, moves them into DIR, then exits with code 130 and a one-line message; worker processes
(``train.n_workers``) ignore Ctrl-C and are closed by the trainer. Ctrl-C once the model is saved (during
the final evaluation) does the same with the trained model: it is published into DIR with its config and
learning curve (and the results, if all were written), and the line gives the ``--eval-only`` command that
evaluates it. An interrupted command never replaces a finished run: over one (``--force``) its files stay
in the staging directory, which the line names. Ctrl-C before training or during an ``--eval-only``
evaluation writes nothing.
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import importlib.util
import json
import math
import os
import re
import shutil
import signal
import sys
import tempfile
import threading
import time
import zipfile
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from swarm_envs.agents.base import Policy
from swarm_envs.agents.config import DEFAULTS, ConfigError, load_config, progress_bar_on, resolve
from swarm_envs.agents.tasks import env_id, headline, metric_reductions
from swarm_envs.agents.evaluation import (
    evaluate,
    make_env,
    markdown_table,
    random_factory,
    run_episode,
    summarise,
    write_csv,
)

__all__ = ["main", "TrainError", "Staging", "RUN_ENTRIES", "planned_timesteps", "load_checkpoint", "plot_learning_curve", "is_interrupt",
           "policy_factories", "report_text", "check_evaluation", "CHECK_STEPS", "check_run_config",
           "StagingDir", "staging_dirs", "report_staging_dirs", "clean_staging_dirs"]

#: exit code after Ctrl-C (128 + SIGINT), as shells report it
EXIT_INTERRUPTED = 130
#: exit code of bad input (config, output directory, checkpoint)
EXIT_BAD_INPUT = 2
RESULT_FILES = ("results.csv", "results.md", "per_seed.json")
#: the entries a run of train.py writes (besides ``eval-*`` directories): a directory holding any is a run
RUN_ENTRIES = ("config.yaml", "model.zip", "progress.csv", "learning_curve.png", "results.csv", "results.md",
               "results.png", "per_seed.json", "timing.json", "episode.gif", "checkpoints", "tensorboard")


class TrainError(Exception):
    """Bad input or a failed write found by train.py (output directory, checkpoint, disk); reported as one
    line, exit code 2."""


def run_entries(directory: Path) -> list[str]:
    """The names in ``directory`` that belong to a run (:data:`RUN_ENTRIES` and ``eval-*`` directories)."""
    try:
        names = sorted(p.name for p in directory.iterdir())
    except OSError:  # missing, or not a directory
        return []
    return [n for n in names if n in RUN_ENTRIES or (n.startswith("eval-") and (directory / n).is_dir())]


class Staging:
    """A hidden directory beside ``out`` that a command writes its files into; :meth:`publish` moves them
    into ``out`` at the end, so a run already in ``out`` changes only then, and only as a whole.

    Raises :class:`TrainError` if the directory cannot be made (``out`` is not writable)."""

    def __init__(self, out: Path) -> None:
        self.out = Path(os.path.abspath(out))  # "." or "runs/.." get a real name and parent
        try:
            self.out.parent.mkdir(parents=True, exist_ok=True)
            self.path = Path(tempfile.mkdtemp(prefix=f".{self.out.name}.{os.getpid()}-", suffix=".partial", dir=self.out.parent))
        except OSError as err:
            raise TrainError(f"output directory '{out}' is not writable: {err.strerror or err}") from None

    def final(self, path: Path) -> Path:
        """Where the staged ``path`` ends up in ``out``."""
        try:
            return self.out / Path(path).relative_to(self.path)
        except ValueError:
            return Path(path)

    @contextlib.contextmanager
    def writing(self, path: Path) -> Iterator[Path]:
        """Yield a temporary name beside ``path`` to write to; it becomes ``path`` only when the block ends
        without error. An ``OSError`` (a full disk) becomes a :class:`TrainError` naming the file."""
        tmp = path.with_name(f".tmp-{os.getpid()}-{path.name}")  # keeps the suffix: writers pick the format by it
        try:
            yield tmp
            os.replace(tmp, path)
        except OSError as err:
            with contextlib.suppress(OSError):
                tmp.unlink()
            raise TrainError(f"could not write '{self.final(path)}': {err.strerror or err}") from None

    def publish(self, replace: bool = False) -> Path:
        """Move the staged files into ``out`` and return where they went. The claim of ``out`` is atomic: a
        new ``out`` is the staging directory renamed (which fails if another run got there first); an
        existing ``out`` is claimed by linking the staged ``config.yaml`` into it (which fails if it holds
        one). A run already in ``out`` is replaced only with ``replace`` (``--force``): it is first moved
        aside and deleted once the staged files are in, keeping ``out`` itself (a shell inside it stays
        there) and its other files. Without ``replace``, a run that finds ``out`` taken keeps its files
        under the first free name ``out.2``, ``out.3``, ... and returns that path. Ctrl-C waits until it
        ends."""
        with _sigint_ignored():
            try:
                if not replace:
                    if not self.out.exists() and self._rename_to(self.out):
                        return self.out
                    if self.out.is_dir() and not run_entries(self.out) and self._claim(self.out):
                        self._move_into(self.out, skip="config.yaml")
                        return self.out
                    for k in range(2, 10_000):
                        other = self.out.with_name(f"{self.out.name}.{k}")
                        if not other.exists() and self._rename_to(other):
                            return other
                    raise OSError(f"no free name beside {self.out}")
                if not self.out.exists():
                    os.replace(self.path, self.out)
                    return self.out
                old, aside = run_entries(self.out), None
                if old:
                    aside = Path(tempfile.mkdtemp(prefix=f".{self.out.name}.", suffix=".replaced", dir=self.out.parent))
                    for name in old:
                        os.replace(self.out / name, aside / name)
                self._move_into(self.out)
                if aside is not None:
                    shutil.rmtree(aside, ignore_errors=True)
                return self.out
            except OSError as err:
                raise TrainError(
                    f"could not move the finished files from '{self.path}' into '{self.out}': {err.strerror or err}"
                ) from None

    def _rename_to(self, target: Path) -> bool:
        """Rename the staging directory to the new ``target``; False if another run took it first."""
        try:
            os.rename(self.path, target)  # fails if target exists and is not an empty directory
        except OSError as err:
            if err.errno in (errno.EEXIST, errno.ENOTEMPTY, errno.ENOTDIR):
                return False
            raise
        self.path = target
        return True

    def _claim(self, target: Path) -> bool:
        """Claim the existing directory ``target`` by linking the staged config into it; False if taken."""
        try:
            os.link(self.path / "config.yaml", target / "config.yaml")
        except FileExistsError:
            return False
        return True

    def _move_into(self, target: Path, skip: str | None = None) -> None:
        for entry in self.path.iterdir():
            if entry.name != skip:
                os.replace(entry, target / entry.name)
        if skip is not None:
            (self.path / skip).unlink()
        self.path.rmdir()

    def abandon(self) -> str:
        """After a failure: delete the staging directory, unless it holds a trained model, which is kept;
        returns a note for the error message (empty if nothing was kept)."""
        if (self.path / "model.zip").is_file():
            return f"; the trained model is kept in '{self.path}'"
        shutil.rmtree(self.path, ignore_errors=True)
        return ""


#: a staging directory's name between ``.<output name>.`` and ``.partial``: the owner's process id and
#: mkdtemp's 8 random characters (names made without the process id have the random characters only)
_STAGING_TAIL = re.compile(r"(?:(?P<pid>[0-9]+)-)?[a-z0-9_]{8}")
#: a staging directory whose name carries no process id counts as in use until this long after its last write
UNKNOWN_OWNER_S = 3600.0


@dataclass(frozen=True)
class StagingDir:
    """A staging directory found on disk (:func:`staging_dirs`): its ``path``, the output it belongs to, the
    process id in its name (None in names without one), seconds since its last write, whether it holds a
    trained model."""

    path: Path
    out: Path
    pid: int | None
    age_s: float
    has_model: bool

    @property
    def owner_running(self) -> bool:
        """Whether the process that made it still runs on this machine (its pid in the name is alive); a
        name without a pid counts as running for :data:`UNKNOWN_OWNER_S` after the last write."""
        if self.pid is None:
            return self.age_s < UNKNOWN_OWNER_S
        if self.pid == os.getpid():
            return True
        try:
            os.kill(self.pid, 0)
        except ProcessLookupError:
            return False
        except OSError:  # exists, owned by another user
            return True
        return True

    def describe(self) -> str:
        """``PATH (3.2 h old, holds a trained model)``."""
        notes = [f"{_age(self.age_s)} old"] + (["holds a trained model"] if self.has_model else [])
        if self.owner_running:
            notes.append(f"in use by process {self.pid}" if self.pid is not None else "written less than an hour ago: may be in use")
        return f"{self.path} ({', '.join(notes)})"


def _age(seconds: float) -> str:
    if seconds < 90:
        return f"{max(seconds, 0):.0f} s"
    if seconds < 90 * 60:
        return f"{seconds / 60:.0f} min"
    if seconds < 48 * 3600:
        return f"{seconds / 3600:.1f} h"
    return f"{seconds / 86400:.1f} days"


def _last_write(path: Path) -> float:
    """The newest modification time of ``path`` and the entries in it (and in its ``checkpoints/``)."""
    times = [path.stat().st_mtime]
    for folder in (path, path / "checkpoints"):
        with contextlib.suppress(OSError):
            for entry in os.scandir(folder):
                with contextlib.suppress(OSError):
                    times.append(entry.stat(follow_symlinks=False).st_mtime)
    return max(times)


def staging_dirs(folder: str | Path) -> list[StagingDir]:
    """The staging directories (``.NAME.<pid>-<random>.partial``) of the output ``folder`` (beside it) and of
    the outputs inside ``folder``, oldest first."""
    folder = Path(os.path.abspath(folder))
    found: list[StagingDir] = []
    try:
        inside = folder.is_dir()
    except OSError:  # e.g. a name too long for the file system: nothing inside it
        inside = False
    places = [(folder.parent, folder.name)] + ([(folder, None)] if inside else [])
    now = time.time()
    for parent, name in places:
        try:
            entries = list(os.scandir(parent))
        except OSError:
            continue
        for entry in entries:
            if not entry.name.startswith(".") or not entry.name.endswith(".partial"):
                continue
            out_name, _, tail = entry.name[1:-len(".partial")].rpartition(".")
            match = _STAGING_TAIL.fullmatch(tail)
            if not match or not out_name or (name is not None and out_name != name):
                continue
            path = Path(entry.path)
            try:
                if not entry.is_dir(follow_symlinks=False):
                    continue
                age = now - _last_write(path)
            except OSError:
                continue
            pid = int(match["pid"]) if match["pid"] else None
            found.append(StagingDir(path, parent / out_name, pid, age, (path / "model.zip").is_file()))
    return sorted(found, key=lambda d: -d.age_s)


def report_staging_dirs(out: Path, command: str) -> list[StagingDir]:
    """Print one line (stderr) per staging directory of ``out`` that another process left or is writing;
    returns them."""
    found = [d for d in staging_dirs(out) if d.out == Path(os.path.abspath(out)) and d.pid != os.getpid()]
    for d in found:
        if d.owner_running and d.pid is not None:
            print(_one_line(f"note: process {d.pid} is also writing a run for {out}: {d.describe()}"), file=sys.stderr)
        else:
            print(_one_line(f"note: staging directory left by an earlier run of {out}: {d.describe()}; list or remove "
                            f"such directories with: {command} --list-partial / --clean-partial {out}"), file=sys.stderr)
    return found


def clean_staging_dirs(folder: str | Path, remove: bool, command: str) -> int:
    """``--list-partial`` / ``--clean-partial FOLDER``: list the staging directories of the output ``folder``
    and of the outputs in it; with ``remove``, delete those whose process no longer runs. Returns the exit
    code (2 if one could not be removed)."""
    found = staging_dirs(folder)
    if not found:
        print(f"no staging directories for {folder}")
        return 0
    code, removed = 0, 0
    for d in found:
        if not remove:
            print(d.describe())
        elif d.owner_running:
            print(f"kept {d.describe()}")
        else:
            try:
                shutil.rmtree(d.path)
            except OSError as err:
                print(_one_line(f"error: could not remove '{d.path}': {err.strerror or err}"), file=sys.stderr)
                code = EXIT_BAD_INPUT
                continue
            removed += 1
            print(f"removed {d.describe()}")
    if remove:
        print(f"removed {removed} of {len(found)} staging directories")
    else:
        free = sum(not d.owner_running for d in found)
        print(f"{len(found)} staging directories, {free} not in use; remove those with: {command} --clean-partial {folder}")
    return code


@contextlib.contextmanager
def _sigint_ignored() -> Iterator[None]:
    """Ignore Ctrl-C inside the block (main thread only), so a file move is never cut short."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


class _CtrlC:
    """Ctrl-C during training and evaluation. The first one asks the work to stop at the next env step (a
    callback that returns False ends SB3's ``learn``; an evaluated policy calls :meth:`check` every step),
    so the request is never lost: raised as a ``KeyboardInterrupt`` wherever the signal lands, it can land
    in a cffi finalizer (pymunk's bodies), where CPython prints it and drops it, or in a Python call made
    from numba-compiled code, where it surfaces as a ``SystemError``. A second Ctrl-C raises
    ``KeyboardInterrupt`` at once. After an interrupted training, Ctrl-C stays ignored so the save that
    follows is never cut short."""

    def __init__(self) -> None:
        self.requested = False

    def check(self) -> None:
        """Raise ``KeyboardInterrupt`` if Ctrl-C was pressed (from ordinary code, where it is never dropped)."""
        if self.requested:
            raise KeyboardInterrupt

    def _handler(self, signum: int, frame: Any) -> None:
        if self.requested:
            raise KeyboardInterrupt
        self.requested = True

    @contextlib.contextmanager
    def installed(self) -> Iterator[None]:
        """The handler inside the block (main thread only; not where Ctrl-C is ignored already)."""
        if threading.current_thread() is not threading.main_thread() or signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
            yield
            return
        previous = signal.signal(signal.SIGINT, self._handler)
        try:
            yield
        finally:
            signal.signal(signal.SIGINT, signal.SIG_IGN if self.requested else previous)

    def callback(self) -> Any:
        """An SB3 callback that ends training once Ctrl-C was pressed."""
        from stable_baselines3.common.callbacks import BaseCallback

        ctrl_c = self

        class StopOnCtrlC(BaseCallback):
            def _on_step(self) -> bool:
                return not ctrl_c.requested

        return StopOnCtrlC()


@contextlib.contextmanager
def _naming(path: Path) -> Iterator[None]:
    """Turn an ``OSError`` inside the block (a full disk) into a :class:`TrainError` naming ``path``."""
    try:
        yield
    except OSError as err:
        raise TrainError(f"could not write '{path}': {err.strerror or err}") from None


def _one_line(message: object) -> str:
    """``message`` on one line (newlines and runs of spaces collapsed)."""
    return " ".join(str(message).split())


def is_interrupt(err: BaseException) -> bool:
    """Whether ``err`` is Ctrl-C: a ``KeyboardInterrupt``, or the ``SystemError`` CPython raises in its place
    when the signal arrives just as a compiled (numba) function returns ("... returned a result with an
    exception set"): the handler runs in a Python call numba makes from compiled code (``_numba_unpickle``),
    and each C level between it and the caller wraps the ``KeyboardInterrupt`` in one more such
    ``SystemError``, so the chain of causes is followed through them."""
    for _ in range(64):
        if not isinstance(err, SystemError):
            break
        err = err.__cause__ or err.__context__
    return isinstance(err, KeyboardInterrupt)


def env_kwargs_of(cfg: dict[str, Any]) -> dict[str, Any]:
    """The env keyword arguments of a config (YAML lists -> tuples where the env wants tuples)."""
    kwargs = dict(cfg["env"])
    if isinstance(kwargs.get("code"), list):
        kwargs["code"] = tuple(kwargs["code"])
    return kwargs


def planned_timesteps(budget: int, n_steps: int, num_envs: int) -> int:
    """Robot-steps PPO really runs for ``budget``: rounded up to whole rollouts of ``n_steps * num_envs``."""
    rollout = n_steps * num_envs
    return math.ceil(budget / rollout) * rollout


def build_model(cfg: dict[str, Any], vec_env, layout):
    """The model of the ``agent`` section for ``vec_env`` (wrapped for the policy variant)."""
    from swarm_envs.agents.policies import build_model as build

    return build(cfg["agent"], vec_env, layout, cfg["seed"])


class _ScaledRewards:
    """Wrap a VecEnv so PPO sees rewards times ``scale`` (metrics and episode returns stay unscaled)."""

    def __new__(cls, venv, scale: float):
        from stable_baselines3.common.vec_env import VecEnvWrapper

        class Scaled(VecEnvWrapper):
            def reset(self):
                return self.venv.reset()

            def step_wait(self):
                obs, rew, done, info = self.venv.step_wait()
                return obs, rew * scale, done, info

        return Scaled(venv)


def _say(line: str) -> None:
    """Print a line without breaking a tqdm bar that may be on screen."""
    from tqdm import tqdm

    tqdm.write(line, file=sys.stdout)


def _progress_writer(total: int, repeat: int = 1):
    """An SB3 logger output that prints one short line per ~10 % of ``total`` PPO timesteps (and the last),
    counted in robot-steps (``repeat`` per timestep)."""
    from stable_baselines3.common.logger import KVWriter

    class ProgressLine(KVWriter):
        def __init__(self) -> None:
            self.next_fraction = 0.1
            self.last = -1

        def write(self, key_values: dict[str, Any], key_excluded: dict, step: int = 0) -> None:
            done = key_values.get("time/total_timesteps", step)
            if done <= self.last or (done < self.next_fraction * total and done < total):
                return
            self.last = done
            self.next_fraction = math.floor(done / total * 10 + 1) / 10
            parts = [f"PPO {done * repeat}/{total * repeat} robot-steps ({100 * done / total:.0f}%)"]
            for key, label, fmt in (("rollout/ep_rew_mean", "ep_rew_mean", ".4g"), ("rollout/ep_len_mean", "ep_len", ".4g"),
                                    (RATE_KEY, "robot-steps/s", ".0f"), ("train/loss", "loss", ".3g")):
                if key in key_values:
                    parts.append(f"{label} {key_values[key]:{fmt}}")
            _say("  ".join(parts))

        def close(self) -> None:
            pass

    return ProgressLine()


#: the progress.csv column of the training rate (robot-steps/s) from the end of the first env step on
RATE_KEY = "time/robot_steps_per_s"


def rate_callback(repeat: int = 1):
    """An SB3 callback that logs :data:`RATE_KEY` at the end of every rollout: robot-steps (PPO timesteps x
    ``repeat``) per second of wall time since the end of the first env step, PPO updates included. The start
    lies after the env's first reset and step, where a cold numba cache compiles the kernels, so unlike
    SB3's ``time/fps`` (from the start of ``learn``) the rate does not count the one-off compile."""
    from stable_baselines3.common.callbacks import BaseCallback

    class RateCallback(BaseCallback):
        start: tuple[float, int] | None = None  # (perf_counter s, num_timesteps) at the end of the first step

        def _on_training_start(self) -> None:
            self.start = None

        def _on_step(self) -> bool:
            if self.start is None:
                self.start = (time.perf_counter(), self.num_timesteps)
            return True

        def _on_rollout_end(self) -> None:
            if self.start is None:
                return
            seconds = time.perf_counter() - self.start[0]
            steps = (self.num_timesteps - self.start[1]) * repeat
            if seconds > 0 and steps > 0:
                self.logger.record(RATE_KEY, steps / seconds)

    return RateCallback()


def make_logger(out: Path, total: int, progress_lines: bool, repeat: int = 1):
    """SB3 logger: ``progress.csv`` always, TensorBoard if installed, short progress lines if asked (``total``
    PPO timesteps, each ``repeat`` robot-steps)."""
    from stable_baselines3.common.logger import Logger, make_output_format

    formats = [make_output_format("csv", str(out))]
    if importlib.util.find_spec("tensorboard") is not None:
        formats.append(make_output_format("tensorboard", str(out / "tensorboard")))
    if progress_lines:
        formats.append(_progress_writer(total, repeat))
    return Logger(folder=str(out), output_formats=formats)


def make_callbacks(cfg: dict[str, Any], out: Path, num_envs: int, total: int):
    """Checkpoints every ``train.checkpoint_freq`` robot-steps and a tqdm bar over the real ``total``
    robot-steps (``num_envs`` robot-steps per callback call: rows x action repeat)."""
    from stable_baselines3.common.callbacks import BaseCallback, CallbackList, CheckpointCallback

    callbacks = []
    freq = cfg["train"]["checkpoint_freq"]
    if freq > 0:
        callbacks.append(CheckpointCallback(save_freq=max(1, freq // num_envs), save_path=str(out / "checkpoints"), name_prefix="ppo"))
    if progress_bar_on(cfg["train"]["progress_bar"]):

        class TqdmCallback(BaseCallback):
            """Progress bar over robot-steps with the latest mean episode return."""

            bar = None

            def _on_training_start(self) -> None:
                from tqdm import tqdm

                self.bar = tqdm(total=total, desc="PPO", unit="step", dynamic_ncols=True)

            def _on_step(self) -> bool:
                self.bar.update(num_envs)
                buf = self.model.ep_info_buffer
                if buf and self.n_calls % 50 == 0:
                    self.bar.set_postfix(ep_rew=f"{np.mean([e['r'] for e in buf]):.3g}")
                return True

            def _on_training_end(self) -> None:
                self.close()

            def close(self) -> None:
                if self.bar is not None:
                    self.bar.close()
                    self.bar = None

        callbacks.append(TqdmCallback())
    return CallbackList(callbacks)


def train(cfg: dict[str, Any], stage: Staging, ctrl_c: _CtrlC | None = None,
          before_learning: Callable[[Any], None] | None = None) -> tuple[Any, float, bool]:
    """Train PPO and save ``model.zip`` in the staging directory; returns (model, seconds, interrupted by Ctrl-C).
    ``ctrl_c`` is a Ctrl-C handler the caller has installed (without one, a handler is installed around
    training and the save); ``before_learning(model)`` runs once the model is built, before any training.
    A failed write of the logs or checkpoints is a :class:`TrainError`."""
    out = stage.path
    from swarm_envs.agents.sb3_vec_env import SwarmVecEnv

    from swarm_envs.agents.policies import PolicySpec, wrap_training_env

    spec = PolicySpec.from_agent(cfg["agent"])
    own = ctrl_c is None
    ctrl_c = ctrl_c or _CtrlC()
    venv = SwarmVecEnv(env_id(cfg["task"]), cfg["train"]["n_envs"], env_kwargs_of(cfg), n_workers=cfg["train"]["n_workers"])
    try:
        venv.seed(cfg["seed"])
        wrapped = venv if cfg["agent"]["reward_scale"] == 1.0 else _ScaledRewards(venv, cfg["agent"]["reward_scale"])
        wrapped = wrap_training_env(wrapped, spec, venv.layout, venv.platform)
        model = build_model(cfg, wrapped, venv.layout)
        if before_learning is not None:
            before_learning(model)
        ctrl_c.check()  # Ctrl-C while setting up: nothing trained, nothing to save
        repeat = spec.action_repeat
        budget = math.ceil(cfg["train"]["total_timesteps"] / repeat)  # PPO counts decisions: robot-steps / action_repeat
        total = planned_timesteps(budget, cfg["agent"]["n_steps"], venv.num_envs)
        if total * repeat != cfg["train"]["total_timesteps"]:
            _say(f"training {total * repeat} robot-steps: the budget {cfg['train']['total_timesteps']} rounded up to "
                 f"{total // (cfg['agent']['n_steps'] * venv.num_envs)} whole rollouts of {cfg['agent']['n_steps']} "
                 f"{'steps' if repeat == 1 else f'decisions of {repeat} steps'} x {venv.num_envs} robots")
        logger = make_logger(out, total, progress_lines=True, repeat=repeat)
        model.set_logger(logger)
        callbacks = make_callbacks(cfg, out, venv.num_envs * repeat, total * repeat)
        callbacks.callbacks.append(rate_callback(repeat))
        callbacks.callbacks.append(ctrl_c.callback())
        with ctrl_c.installed() if own else contextlib.nullcontext():
            t0 = time.perf_counter()
            try:
                model.learn(budget, callback=callbacks)  # SB3 dumps a row per iteration, before that iteration's update
            except (KeyboardInterrupt, SystemError) as err:  # a second Ctrl-C, or one outside the main thread's handler
                if not is_interrupt(err):
                    raise
                ctrl_c.requested = True
            except OSError as err:  # the logger or a checkpoint could not write (a full disk)
                where = stage.final(Path(err.filename)) if getattr(err, "filename", None) else stage.out
                raise TrainError(f"could not write the training logs or checkpoints in '{where}': {err.strerror or err}") from None
            finally:
                for cb in callbacks.callbacks:
                    if hasattr(cb, "close"):
                        cb.close()
                with contextlib.suppress(OSError):
                    logger.close()
            seconds = time.perf_counter() - t0
            if ctrl_c.requested and threading.current_thread() is threading.main_thread():
                signal.signal(signal.SIGINT, signal.SIG_IGN)  # a further Ctrl-C must not cut the save short
            # a first Ctrl-C from here on only sets ctrl_c.requested: the save is never cut short
            with stage.writing(out / "model.zip") as tmp:
                model.save(tmp)
    finally:
        venv.close()
    return model, seconds, ctrl_c.requested


def _read_progress(path: Path) -> dict[str, np.ndarray]:
    import csv

    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    keys = rows[0].keys() if rows else []
    return {k: np.array([float(r[k]) if r.get(k) not in (None, "") else np.nan for r in rows]) for k in keys}


def _save_figure(fig: Any, path: Path) -> None:
    """Save a matplotlib figure to ``path`` under a temporary name, renamed when complete."""
    tmp = path.with_name(f".tmp-{os.getpid()}-{path.name}")
    try:
        fig.savefig(tmp, dpi=110)
        os.replace(tmp, path)
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink()


def plot_learning_curve(csv_path: str | Path, png_path: str | Path, title: str) -> bool:
    """Plot ``progress.csv`` (mean episode return, episode length, losses vs robot-steps); False if no data.
    The PNG is written under a temporary name and renamed when complete."""
    data = _read_progress(Path(csv_path))
    steps = data.get("time/total_timesteps")
    if steps is None or not np.isfinite(steps).any():
        return False
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import EngFormatter

    panels = [("rollout/ep_rew_mean", "mean episode return (per robot)"), ("rollout/ep_len_mean", "mean episode length (steps)"),
              ("train/value_loss", "value loss"), ("train/policy_gradient_loss", "policy-gradient loss")]
    panels = [(k, label) for k, label in panels if k in data and np.isfinite(data[k]).any()]
    if not panels:
        return False
    fig, axes = plt.subplots(1, len(panels), figsize=(3.3 * len(panels), 3.0), squeeze=False)
    for ax, (key, label) in zip(axes[0], panels):
        ok = np.isfinite(steps) & np.isfinite(data[key])
        ax.plot(steps[ok], data[key][ok], marker="." if ok.sum() <= 30 else None, lw=1)
        ax.xaxis.set_major_formatter(EngFormatter(sep=""))  # 50k, not 50000 (labels would overlap)
        ax.set_xlabel("robot-steps", fontsize=8)
        ax.set_title(label, fontsize=9)
        ax.tick_params(labelsize=7)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    try:
        _save_figure(fig, Path(png_path))
    finally:
        plt.close(fig)
    return True


def plot_results(rows: list[dict[str, Any]], path: Path, title: str) -> None:
    """One bar panel per metric (policies side by side) with bootstrap 95 % CI error bars (none for n=1)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    metrics = list(dict.fromkeys(r["metric"] for r in rows))
    policies = list(dict.fromkeys(r["policy"] for r in rows))
    fig, axes = plt.subplots(1, len(metrics), figsize=(3.2 * len(metrics), 3.2), squeeze=False)
    cell = {(r["policy"], r["metric"]): r for r in rows}
    for ax, m in zip(axes[0], metrics):
        means = [cell[(p, m)]["mean"] for p in policies]
        err = np.array([[cell[(p, m)]["mean"] - cell[(p, m)]["ci_low"], cell[(p, m)]["ci_high"] - cell[(p, m)]["mean"]] for p in policies]).T
        ax.bar(policies, means, yerr=np.nan_to_num(err), capsize=4, color=["tab:blue", "tab:green", "tab:gray"][: len(policies)])
        ax.set_title(m, fontsize=9)
        ax.tick_params(labelsize=8)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    try:
        _save_figure(fig, Path(path))
    finally:
        plt.close(fig)


def write_gif(cfg: dict[str, Any], policy_factory, path: Path, seed: int) -> None:
    """One evaluation episode of ``policy_factory`` rendered to a GIF."""
    import imageio.v2 as imageio

    kwargs = {**env_kwargs_of(cfg), "render_mode": "rgb_array"}
    if cfg["eval"]["max_cycles"] is not None:
        kwargs["max_cycles"] = cfg["eval"]["max_cycles"]
    env = make_env(cfg["task"], **kwargs)
    frames: list = []
    run_episode(env, policy_factory(env), seed, cfg["task"], frames=frames)
    env.close()
    tmp = path.with_name(f".tmp-{os.getpid()}-{path.name}")
    try:
        imageio.mimsave(tmp, [np.asarray(f) for f in frames if f is not None], duration=100, loop=0)
        os.replace(tmp, path)
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink()


def check_output(out: Path, force: bool, eval_only: bool = False) -> None:
    """:class:`TrainError` if ``out`` is a file, or holds a run (:func:`run_entries`) and ``force`` is not
    set. Reads only; the staging directory (:class:`Staging`) is the write test."""
    try:
        is_file = out.exists() and not out.is_dir()
    except OSError as err:  # e.g. a name too long for the file system
        raise TrainError(f"output directory '{out}' cannot be used: {err.strerror or err}") from None
    if is_file:
        raise TrainError(f"output directory '{out}' exists and is a file, not a directory")
    existing = run_entries(out)
    if existing and not force:
        kind = "results" if eval_only and set(existing) & set(RESULT_FILES) else "a run"
        shown = [n for n in existing if n in RESULT_FILES] if kind == "results" else existing
        hint = "omit it (a new eval-<timestamp> directory)" if eval_only else "use another --output"
        raise TrainError(f"output directory '{out}' already holds {kind} ({', '.join(shown[:6])}); {hint}, "
                         "or add --force to replace it")


def eval_output_dir(checkpoint: Path, output: str | None, force: bool) -> Path:
    """Where ``--eval-only`` writes: ``output`` (refused if it holds a run, unless ``force``, and if it holds
    the checkpoint), else a new ``eval-<UTC timestamp>`` directory beside the checkpoint (its run directory
    for ``checkpoints/*.zip``)."""
    if output is not None:
        out = Path(output)
        if out.resolve() in checkpoint.resolve().parents:
            raise TrainError(f"--output '{out}' holds the checkpoint being evaluated; omit --output (a new "
                             "eval-<timestamp> directory is made beside it) or choose another directory")
        check_output(out, force, eval_only=True)
        return out
    run = checkpoint.parent.parent if checkpoint.parent.name == "checkpoints" else checkpoint.parent
    stamp = time.strftime("%Y%m%d-%H%M%S", time.gmtime())
    out = run / f"eval-{stamp}"
    k = 2
    while out.exists():
        out, k = run / f"eval-{stamp}-{k}", k + 1
    return out


def resolve_checkpoint(path: str) -> Path:
    """The checkpoint file (SB3 accepts the name without ``.zip``); :class:`TrainError` if missing."""
    p = Path(path)
    try:
        if not p.exists() and p.suffix != ".zip" and p.with_name(p.name + ".zip").is_file():
            p = p.with_name(p.name + ".zip")
        if not p.exists():
            raise TrainError(f"checkpoint '{path}' not found")
        if p.is_dir():
            raise TrainError(f"checkpoint '{p}' is a directory, not a model .zip")
        if not p.is_file():
            raise TrainError(f"checkpoint '{p}' is not a regular file (a device or a pipe), not a model .zip")
    except OSError as err:  # e.g. a name too long for the file system
        raise TrainError(f"checkpoint '{path}' cannot be read: {err.strerror or err}") from None
    return p


def load_checkpoint(path: Path, cfg: dict[str, Any], env_kwargs: dict[str, Any]):
    """Load a PPO ``.zip`` and check it fits the config's env; :class:`TrainError` with one line otherwise."""
    from swarm_envs.agents.policies import PolicySpec, algorithm_class

    spec = PolicySpec.from_agent(cfg["agent"])
    if not zipfile.is_zipfile(path):
        raise TrainError(f"checkpoint '{path}' is not a zip archive (truncated, or not a stable-baselines3 model)")
    try:
        model = algorithm_class(spec).load(path, device="cpu")
    except Exception as err:  # SB3 raises many kinds (KeyError, BadZipFile, ValueError, pickle errors)
        detail = str(err).strip().splitlines()[0] if str(err).strip() else ""
        raise TrainError(f"checkpoint '{path}' cannot be loaded as a {'RecurrentPPO' if spec.algorithm == 'recurrent_ppo' else 'PPO'} model ({type(err).__name__}{': ' + detail if detail else ''})") from None
    env = make_env(cfg["task"], **{**env_kwargs, "flatten": True})
    agent = env.possible_agents[0]
    obs_shape, act_shape = env.observation_space(agent).shape, env.action_space(agent).shape
    obs_shape = (obs_shape[0] * spec.frame_stack,)
    env.close()
    settings = ", ".join(f"{k}={v}" for k, v in env_kwargs.items())
    if model.observation_space.shape != obs_shape:
        raise TrainError(f"checkpoint '{path}' expects observations of size {_size(model.observation_space.shape)} but the "
                         f"config's {cfg['task']} env ({settings or 'defaults'}) gives {_size(obs_shape)}; "
                         "evaluate it with the config it was trained with (its config.yaml)")
    if model.action_space.shape != act_shape:
        raise TrainError(f"checkpoint '{path}' gives actions of size {_size(model.action_space.shape)} but the "
                         f"config's {cfg['task']} env expects {_size(act_shape)}")
    return model


def check_run_config(checkpoint: Path, cfg: dict[str, Any], env_kwargs: dict[str, Any], config: str) -> None:
    """:class:`TrainError` (one line naming both) if the run that saved ``checkpoint`` (its ``config.yaml``:
    :func:`swarm_envs.agents.config.run_config_path`) trained another task, on another platform, with other
    observation or action spaces or another policy variant than the config ``config`` (resolved: ``cfg``,
    env settings ``env_kwargs``) evaluates. A model without a run config (or with one train.py did not
    write) is checked by :func:`load_checkpoint`'s observation and action sizes only."""
    from swarm_envs.agents.config import run_config_path
    from swarm_envs.agents.policies import PolicySpec
    from swarm_envs.agents.tasks import SHORT_NAMES

    path = run_config_path(checkpoint)
    if path is None:
        return
    try:
        run = yaml.safe_load(path.read_text())
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        return
    if not isinstance(run, dict) or not isinstance(run.get("task"), str) or not isinstance(run.get("env") or {}, dict):
        return
    trained = f"checkpoint '{checkpoint}' was trained"
    hint = f"evaluate it with its run's config ({path})"
    run_id, ours = SHORT_NAMES.get(run["task"], run["task"]), env_id(cfg["task"])
    if run_id != ours:
        raise TrainError(f"{trained} on {run_id} (its run config {path}) but {config} evaluates {ours}; {hint}")
    try:
        run_kwargs = {k: v for k, v in env_kwargs_of({"env": run.get("env") or {}}).items() if k != "render_mode"}
        run_env = make_env(run_id, **run_kwargs, flatten=True)
    except Exception:  # settings this version does not take: the sizes were checked
        return
    env = make_env(ours, **{**env_kwargs, "flatten": True})
    try:
        if run_env.platform.name != env.platform.name:
            raise TrainError(f"{trained} on the {run_env.platform.name} platform (its run config {path}) but {config} "
                             f"uses the {env.platform.name}; {hint}")
        spaces = [(e.layout.dict_space(), e.action_space(e.possible_agents[0])) for e in (run_env, env)]
        if spaces[0] != spaces[1]:
            raise TrainError(f"{trained} with {_spaces_text(*spaces[0])} (its run config {path}) but {config} gives "
                             f"{_spaces_text(*spaces[1])}; {hint}")
    finally:
        run_env.close()
        env.close()
    agent = run.get("agent") if isinstance(run.get("agent"), dict) else {}
    try:
        run_spec = PolicySpec.from_agent({**DEFAULTS["agent"], **agent})
    except TypeError:
        return
    spec = PolicySpec.from_agent(cfg["agent"])
    differ = [k for k in spec.__dataclass_fields__ if getattr(run_spec, k) != getattr(spec, k)]
    if differ:
        raise TrainError(f"{trained} as the policy variant {run_spec.name}, {_fields(run_spec, differ)} (its run config "
                         f"{path}) but {config} evaluates {spec.name}, {_fields(spec, differ)}; {hint}")


def _spaces_text(observations: Any, actions: Any) -> str:
    """``observations range_bearing 8x7, proprio 10; actions 2`` (each part's shape)."""
    parts = ", ".join(f"{name} {_size(space.shape)}" for name, space in observations.spaces.items())
    return f"observations {parts}; actions {_size(actions.shape)}"


def _fields(spec: Any, names: list[str]) -> str:
    """``agent.frame_stack=4, agent.odometry=True``: the named fields of a policy variant."""
    return ", ".join(f"agent.{k}={getattr(spec, k)}" for k in names)


def _size(shape: tuple[int, ...] | None) -> str:
    return "x".join(str(s) for s in shape) if shape else "?"


def _command() -> str:
    """How the user runs this command, for the messages: ``swarm-train`` or ``python train.py``."""
    return "swarm-train" if os.path.basename(sys.argv[0] or "") == "swarm-train" else "python train.py"


def _parser() -> argparse.ArgumentParser:
    from swarm_envs.tasks.settings import OneLineArgumentParser

    parser = OneLineArgumentParser(prog=_command().removeprefix("python "), description=__doc__.split("\n\n")[0])
    what = parser.add_mutually_exclusive_group(required=True)
    what.add_argument("--config", help="YAML config, e.g. configs/aggregation.yaml")
    what.add_argument("--list-partial", metavar="DIR", default=None,
                      help="list the staging directories (.NAME.<pid>-<random>.partial) of the output DIR and of the "
                           "outputs in DIR: their age, whether they hold a trained model, whether their process still runs")
    what.add_argument("--clean-partial", metavar="DIR", default=None,
                      help="remove the staging directories of the output DIR and of the outputs in DIR whose process "
                           "no longer runs (a run killed before it could publish leaves one)")
    parser.add_argument("--output", default=None,
                        help="output directory (default: the config's output_dir; with --eval-only: a new "
                             "eval-<timestamp> directory beside the checkpoint)")
    parser.add_argument("--render", action="store_true", help="write a GIF of one evaluation episode")
    parser.add_argument("--eval-only", metavar="CHECKPOINT", default=None, help="skip training; evaluate this PPO .zip")
    parser.add_argument("--baselines-only", action="store_true",
                        help="no RL policy: evaluate the scripted baseline and random actions only (results as a run's)")
    parser.add_argument("--force", action="store_true",
                        help="replace the run already in the output directory (when the command ends; never before, "
                             "and never by an interrupted or failed command)")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                        help="override a config value (dotted key), e.g. train.total_timesteps=2000; repeatable")
    return parser


def main(argv: list[str] | None = None) -> int:
    """Command line of ``train.py``; returns the exit code (0 ok, 2 bad input or a failed write, 130 interrupted).
    Every failure is one line on stderr; no run on disk is changed by a failed or interrupted command."""
    parser = _parser()
    args = parser.parse_args(argv)
    folder = args.clean_partial if args.clean_partial is not None else args.list_partial
    if folder is not None:
        option = "--clean-partial" if args.clean_partial is not None else "--list-partial"
        given = [flag for flag, value in (("--output", args.output), ("--set", args.overrides), ("--eval-only", args.eval_only),
                                          ("--render", args.render), ("--baselines-only", args.baselines_only),
                                          ("--force", args.force)) if value not in (None, False, [])]
        if given:
            parser.error(f"{option} takes no other option, got {given[0]}")
        if not folder.strip():
            parser.error(f"{option} needs an output directory (or a folder of outputs), got {folder!r}")
        try:
            return clean_staging_dirs(folder, remove=option == "--clean-partial", command=_command())
        except KeyboardInterrupt:
            print(f"interrupted by Ctrl-C during {option}", file=sys.stderr)
            return EXIT_INTERRUPTED
    state: dict[str, Any] = {"phase": "setup"}
    main_thread = threading.current_thread() is threading.main_thread()
    handler = signal.getsignal(signal.SIGINT) if main_thread else None
    try:
        return _main(args, state)
    finally:  # the command leaves Ctrl-C as it found it (it ignores Ctrl-C after an interrupt)
        if main_thread and handler is not None:
            signal.signal(signal.SIGINT, handler)


def _main(args: argparse.Namespace, state: dict[str, Any]) -> int:
    try:
        return _run(args, state)
    except (TrainError, OSError, MemoryError) as err:
        stage = state.get("stage")
        note = stage.abandon() if stage is not None else ""
        if isinstance(err, MemoryError):
            text = "out of memory; use fewer env copies (train.n_envs), robots or rollout steps (agent.n_steps)"
        elif isinstance(err, OSError):
            path = f" '{err.filename}'" if getattr(err, "filename", None) else ""
            text = f"could not write{path}: {err.strerror or err}"
        else:
            text = str(err)
        print(_one_line(f"error: {text}{note}"), file=sys.stderr)
        return EXIT_BAD_INPUT
    except (KeyboardInterrupt, SystemError) as err:
        if not is_interrupt(err):
            return _unexpected(err, state)
        return _interrupted(state)
    except Exception as err:  # anything else is still one line, and leaves the output as it was
        return _unexpected(err, state)


def _unexpected(err: BaseException, state: dict[str, Any]) -> int:
    """One line for an error no check foresaw (the traceback with ``SWARM_ENVS_TRACEBACK=1``); the staging
    directory goes as after any failure (a trained model in it is kept and named)."""
    if os.environ.get("SWARM_ENVS_TRACEBACK"):
        import traceback

        traceback.print_exception(err)
    stage = state.get("stage")
    note = stage.abandon() if stage is not None else ""
    hint = "" if os.environ.get("SWARM_ENVS_TRACEBACK") else " (SWARM_ENVS_TRACEBACK=1 shows the traceback)"
    print(_one_line(f"error: unexpected {type(err).__name__} during {state['phase']}: {err}{note}{hint}"), file=sys.stderr)
    return EXIT_BAD_INPUT


def _interrupted(state: dict[str, Any]) -> int:
    """One line after Ctrl-C outside training (further Ctrl-C ignored meanwhile). Once the trained model is
    saved, the run so far is published (:func:`_publish_interrupted`); before that, and in an ``--eval-only``
    or ``--baselines-only`` evaluation, nothing is kept."""
    with _sigint_ignored():
        stage, phase = state.get("stage"), state["phase"]
        if stage is not None and phase in ("train", "eval") and (stage.path / "model.zip").is_file():
            line = _publish_interrupted(stage, state)
        else:
            if stage is not None:
                stage.abandon()
            line = "interrupted by Ctrl-C " + {
                "setup": "before training started; nothing saved",
                "train": "while setting up training; nothing saved",
                "eval": "during evaluation; nothing saved",
                "eval-only": f"during the evaluation of {state.get('model', '?')}; no results written",
                "done": f"after the run was written to {state.get('final', '?')}",
            }[phase]
        print(_one_line(line), file=sys.stderr)
    return EXIT_INTERRUPTED


def _publish_interrupted(stage: Staging, state: dict[str, Any]) -> str:
    """After Ctrl-C with the trained model saved: publish the model, config, learning curve and the results
    if all were written (``timing.json`` says ``"interrupted": true``), as a run that ended does; over a
    finished run (``--force``) the files stay in the staging directory. Returns the message line."""
    staged, out = stage.path, stage.out
    when = "during evaluation" if state["phase"] == "eval" else "after training"
    written = [name for name in RESULT_FILES if (staged / name).is_file()]
    results = len(written) == len(RESULT_FILES)
    if not results:  # never publish part of a result set
        for name in written:
            (staged / name).unlink(missing_ok=True)
    timing = {**state.get("timing", {}), "interrupted": True}
    with contextlib.suppress(TrainError), stage.writing(staged / "timing.json") as tmp:
        tmp.write_text(json.dumps(timing, indent=1))
    if run_entries(out):  # an interrupted command never replaces a finished run (--force or not)
        return (f"interrupted by Ctrl-C {when}: the run in {out} is kept; this run's trained model and config are in "
                f"{staged}" + ("" if results else " (no results)"))
    try:
        final = stage.publish()
    except TrainError as err:
        return f"interrupted by Ctrl-C {when}: the trained model is kept in {staged} ({err})"
    tail = ("with its results" if results else
            f"no results (evaluate it with: {_command()} --config {final / 'config.yaml'} --eval-only {final / 'model.zip'})")
    return (f"interrupted by Ctrl-C {when}: saved the trained model to {final / 'model.zip'} and the config to "
            f"{final / 'config.yaml'}; {tail}")


class _StopsOnCtrlC(Policy):
    """An evaluated policy that raises ``KeyboardInterrupt`` at its next step once Ctrl-C was pressed."""

    def __init__(self, policy: Policy, ctrl_c: _CtrlC) -> None:
        super().__init__(policy.platform, policy.layout, policy.rng)
        self.policy, self.ctrl_c, self.name = policy, ctrl_c, policy.name

    def reset(self, n: int, rng: np.random.Generator | None = None) -> None:
        self.ctrl_c.check()
        super().reset(n, rng)
        self.policy.reset(n, rng)

    def act_batch(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        self.ctrl_c.check()
        return self.policy.act_batch(obs)


def policy_factories(cfg: dict[str, Any], model: Any, baselines_only: bool = False,
                     ctrl_c: _CtrlC | None = None) -> dict[str, Callable[[Any], Policy]]:
    """``{name: factory(env)}`` of the policies the run evaluates: ``ppo`` (``model`` through the config's
    policy variant; not with ``baselines_only``), then, if ``eval.baselines``, ``scripted`` (when the
    config names one) and ``random``. With ``ctrl_c``, each policy stops the evaluation once Ctrl-C was
    pressed."""
    from swarm_envs.agents.policies import PolicySpec, TrainedPolicy
    from swarm_envs.agents.scripted import make_scripted

    spec = PolicySpec.from_agent(cfg["agent"])
    factories: dict[str, Callable[[Any], Policy]] = {}
    if not baselines_only:
        factories["ppo"] = lambda env: TrainedPolicy(model, env.platform, env.layout, spec, deterministic=cfg["eval"]["deterministic"])
    if cfg["eval"]["baselines"] or baselines_only:
        if cfg["agent"]["scripted"] is not None:  # a task without a scripted baseline is compared with random only
            factories["scripted"] = lambda env: make_scripted(cfg["agent"]["scripted"], env, **cfg["agent"]["scripted_kwargs"])
        factories["random"] = random_factory
    if ctrl_c is None:
        return factories
    return {name: (lambda env, f=f: _StopsOnCtrlC(f(env), ctrl_c)) for name, f in factories.items()}


def report_text(cfg: dict[str, Any], eval_kwargs: dict[str, Any], policies: list[str], seeds: list[int],
                rows: list[dict[str, Any]], source: str) -> tuple[str, str]:
    """(header, table) of ``results.md``: the policies compared, the env, ``source`` (where the PPO policy
    comes from), the task's headline metric and reductions, then the Markdown table of ``rows``."""
    from swarm_envs.agents.policies import PolicySpec

    task, spec = cfg["task"], PolicySpec.from_agent(cfg["agent"])
    best = headline(task)
    reductions = ", ".join(f"{m} {how}" for m, how in metric_reductions(task).items())
    names = ([f"PPO ({spec.name})"] if "ppo" in policies else []) + ([f"scripted ({cfg['agent']['scripted']})"] if "scripted" in policies else [])
    names += ["random"] if "random" in policies else []
    header = (
        f"# {task}: " + " vs ".join(names) + f", {len(seeds)} evaluation seeds\n\n"
        f"env: {json.dumps(eval_kwargs)}; {source}"
        + (f"; headline metric `{best[0]}` ({'higher' if best[1] > 0 else 'lower'} is better)" if best else "")
        + (f". Metrics over an episode: {reductions} (final = after the last step, mean = over the episode)" if reductions else "")
        + "; episode_return = mean per-robot return.\n\n"
    )
    return header, markdown_table(rows, n_seeds=len(seeds))


#: steps of the evaluation episode each policy runs before training (:func:`check_evaluation`)
CHECK_STEPS = 3


def check_evaluation(cfg: dict[str, Any], eval_kwargs: dict[str, Any], factories: dict[str, Callable[[Any], Policy]]) -> float:
    """Run each policy of ``factories`` for one :data:`CHECK_STEPS`-step episode (the first evaluation seed)
    through the evaluation the run ends with, and build its results table and headline, so a task that
    cannot be evaluated (e.g. a metric its ``METRICS`` declares but its env never reports) fails before
    training; returns the seconds taken. :class:`TrainError` naming the task, the policy and the problem."""
    t0 = time.perf_counter()
    task = cfg["task"]
    kwargs = {**eval_kwargs, "max_cycles": min(CHECK_STEPS, eval_kwargs.get("max_cycles") or CHECK_STEPS)}
    seeds = [cfg["eval"]["seed_start"]]
    results = {}
    for name, factory in factories.items():
        try:
            results[name] = evaluate(task, kwargs, factory, seeds)
        except Exception as err:  # whatever the task's or the policy's code raises
            if is_interrupt(err):
                raise
            text = _error_text(err)
            where = "" if task in text else f" on {task}"
            raise TrainError(f"the evaluation check before training failed (a {kwargs['max_cycles']}-step episode of "
                             f"'{name}'{where}): {text}") from None
    try:
        report_text(cfg, kwargs, list(results), seeds, summarise(results, seed=cfg["seed"]), "check")
    except Exception as err:
        raise TrainError(f"the evaluation check before training failed (the results table of {task}): {_error_text(err)}") from None
    return time.perf_counter() - t0


def _error_text(err: BaseException) -> str:
    """``err`` as one short phrase: its message, or its type with the message for a bare built-in error."""
    text = _one_line(err)
    if isinstance(err, (ValueError, TrainError)) and text:
        return text
    return f"{type(err).__name__}: {text}" if text else type(err).__name__


def _run(args: argparse.Namespace, state: dict[str, Any]) -> int:
    try:
        cfg = resolve(load_config(args.config, args.overrides))
    except ConfigError as err:
        print(_one_line(f"config error: {err}"), file=sys.stderr)
        return EXIT_BAD_INPUT

    eval_kwargs = env_kwargs_of(cfg)
    if cfg["eval"]["max_cycles"] is not None:
        eval_kwargs["max_cycles"] = cfg["eval"]["max_cycles"]
    checkpoint = model = None
    if args.eval_only and args.baselines_only:
        print("error: --eval-only and --baselines-only exclude each other", file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.eval_only:
        checkpoint = resolve_checkpoint(args.eval_only)
        out = eval_output_dir(checkpoint, args.output, args.force)
        model = load_checkpoint(checkpoint, cfg, eval_kwargs)
        check_run_config(checkpoint, cfg, eval_kwargs, args.config)
    else:
        out = Path(args.output or cfg["output_dir"])
        check_output(out, args.force)
    report_staging_dirs(out, _command())
    import torch

    torch.set_num_threads(cfg["train"]["torch_threads"])
    # everything is checked: from here on files are written, into the staging directory
    stage = state["stage"] = Staging(out)
    ctrl_c = _CtrlC()
    with ctrl_c.installed():
        return _staged_run(args, cfg, eval_kwargs, stage, checkpoint, model, state, ctrl_c)


def _staged_run(args: argparse.Namespace, cfg: dict[str, Any], eval_kwargs: dict[str, Any], stage: Staging,
                checkpoint: Path | None, model: Any, state: dict[str, Any], ctrl_c: _CtrlC) -> int:
    """The part of a command that writes: train (unless ``checkpoint`` or ``--baselines-only``), evaluate,
    write the results into the staging directory and publish it; Ctrl-C is handled by ``ctrl_c``."""
    task, out, staged = cfg["task"], stage.out, stage.path
    with stage.writing(staged / "config.yaml") as tmp:
        tmp.write_text(yaml.safe_dump(cfg, sort_keys=False))
    t_start = time.perf_counter()
    timing: dict[str, Any] = state.setdefault("timing", {})
    if checkpoint is not None:
        state.update(phase="eval-only", model=checkpoint)
        print(f"loaded {checkpoint}; writing results to {out} (staged in {staged} until the evaluation ends)")
        source = f"PPO checkpoint {checkpoint} (eval-only)"
    elif args.baselines_only:
        state.update(phase="eval-only", model="the baselines")
        print(f"evaluating the baselines into {out} (staged in {staged} until the evaluation ends)")
        source = "no RL policy (--baselines-only)"
    else:
        state["phase"] = "train"
        print(f"training into {out} (staged in {staged} until the run ends)")

        def check(untrained: Any) -> None:
            timing["check_s"] = check_evaluation(cfg, eval_kwargs, policy_factories(cfg, untrained, ctrl_c=ctrl_c))

        model, timing["train_s"], interrupted = train(cfg, stage, ctrl_c, before_learning=check)
        robot_steps = timing["robot_steps"] = model.num_timesteps * cfg["agent"]["action_repeat"]
        state["phase"] = "eval"
        with _naming(out / "learning_curve.png"):
            if plot_learning_curve(staged / "progress.csv", staged / "learning_curve.png", f"{task}: PPO learning curve"):
                print(f"wrote {out / 'learning_curve.png'}")
        if interrupted:
            with stage.writing(staged / "timing.json") as tmp:
                tmp.write_text(json.dumps(timing | {"interrupted": True}, indent=1))
            if run_entries(out):  # an interrupted command never replaces a finished run (--force or not)
                print(f"interrupted by Ctrl-C after {robot_steps} robot-steps: the run in {out} is kept; this run's "
                      f"model and config are in {staged}", file=sys.stderr)
                return EXIT_INTERRUPTED
            final = stage.publish()
            print(f"interrupted by Ctrl-C after {robot_steps} robot-steps: saved the model to {final / 'model.zip'} "
                  f"and the config to {final / 'config.yaml'}", file=sys.stderr)
            return EXIT_INTERRUPTED
        print(f"trained {robot_steps} robot-steps in {timing['train_s']:.1f} s -> {out / 'model.zip'}")
        source = f"PPO budget {cfg['train']['total_timesteps']} robot-steps ({robot_steps} run)"

    seeds = list(range(cfg["eval"]["seed_start"], cfg["eval"]["seed_start"] + cfg["eval"]["n_seeds"]))
    factories = policy_factories(cfg, model, args.baselines_only, ctrl_c)
    print(f"evaluating {', '.join(factories)} on {len(seeds)} seeds")
    t0 = time.perf_counter()
    results = {}
    for name, factory in factories.items():
        ctrl_c.check()
        results[name] = evaluate(task, eval_kwargs, factory, seeds, progress=progress_bar_on(cfg["train"]["progress_bar"]), desc=f"eval {name}")
    timing["eval_s"] = time.perf_counter() - t0
    rows = summarise(results, seed=cfg["seed"])
    header, table = report_text(cfg, eval_kwargs, list(factories), seeds, rows, source)
    with stage.writing(staged / "results.csv") as tmp:
        write_csv(rows, tmp)
    with stage.writing(staged / "results.md") as tmp:
        tmp.write_text(header + table)
    with stage.writing(staged / "per_seed.json") as tmp:
        tmp.write_text(json.dumps({p: {m: v.tolist() for m, v in r.items()} for p, r in results.items()} | {"seeds": seeds}))
    with _naming(out / "results.png"):
        plot_results(rows, staged / "results.png", f"{task} (n={len(seeds)} seeds, bootstrap 95% CI)")
    if args.render:
        with _naming(out / "episode.gif"):
            write_gif(cfg, next(iter(factories.values())), staged / "episode.gif", seeds[0])
        print(f"wrote {out / 'episode.gif'}")
    timing["total_s"] = time.perf_counter() - t_start
    with stage.writing(staged / "timing.json") as tmp:
        tmp.write_text(json.dumps(timing, indent=1))
    final = stage.publish(replace=args.force)
    state.update(stage=None, phase="done", final=final)
    print(f"\n{header}{table}")
    if final != stage.out:
        print(f"another run finished into {out} first: this run is kept in {final}", file=sys.stderr)
    print(f"wrote {final / 'results.csv'}, {final / 'results.md'}, {final / 'results.png'}; timing {json.dumps({k: round(v, 1) for k, v in timing.items()})}")
    if ctrl_c.requested:
        print(f"interrupted by Ctrl-C after the evaluation had ended: the complete run is in {final}", file=sys.stderr)
        return EXIT_INTERRUPTED
    return 0


if __name__ == "__main__":
    sys.exit(main())
