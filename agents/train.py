"""Train one PPO policy shared by all robots of a swarm task, then compare it with the scripted baseline and
a random policy on the task metrics.

    python train.py --config configs/aggregation.yaml [--output DIR] [--render] [--set key=value ...]
    python train.py --config configs/aggregation.yaml --eval-only CHECKPOINT [--output DIR [--force]]

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

``--eval-only`` never overwrites a training run: it writes into ``eval-<UTC timestamp>/`` beside the checkpoint
(in the run directory when the checkpoint is in ``checkpoints/``), or into ``--output``, which must not already
hold results unless ``--force`` is given.

Ctrl-C during training saves the current model (``model.zip``) and the resolved config, then exits with
code 130 and a one-line message. Bad input (output directory, checkpoint) gives a one-line error and exit code 2.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import math
import os
import signal
import sys
import threading
import time
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from swarm_envs.agents.config import ConfigError, load_config, resolve
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

__all__ = ["main", "TrainError", "planned_timesteps", "load_checkpoint", "plot_learning_curve", "is_interrupt"]

#: exit code after Ctrl-C (128 + SIGINT), as shells report it
EXIT_INTERRUPTED = 130
#: exit code of bad input (config, output directory, checkpoint)
EXIT_BAD_INPUT = 2
RESULT_FILES = ("results.csv", "results.md", "per_seed.json")


class TrainError(Exception):
    """Bad input found by train.py (output directory, checkpoint); reported as one line, exit code 2."""


def is_interrupt(err: BaseException) -> bool:
    """Whether ``err`` is Ctrl-C: a ``KeyboardInterrupt``, or the ``SystemError`` CPython raises in its place
    when the signal arrives just as a compiled (numba) function returns ("... returned a result with an
    exception set", caused by the ``KeyboardInterrupt``)."""
    if isinstance(err, KeyboardInterrupt):
        return True
    return isinstance(err, SystemError) and isinstance(err.__cause__ or err.__context__, KeyboardInterrupt)


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


def build_model(cfg: dict[str, Any], vec_env):
    """A PPO model for ``vec_env`` from the ``agent`` section."""
    import torch
    from stable_baselines3 import PPO

    a = cfg["agent"]
    activation = {"tanh": torch.nn.Tanh, "relu": torch.nn.ReLU}[a["activation"]]
    return PPO(
        "MlpPolicy",
        vec_env,
        learning_rate=a["learning_rate"],
        n_steps=a["n_steps"],
        batch_size=a["batch_size"],
        n_epochs=a["n_epochs"],
        gamma=a["gamma"],
        gae_lambda=a["gae_lambda"],
        clip_range=a["clip_range"],
        ent_coef=a["ent_coef"],
        vf_coef=a["vf_coef"],
        max_grad_norm=a["max_grad_norm"],
        policy_kwargs={"net_arch": list(a["net_arch"]), "activation_fn": activation, "log_std_init": a["log_std_init"]},
        seed=cfg["seed"],
        device="cpu",
        verbose=0,
    )


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


def _progress_writer(total: int):
    """An SB3 logger output that prints one short line per ~10 % of ``total`` robot-steps (and the last)."""
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
            parts = [f"PPO {done}/{total} robot-steps ({100 * done / total:.0f}%)"]
            for key, label, fmt in (("rollout/ep_rew_mean", "ep_rew_mean", ".4g"), ("rollout/ep_len_mean", "ep_len", ".4g"),
                                    ("time/fps", "fps", ".0f"), ("train/loss", "loss", ".3g")):
                if key in key_values:
                    parts.append(f"{label} {key_values[key]:{fmt}}")
            _say("  ".join(parts))

        def close(self) -> None:
            pass

    return ProgressLine()


def make_logger(out: Path, total: int, progress_lines: bool):
    """SB3 logger: ``progress.csv`` always, TensorBoard if installed, short progress lines if asked."""
    from stable_baselines3.common.logger import Logger, make_output_format

    formats = [make_output_format("csv", str(out))]
    if importlib.util.find_spec("tensorboard") is not None:
        formats.append(make_output_format("tensorboard", str(out / "tensorboard")))
    if progress_lines:
        formats.append(_progress_writer(total))
    return Logger(folder=str(out), output_formats=formats)


def make_callbacks(cfg: dict[str, Any], out: Path, num_envs: int, total: int):
    """Checkpoints every ``train.checkpoint_freq`` robot-steps and a tqdm bar over the real ``total``."""
    from stable_baselines3.common.callbacks import BaseCallback, CallbackList, CheckpointCallback

    callbacks = []
    freq = cfg["train"]["checkpoint_freq"]
    if freq > 0:
        callbacks.append(CheckpointCallback(save_freq=max(1, freq // num_envs), save_path=str(out / "checkpoints"), name_prefix="ppo"))
    if cfg["train"]["progress_bar"]:

        class TqdmCallback(BaseCallback):
            """Progress bar over robot-steps with the latest mean episode return."""

            bar = None

            def _on_training_start(self) -> None:
                from tqdm import tqdm

                self.bar = tqdm(total=total, desc="PPO", unit="step", dynamic_ncols=True)

            def _on_step(self) -> bool:
                self.bar.update(self.training_env.num_envs)
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


def train(cfg: dict[str, Any], out: Path) -> tuple[Any, float, bool]:
    """Train PPO and save ``out/model.zip``; returns (model, seconds, interrupted by Ctrl-C)."""
    from swarm_envs.agents.sb3_vec_env import SwarmVecEnv

    venv = SwarmVecEnv(env_id(cfg["task"]), cfg["train"]["n_envs"], env_kwargs_of(cfg), n_workers=cfg["train"]["n_workers"])
    venv.seed(cfg["seed"])
    wrapped = venv if cfg["agent"]["reward_scale"] == 1.0 else _ScaledRewards(venv, cfg["agent"]["reward_scale"])
    model = build_model(cfg, wrapped)
    budget = cfg["train"]["total_timesteps"]
    total = planned_timesteps(budget, cfg["agent"]["n_steps"], venv.num_envs)
    if total != budget:
        _say(f"training {total} robot-steps: the budget {budget} rounded up to {total // (cfg['agent']['n_steps'] * venv.num_envs)} "
             f"whole rollouts of {cfg['agent']['n_steps']} steps x {venv.num_envs} robots")
    logger = make_logger(out, total, progress_lines=True)
    model.set_logger(logger)
    callbacks = make_callbacks(cfg, out, venv.num_envs, total)
    interrupted = False
    t0 = time.perf_counter()
    try:
        model.learn(budget, callback=callbacks)  # SB3 dumps a row per iteration, before that iteration's update
    except (KeyboardInterrupt, SystemError) as err:
        if not is_interrupt(err):
            raise
        interrupted = True
        if threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGINT, signal.SIG_IGN)  # a second Ctrl-C must not cut the save short
    finally:
        for cb in callbacks.callbacks:
            if hasattr(cb, "close"):
                cb.close()
        logger.close()
    seconds = time.perf_counter() - t0
    model.save(out / "model.zip")
    venv.close()
    return model, seconds, interrupted


def _read_progress(path: Path) -> dict[str, np.ndarray]:
    import csv

    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    keys = rows[0].keys() if rows else []
    return {k: np.array([float(r[k]) if r.get(k) not in (None, "") else np.nan for r in rows]) for k in keys}


def plot_learning_curve(csv_path: str | Path, png_path: str | Path, title: str) -> bool:
    """Plot ``progress.csv`` (mean episode return, episode length, losses vs robot-steps); False if no data."""
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
    fig.savefig(png_path, dpi=110)
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
    fig.savefig(path, dpi=110)
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
    imageio.mimsave(path, [np.asarray(f) for f in frames if f is not None], duration=100, loop=0)


def prepare_output(out: Path) -> None:
    """Create ``out`` (and parents); :class:`TrainError` if it is a file or cannot be written."""
    if out.exists() and not out.is_dir():
        raise TrainError(f"output directory '{out}' exists and is a file, not a directory")
    try:
        out.mkdir(parents=True, exist_ok=True)
        probe = out / f".write-test-{os.getpid()}"
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as err:
        raise TrainError(f"output directory '{out}' is not writable: {err.strerror or err}") from None


def eval_output_dir(checkpoint: Path, output: str | None, force: bool) -> Path:
    """Where ``--eval-only`` writes: ``output`` (refused if it holds results, unless ``force``), else a new
    ``eval-<UTC timestamp>`` directory beside the checkpoint (its run directory for ``checkpoints/*.zip``)."""
    if output is not None:
        out = Path(output)
        existing = [name for name in RESULT_FILES if (out / name).exists()]
        if existing and not force:
            raise TrainError(f"output directory '{out}' already holds results ({', '.join(existing)}); "
                             "choose another --output, omit it (a new eval-<timestamp> directory), or add --force")
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
    if not p.exists() and p.suffix != ".zip" and p.with_name(p.name + ".zip").is_file():
        p = p.with_name(p.name + ".zip")
    if not p.exists():
        raise TrainError(f"checkpoint '{path}' not found")
    if not p.is_file():
        raise TrainError(f"checkpoint '{p}' is a directory, not a model .zip")
    return p


def load_checkpoint(path: Path, cfg: dict[str, Any], env_kwargs: dict[str, Any]):
    """Load a PPO ``.zip`` and check it fits the config's env; :class:`TrainError` with one line otherwise."""
    from stable_baselines3 import PPO

    if not zipfile.is_zipfile(path):
        raise TrainError(f"checkpoint '{path}' is not a zip archive (truncated, or not a stable-baselines3 model)")
    try:
        model = PPO.load(path, device="cpu")
    except Exception as err:  # SB3 raises many kinds (KeyError, BadZipFile, ValueError, pickle errors)
        detail = str(err).strip().splitlines()[0] if str(err).strip() else ""
        raise TrainError(f"checkpoint '{path}' cannot be loaded as a PPO model ({type(err).__name__}{': ' + detail if detail else ''})") from None
    env = make_env(cfg["task"], **{**env_kwargs, "flatten": True})
    agent = env.possible_agents[0]
    obs_shape, act_shape = env.observation_space(agent).shape, env.action_space(agent).shape
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


def _size(shape: tuple[int, ...] | None) -> str:
    return "x".join(str(s) for s in shape) if shape else "?"


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--config", required=True, help="YAML config, e.g. configs/aggregation.yaml")
    parser.add_argument("--output", default=None,
                        help="output directory (default: the config's output_dir; with --eval-only: a new "
                             "eval-<timestamp> directory beside the checkpoint)")
    parser.add_argument("--render", action="store_true", help="write a GIF of one evaluation episode")
    parser.add_argument("--eval-only", metavar="CHECKPOINT", default=None, help="skip training; evaluate this PPO .zip")
    parser.add_argument("--force", action="store_true", help="with --eval-only: allow --output to overwrite existing results")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                        help="override a config value (dotted key), e.g. train.total_timesteps=2000; repeatable")
    return parser


def main(argv: list[str] | None = None) -> int:
    """Command line of ``train.py``; returns the exit code (0 ok, 2 bad input, 130 interrupted)."""
    args = _parser().parse_args(argv)
    state: dict[str, Any] = {"phase": "setup"}
    try:
        return _run(args, state)
    except TrainError as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except (KeyboardInterrupt, SystemError) as err:
        if not is_interrupt(err):
            raise
        where = {"setup": "before training started; nothing saved",
                 "train": "while setting up training; nothing saved",
                 "eval": f"during evaluation; the model is saved in {state.get('model', '?')}",
                 "eval-only": f"during the evaluation of {state.get('model', '?')}; results are incomplete"}[state["phase"]]
        print(f"interrupted by Ctrl-C {where}", file=sys.stderr)
        return EXIT_INTERRUPTED


def _run(args: argparse.Namespace, state: dict[str, Any]) -> int:
    try:
        cfg = resolve(load_config(args.config, args.overrides))
    except ConfigError as err:
        print(f"config error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.force and not args.eval_only:
        raise TrainError("--force only applies to --eval-only (training always writes into its output directory)")

    task = cfg["task"]
    eval_kwargs = env_kwargs_of(cfg)
    if cfg["eval"]["max_cycles"] is not None:
        eval_kwargs["max_cycles"] = cfg["eval"]["max_cycles"]
    import torch

    torch.set_num_threads(cfg["train"]["torch_threads"])
    checkpoint = model = None
    if args.eval_only:
        checkpoint = resolve_checkpoint(args.eval_only)
        out = eval_output_dir(checkpoint, args.output, args.force)
        model = load_checkpoint(checkpoint, cfg, eval_kwargs)
    else:
        out = Path(args.output or cfg["output_dir"])
    prepare_output(out)
    with open(out / "config.yaml", "w") as fh:
        yaml.safe_dump(cfg, fh, sort_keys=False)
    t_start = time.perf_counter()

    from swarm_envs.agents.sb3_vec_env import SB3Policy
    from swarm_envs.agents.scripted import make_scripted

    timing: dict[str, float] = {}
    if checkpoint is not None:
        state.update(phase="eval-only", model=checkpoint)
        print(f"loaded {checkpoint}; writing results to {out}")
    else:
        state["phase"] = "train"
        model, timing["train_s"], interrupted = train(cfg, out)
        timing["robot_steps"] = model.num_timesteps
        state.update(phase="eval", model=out / "model.zip")
        if plot_learning_curve(out / "progress.csv", out / "learning_curve.png", f"{task}: PPO learning curve"):
            print(f"wrote {out / 'learning_curve.png'}")
        if interrupted:
            with open(out / "config.yaml", "w") as fh:
                yaml.safe_dump(cfg, fh, sort_keys=False)
            with open(out / "timing.json", "w") as fh:
                json.dump(timing | {"interrupted": True}, fh, indent=1)
            print(f"interrupted by Ctrl-C after {model.num_timesteps} robot-steps: saved the model to {out / 'model.zip'} "
                  f"and the config to {out / 'config.yaml'}", file=sys.stderr)
            return EXIT_INTERRUPTED
        print(f"trained {model.num_timesteps} robot-steps in {timing['train_s']:.1f} s -> {out / 'model.zip'}")

    seeds = list(range(cfg["eval"]["seed_start"], cfg["eval"]["seed_start"] + cfg["eval"]["n_seeds"]))
    factories = {"ppo": lambda env: SB3Policy(model, env.platform, env.layout, deterministic=cfg["eval"]["deterministic"])}
    if cfg["agent"]["scripted"] is not None:  # a task without a scripted baseline is compared with random only
        factories["scripted"] = lambda env: make_scripted(cfg["agent"]["scripted"], env, **cfg["agent"]["scripted_kwargs"])
    factories["random"] = random_factory
    t0 = time.perf_counter()
    results = {name: evaluate(task, eval_kwargs, f, seeds, progress=cfg["train"]["progress_bar"], desc=f"eval {name}")
               for name, f in factories.items()}
    timing["eval_s"] = time.perf_counter() - t0
    rows = summarise(results, seed=cfg["seed"])
    write_csv(rows, out / "results.csv")
    best = headline(task)
    reductions = ", ".join(f"{m} {how}" for m, how in metric_reductions(task).items())
    header = (
        f"# {task}: PPO vs " + (f"scripted ({cfg['agent']['scripted']}) vs " if "scripted" in factories else "") +
        f"random, {len(seeds)} evaluation seeds\n\n"
        f"env: {json.dumps(eval_kwargs)}; "
        + (f"PPO checkpoint {checkpoint} (eval-only)" if checkpoint else
           f"PPO budget {cfg['train']['total_timesteps']} robot-steps ({model.num_timesteps} run)")
        + (f"; headline metric `{best[0]}` ({'higher' if best[1] > 0 else 'lower'} is better)" if best else "")
        + (f". Metrics over an episode: {reductions} (final = after the last step, mean = over the episode)" if reductions else "")
        + "; episode_return = mean per-robot return.\n\n"
    )
    table = markdown_table(rows, n_seeds=len(seeds))
    (out / "results.md").write_text(header + table)
    with open(out / "per_seed.json", "w") as fh:
        json.dump({p: {m: v.tolist() for m, v in r.items()} for p, r in results.items()} | {"seeds": seeds}, fh)
    plot_results(rows, out / "results.png", f"{task} (n={len(seeds)} seeds, bootstrap 95% CI)")
    if args.render:
        write_gif(cfg, factories["ppo"], out / "episode.gif", seeds[0])
        print(f"wrote {out / 'episode.gif'}")
    timing["total_s"] = time.perf_counter() - t_start
    with open(out / "timing.json", "w") as fh:
        json.dump(timing, fh, indent=1)
    print(f"\n{header}{table}")
    print(f"wrote {out / 'results.csv'}, {out / 'results.md'}, {out / 'results.png'}; timing {json.dumps({k: round(v, 1) for k, v in timing.items()})}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
