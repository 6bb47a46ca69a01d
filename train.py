#!/usr/bin/env python
"""Train one PPO policy shared by all robots of a swarm task, then compare it with the scripted baseline and
a random policy on the task metrics.

    python train.py --config configs/aggregation.yaml [--output DIR] [--render] [--eval-only CHECKPOINT]
                    [--set key=value ...]      # e.g. --set train.total_timesteps=2000 --set env.sensing=ideal

Writes into DIR (``output_dir`` of the config unless ``--output``): ``config.yaml`` (resolved), checkpoints
``checkpoints/ppo_<steps>_steps.zip`` and ``model.zip``, ``results.csv`` (columns
``policy,metric,mean,ci_low,ci_high``; policies ``ppo``, ``scripted``, ``random``), ``results.md``,
``results.png`` and, with ``--render``, ``episode.gif`` (one evaluation episode of the PPO policy).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from swarm_envs.agents.config import ConfigError, load_config, resolve
from swarm_envs.agents.evaluation import (
    PRIMARY_METRIC,
    TASKS,
    evaluate,
    make_env,
    markdown_table,
    random_factory,
    run_episode,
    summarise,
    write_csv,
)


def env_kwargs_of(cfg: dict[str, Any]) -> dict[str, Any]:
    kwargs = dict(cfg["env"])
    if isinstance(kwargs.get("code"), list):
        kwargs["code"] = tuple(kwargs["code"])
    return kwargs


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


def make_callbacks(cfg: dict[str, Any], out: Path, num_envs: int):
    from stable_baselines3.common.callbacks import BaseCallback, CallbackList, CheckpointCallback

    callbacks = []
    freq = cfg["train"]["checkpoint_freq"]
    if freq > 0:
        callbacks.append(CheckpointCallback(save_freq=max(1, freq // num_envs), save_path=str(out / "checkpoints"), name_prefix="ppo"))
    if cfg["train"]["progress_bar"]:

        class TqdmCallback(BaseCallback):
            """Progress bar over robot-steps with the latest mean episode return."""

            def _on_training_start(self) -> None:
                from tqdm import tqdm

                self.bar = tqdm(total=self.locals["total_timesteps"], desc="PPO", unit="step", dynamic_ncols=True)

            def _on_step(self) -> bool:
                self.bar.update(self.training_env.num_envs)
                buf = self.model.ep_info_buffer
                if buf and self.n_calls % 50 == 0:
                    self.bar.set_postfix(ep_rew=f"{np.mean([e['r'] for e in buf]):.3g}")
                return True

            def _on_training_end(self) -> None:
                self.bar.close()

        callbacks.append(TqdmCallback())
    return CallbackList(callbacks)


def train(cfg: dict[str, Any], out: Path):
    """Train PPO; returns (model, seconds)."""
    from swarm_envs.agents.sb3_vec_env import SwarmVecEnv

    module = __import__(TASKS[cfg["task"]], fromlist=["parallel_env"])
    venv = SwarmVecEnv(module.parallel_env, cfg["train"]["n_envs"], env_kwargs_of(cfg))
    venv.seed(cfg["seed"])
    wrapped = venv if cfg["agent"]["reward_scale"] == 1.0 else _ScaledRewards(venv, cfg["agent"]["reward_scale"])
    model = build_model(cfg, wrapped)
    t0 = time.perf_counter()
    model.learn(cfg["train"]["total_timesteps"], callback=make_callbacks(cfg, out, venv.num_envs))
    seconds = time.perf_counter() - t0
    model.save(out / "model.zip")
    venv.close()
    return model, seconds


def plot_results(rows: list[dict[str, Any]], path: Path, title: str) -> None:
    """One bar panel per metric (policies side by side) with 95 % CI error bars."""
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
        ax.bar(policies, means, yerr=err, capsize=4, color=["tab:blue", "tab:green", "tab:gray"][: len(policies)])
        ax.set_title(m, fontsize=9)
        ax.tick_params(labelsize=8)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write_gif(cfg: dict[str, Any], policy_factory, path: Path, seed: int) -> None:
    import imageio.v2 as imageio

    kwargs = {**env_kwargs_of(cfg), "render_mode": "rgb_array"}
    if cfg["eval"]["max_cycles"] is not None:
        kwargs["max_cycles"] = cfg["eval"]["max_cycles"]
    env = make_env(cfg["task"], **kwargs)
    frames: list = []
    run_episode(env, policy_factory(env), seed, cfg["task"], frames=frames)
    env.close()
    imageio.mimsave(path, [np.asarray(f) for f in frames if f is not None], duration=100, loop=0)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--config", required=True, help="YAML config, e.g. configs/aggregation.yaml")
    parser.add_argument("--output", default=None, help="output directory (default: the config's output_dir)")
    parser.add_argument("--render", action="store_true", help="write a GIF of one evaluation episode")
    parser.add_argument("--eval-only", metavar="CHECKPOINT", default=None, help="skip training; evaluate this PPO .zip")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                        help="override a config value (dotted key), e.g. train.total_timesteps=2000; repeatable")
    args = parser.parse_args(argv)
    try:
        cfg = resolve(load_config(args.config, args.overrides))
    except ConfigError as err:
        print(f"config error: {err}", file=sys.stderr)
        return 2

    import torch

    torch.set_num_threads(cfg["train"]["torch_threads"])
    out = Path(args.output or cfg["output_dir"])
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "config.yaml", "w") as fh:
        yaml.safe_dump(cfg, fh, sort_keys=False)
    t_start = time.perf_counter()

    from stable_baselines3 import PPO

    from swarm_envs.agents.sb3_vec_env import SB3Policy
    from swarm_envs.agents.scripted import make_scripted

    timing: dict[str, float] = {}
    if args.eval_only:
        model = PPO.load(args.eval_only, device="cpu")
        print(f"loaded {args.eval_only}")
    else:
        model, timing["train_s"] = train(cfg, out)
        print(f"trained {cfg['train']['total_timesteps']} robot-steps in {timing['train_s']:.1f} s -> {out / 'model.zip'}")

    task = cfg["task"]
    eval_kwargs = env_kwargs_of(cfg)
    if cfg["eval"]["max_cycles"] is not None:
        eval_kwargs["max_cycles"] = cfg["eval"]["max_cycles"]
    seeds = list(range(cfg["eval"]["seed_start"], cfg["eval"]["seed_start"] + cfg["eval"]["n_seeds"]))
    factories = {
        "ppo": lambda env: SB3Policy(model, env.platform, env.layout, deterministic=cfg["eval"]["deterministic"]),
        "scripted": lambda env: make_scripted(cfg["agent"]["scripted"], env, **cfg["agent"]["scripted_kwargs"]),
        "random": random_factory,
    }
    t0 = time.perf_counter()
    results = {name: evaluate(task, eval_kwargs, f, seeds, progress=cfg["train"]["progress_bar"], desc=f"eval {name}")
               for name, f in factories.items()}
    timing["eval_s"] = time.perf_counter() - t0
    rows = summarise(results)
    write_csv(rows, out / "results.csv")
    primary, sign = PRIMARY_METRIC[task]
    header = (
        f"# {task}: PPO vs scripted ({cfg['agent']['scripted']}) vs random\n\n"
        f"env: {json.dumps(eval_kwargs)}; "
        + (f"PPO checkpoint {args.eval_only} (eval-only)" if args.eval_only else f"PPO budget {cfg['train']['total_timesteps']} robot-steps")
        + f"; headline metric `{primary}` "
        f"({'higher' if sign > 0 else 'lower'} is better). Final-step values except flocking metrics "
        "(mean over the episode); episode_return = mean per-robot return.\n\n"
    )
    table = markdown_table(rows, n_seeds=len(seeds))
    (out / "results.md").write_text(header + table)
    with open(out / "per_seed.json", "w") as fh:
        json.dump({p: {m: v.tolist() for m, v in r.items()} for p, r in results.items()} | {"seeds": seeds}, fh)
    plot_results(rows, out / "results.png", f"{task} ({len(seeds)} seeds, 95% CI)")
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
