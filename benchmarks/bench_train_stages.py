"""Where the time of PPO training goes: env steps, the SB3 adapter, SB3's rollout collection, PPO updates.

Runs ``agents.train.train`` on a config (the numba kernels compiled by one warm-up step first) with a wall
clock timer around each stage, and prints each stage's seconds and share of the ``model.learn`` time:

- ``env step`` / ``env reset``: the batched core (``CoreBatch.step`` / ``reset``: act, physics,
  sensing, observations, rewards, infos; only with ``train.n_workers = 1``, where it runs in this process);
- ``adapter``: ``SwarmVecEnv.step_wait`` minus the env calls inside it (reshapes, the per-row info list);
- ``rollout, policy forward`` and ``rollout, buffer add``: SB3's own per-step work in ``collect_rollouts``;
- ``rollout, rest``: the rest of ``collect_rollouts`` (tensor conversion, episode-info buffer, callbacks,
  the value of truncated rows' last observations);
- ``PPO update``: ``PPO.train`` (the epochs of minibatch gradient steps);
- ``rest``: ``learn`` outside both and the first reset (logging, checkpoints).

    python benchmarks/bench_train_stages.py                                   # configs/aggregation.yaml, 51200 robot-steps
    python benchmarks/bench_train_stages.py --set train.total_timesteps=102400 --set train.n_workers=2
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default="configs/aggregation.yaml")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="config override, as in train.py")
    args = parser.parse_args()

    from stable_baselines3 import PPO
    from stable_baselines3.common.buffers import RolloutBuffer
    from stable_baselines3.common.policies import ActorCriticPolicy

    import swarm_envs
    from swarm_envs.adapters.batch import CoreBatch
    from swarm_envs.agents import train as train_mod
    from swarm_envs.agents.config import env_kwargs_of, load_config
    from swarm_envs.agents.staging import Staging
    from swarm_envs.agents.tasks import env_id
    from swarm_envs.agents.sb3_vec_env import SwarmVecEnv

    overrides = ["train.total_timesteps=51200", "train.checkpoint_freq=0", "train.progress_bar=false", *args.set]
    cfg = load_config(args.config, overrides)
    warm = swarm_envs.make_vec(env_id(cfg["task"]), 1, **{**env_kwargs_of(cfg), "flatten": True})
    warm.reset(seed=0)
    warm.step(np.zeros((1, warm.n_agents, warm.layout.action_size)))  # compile the kernels outside the timing

    seconds: dict[str, float] = {}

    def timed(cls: type, name: str, key: str) -> None:
        inner = getattr(cls, name)

        def wrapper(*a, **k):
            t = time.perf_counter()
            try:
                return inner(*a, **k)
            finally:
                seconds[key] = seconds.get(key, 0.0) + time.perf_counter() - t

        setattr(cls, name, wrapper)

    timed(CoreBatch, "step", "env step")
    timed(CoreBatch, "reset", "env reset")
    timed(SwarmVecEnv, "step_wait", "step_wait")
    inside = {"resets": 0.0}
    outer_reset = CoreBatch.reset

    def reset_in_step(self, *a, **k):  # the resets at episode ends happen inside step_wait
        before = seconds.get("env reset", 0.0)
        try:
            return outer_reset(self, *a, **k)
        finally:
            if in_step_wait[0]:
                inside["resets"] += seconds["env reset"] - before

    CoreBatch.reset = reset_in_step
    in_step_wait = [False]
    timed_step_wait = SwarmVecEnv.step_wait

    def flagged(self):
        in_step_wait[0] = True
        try:
            return timed_step_wait(self)
        finally:
            in_step_wait[0] = False

    SwarmVecEnv.step_wait = flagged
    timed(ActorCriticPolicy, "forward", "rollout, policy forward")
    timed(RolloutBuffer, "add", "rollout, buffer add")
    timed(PPO, "collect_rollouts", "collect_rollouts")
    timed(PPO, "train", "PPO update")
    timed(PPO, "learn", "learn")

    with tempfile.TemporaryDirectory() as tmp:
        stage = Staging(Path(tmp) / "run")
        model, _, _ = train_mod.train(cfg, stage)
    learn = seconds["learn"]
    in_learn = {k: v for k, v in seconds.items() if k != "learn"}
    reset_in_steps = inside["resets"]
    rows = {
        "env step": in_learn.get("env step", 0.0),
        "env reset": in_learn.get("env reset", 0.0),
        "adapter": in_learn["step_wait"] - in_learn.get("env step", 0.0) - reset_in_steps if "env step" in in_learn else 0.0,
        "rollout, policy forward": in_learn["rollout, policy forward"],
        "rollout, buffer add": in_learn["rollout, buffer add"],
        "rollout, rest": in_learn["collect_rollouts"] - in_learn["step_wait"] - in_learn["rollout, policy forward"] - in_learn["rollout, buffer add"],
        "PPO update": in_learn["PPO update"],
        "rest": learn - in_learn["collect_rollouts"] - in_learn["PPO update"] - (in_learn.get("env reset", 0.0) - reset_in_steps),
    }
    if "env step" not in in_learn:  # worker processes: the env time is only visible as step_wait
        rows["env step + adapter (workers)"] = in_learn["step_wait"]
    steps = model.num_timesteps
    print(f"{args.config} {' '.join(args.set)}: {steps} robot-steps in {learn:.2f} s of learn = {steps / learn:,.0f} robot-steps/s "
          f"(load {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)")
    print("| stage | s | share |\n|---|---|---|")
    for key, value in rows.items():
        print(f"| {key} | {value:.2f} | {100 * value / learn:.1f} % |")
    checksum = sum(float(v.double().sum()) for v in model.policy.state_dict().values())
    print(f"policy parameter sum (same seed and config, same training: same sum): {checksum:.12f}")


if __name__ == "__main__":
    main()
