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
  no longer runs (:func:`swarm_envs.agents.staging.staging_dirs`).

``--eval-only`` writes into ``eval-<UTC timestamp>/`` beside the checkpoint (in the run directory when the
checkpoint is in ``checkpoints/``), or into ``--output``, with the same rules (never the checkpoint's own
directory). The checkpoint's run (its ``config.yaml``) must have trained the config's task, platform,
observation and action spaces and policy variant (:func:`swarm_envs.agents.checkpoints.check_run_config`).

Ctrl-C during training saves the current model (``model.zip``), the learning curve and the resolved
config, moves them into DIR, then exits with code 130 and a one-line message; worker processes
(``train.n_workers``) ignore Ctrl-C and are closed by the trainer. Ctrl-C once the model is saved (during
the final evaluation) does the same with the trained model: it is published into DIR with its config and
learning curve (and the results, if all were written), and the line gives the ``--eval-only`` command that
evaluates it. An interrupted command never replaces a finished run: over one (``--force``) its files stay
in the staging directory, which the line names. Ctrl-C before training or during an ``--eval-only``
evaluation writes nothing.

This module runs the command; its parts live beside it: run directories (:mod:`swarm_envs.agents.staging`),
Ctrl-C and exit codes (:mod:`swarm_envs.agents.signals`), the progress line and logger
(:mod:`swarm_envs.agents.training_log`), figures (:mod:`swarm_envs.agents.figures`) and reading runs back
(:mod:`swarm_envs.agents.checkpoints`).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import signal
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from swarm_envs.agents.base import Policy
from swarm_envs.agents.config import ConfigError, env_kwargs_of, load_config, progress_bar_on, resolve
from swarm_envs.agents.tasks import env_id, headline, metric_reductions
from swarm_envs.agents.evaluation import evaluate, markdown_table, random_factory, summarise, write_csv
from swarm_envs.agents.staging import RESULT_FILES, Staging, TrainError, errors_naming, check_output, clean_staging_dirs, eval_output_dir, report_staging_dirs, run_entries
from swarm_envs.agents.signals import CtrlC, EXIT_BAD_INPUT, EXIT_INTERRUPTED, is_interrupt, one_line, sigint_ignored
from swarm_envs.agents.training_log import say, make_callbacks, make_logger, rate_callback
from swarm_envs.agents.figures import plot_learning_curve, plot_results, write_gif
from swarm_envs.agents.checkpoints import check_run_config, load_checkpoint, resolve_checkpoint

__all__ = ["main", "planned_timesteps", "policy_factories", "report_text", "check_evaluation", "CHECK_STEPS"]


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


def train(cfg: dict[str, Any], stage: Staging, ctrl_c: CtrlC | None = None,
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
    ctrl_c = ctrl_c or CtrlC()
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
            say(f"training {total * repeat} robot-steps: the budget {cfg['train']['total_timesteps']} rounded up to "
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


def _command() -> str:
    """How the user runs this command, for the messages: ``swarm-train`` or ``python train.py``."""
    return "swarm-train" if os.path.basename(sys.argv[0] or "") == "swarm-train" else "python train.py"


def _parser() -> argparse.ArgumentParser:
    from swarm_envs.tasks.settings_cli import OneLineArgumentParser

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
        print(one_line(f"error: {text}{note}"), file=sys.stderr)
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
    print(one_line(f"error: unexpected {type(err).__name__} during {state['phase']}: {err}{note}{hint}"), file=sys.stderr)
    return EXIT_BAD_INPUT


def _interrupted(state: dict[str, Any]) -> int:
    """One line after Ctrl-C outside training (further Ctrl-C ignored meanwhile). Once the trained model is
    saved, the run so far is published (:func:`_publish_interrupted`); before that, and in an ``--eval-only``
    or ``--baselines-only`` evaluation, nothing is kept."""
    with sigint_ignored():
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
        print(one_line(line), file=sys.stderr)
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

    def __init__(self, policy: Policy, ctrl_c: CtrlC) -> None:
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
                     ctrl_c: CtrlC | None = None) -> dict[str, Callable[[Any], Policy]]:
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
    text = one_line(err)
    if isinstance(err, (ValueError, TrainError)) and text:
        return text
    return f"{type(err).__name__}: {text}" if text else type(err).__name__


def _run(args: argparse.Namespace, state: dict[str, Any]) -> int:
    # Ctrl-C from the start is handled by a CtrlC, which notes the first press: raised at once, a press during
    # the checks could land in a finalizer (pymunk frees its bodies in cffi finalizers) and be dropped there
    ctrl_c = CtrlC()
    with ctrl_c.installed():
        return _checked_run(args, state, ctrl_c)


def _checked_run(args: argparse.Namespace, state: dict[str, Any], ctrl_c: CtrlC) -> int:
    """Check the config, the output directory and the checkpoint, then :func:`_staged_run`; a Ctrl-C noted
    by ``ctrl_c`` during the checks stops the command before anything is written."""
    try:
        cfg = resolve(load_config(args.config, args.overrides))
    except ConfigError as err:
        print(one_line(f"config error: {err}"), file=sys.stderr)
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
    ctrl_c.check()  # Ctrl-C during the checks: nothing written
    # everything is checked: from here on files are written, into the staging directory
    stage = state["stage"] = Staging(out)
    return _staged_run(args, cfg, eval_kwargs, stage, checkpoint, model, state, ctrl_c)


def _staged_run(args: argparse.Namespace, cfg: dict[str, Any], eval_kwargs: dict[str, Any], stage: Staging,
                checkpoint: Path | None, model: Any, state: dict[str, Any], ctrl_c: CtrlC) -> int:
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
        with errors_naming(out / "learning_curve.png"):
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
    with errors_naming(out / "results.png"):
        plot_results(rows, staged / "results.png", f"{task} (n={len(seeds)} seeds, bootstrap 95% CI)")
    if args.render:
        with errors_naming(out / "episode.gif"):
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
