"""Rollout throughput of the batched TorchRL env (``swarm_envs.make_torchrl``) against raw ``make_vec``.

Times, in the same run and alternated round by round (so every ratio sees the same machine load):

- ``make_vec``: ``SwarmVectorEnv.step`` with uniform random actions (drawn inside the timed loop);
- ``make_torchrl rollout``: ``SwarmTorchRLEnv.rollout(T, auto_reset=False, tensordict=...)`` with TorchRL's
  random policy (``action_spec.rand``), i.e. everything a TorchRL rollout does per step;
- ``PettingZooWrapper rollout``: TorchRL's stock wrapper around one single env (B = 1, in ``FlatInfos``), for reference.

Each round runs T steps of each, continuing the same episodes (no resets are timed); the table gives the median agent-steps/s (robots x copies x steps per
second) over the rounds and the median of the per-round ratios to ``make_vec``.

    python benchmarks/bench_torchrl.py                            # N = 10, B = 64, full sensing, 5 rounds
    python benchmarks/bench_torchrl.py --copies 256 --sensing ideal --rounds 3
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
import warnings

import numpy as np

os.environ.setdefault("OMP_NUM_THREADS", "1")

import swarm_envs  # noqa: E402
from swarm_envs.adapters.env import FlatInfos  # noqa: E402

TASK = "swarm_envs/Flocking-v0"


def time_make_vec(vec, steps: int, rng: np.random.Generator) -> float:
    """Seconds for ``steps`` vector steps (actions drawn inside the loop)."""
    shape = (vec.num_envs, vec.n_agents, vec.layout.action_size)
    t0 = time.perf_counter()
    for _ in range(steps):
        vec.step(rng.uniform(-1, 1, shape))
    return time.perf_counter() - t0


def time_rollout(env, steps: int, start):
    """(seconds, last tensordict) for ``env.rollout(steps)`` continuing from ``start`` (no reset: the
    episodes are longer than the run), with TorchRL's random policy."""
    t0 = time.perf_counter()
    td = env.rollout(steps, break_when_any_done=False, auto_reset=False, tensordict=start)
    return time.perf_counter() - t0, td[..., -1]["next"]


def main(argv: list[str] | None = None) -> dict[str, float]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=10, help="robots per copy")
    parser.add_argument("--copies", type=int, default=64, help="env copies B")
    parser.add_argument("--sensing", default="full", choices=["full", "ideal"])
    parser.add_argument("--steps", type=int, default=50, help="steps per round and method")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--no-pettingzoo", action="store_true", help="skip the single-env PettingZooWrapper row")
    parser.add_argument("--json", action="store_true", help="also print the medians as one JSON line (for run_all.py)")
    args = parser.parse_args(argv)

    kwargs = dict(n_robots=args.n, sensing=args.sensing, max_cycles=10**6)
    vec = swarm_envs.make_vec(TASK, args.copies, **kwargs)
    vec.reset(seed=0)
    env = swarm_envs.make_torchrl(TASK, args.copies, seed=0, **kwargs)
    env.reset()
    single = None
    if not args.no_pettingzoo:
        from torchrl.envs.libs.pettingzoo import PettingZooWrapper

        warnings.filterwarnings("ignore", message="PettingZoo in TorchRL is tested")
        single = PettingZooWrapper(FlatInfos(swarm_envs.make(TASK, **kwargs)), seed=0)  # flat info keys for the stock wrapper
    rng = np.random.default_rng(0)
    time_make_vec(vec, 3, rng)  # warm-up (compiled kernels load, caches fill)
    _, last = time_rollout(env, 3, env.reset())
    if single is not None:
        _, last_single = time_rollout(single, 3, single.reset())

    agent_steps = {"make_vec": args.copies * args.n * args.steps, "make_torchrl rollout": args.copies * args.n * args.steps,
                   "PettingZooWrapper rollout (B = 1)": args.n * args.steps}
    rates: dict[str, list[float]] = {name: [] for name in agent_steps}
    ratios: dict[str, list[float]] = {name: [] for name in agent_steps}
    for _ in range(args.rounds):
        seconds = {"make_vec": time_make_vec(vec, args.steps, rng)}
        seconds["make_torchrl rollout"], last = time_rollout(env, args.steps, last)
        if single is not None:
            seconds["PettingZooWrapper rollout (B = 1)"], last_single = time_rollout(single, args.steps, last_single)
        for name, s in seconds.items():
            rates[name].append(agent_steps[name] / s)
        for name in seconds:
            ratios[name].append(rates[name][-1] / rates["make_vec"][-1])

    import torch

    load = os.getloadavg()
    print(f"flocking, N = {args.n}, B = {args.copies}, sensing {args.sensing}, {args.steps} steps x {args.rounds} rounds "
          f"(alternated), torch threads {torch.get_num_threads()}, load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    print(f"{'method':<36}{'agent-steps/s (median)':>24}{'ratio to make_vec (median)':>30}")
    out = {}
    for name in agent_steps:
        if not rates[name]:
            continue
        rate, ratio = statistics.median(rates[name]), statistics.median(ratios[name])
        print(f"{name:<36}{rate:>24,.0f}{ratio:>30.3f}")
        out[name] = rate
        out[f"{name} ratio"] = ratio
    if args.json:
        print(json.dumps({"n": args.n, "copies": args.copies, "sensing": args.sensing, "rounds": args.rounds, **out}))
    return out


if __name__ == "__main__":
    main()
