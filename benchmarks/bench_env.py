"""Env cost per step: physics, sensing, observation and reward, for sensing="ideal" vs "full".

    python benchmarks/bench_env.py [--sizes 100 1000] [--platform epuck] [--steps 20]

Prints one table row per (n_robots, sensing): milliseconds per control step for each stage and the
resulting env steps per second, measured on one process (numpy's BLAS threads are not used by these
code paths). Density is each platform's default (arena side = spacing x sqrt(N); e-puck 0.25 m).
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def measure(task: str, n: int, platform: str, sensing: str, steps: int, seed: int = 0) -> dict[str, float]:
    import swarm_envs

    env = swarm_envs.make(task, n_robots=n, platform=platform, sensing=sensing, max_cycles=10**6)
    env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    act = rng.uniform(-1, 1, (env.n_world, 2)) * np.array([0.5, 0.3])
    timings = {"physics": 0.0, "sensing": 0.0, "observation": 0.0, "reward": 0.0}
    world, sensing_stack = env.world, env.sensing
    for _ in range(steps):
        t0 = time.perf_counter()
        world.step(act[:, 0] * env.platform.max_speed, act[:, 1] * env.platform.max_angular_speed, 0.1)
        t1 = time.perf_counter()
        env.core.frame = sensing_stack.step(world.positions, world.headings, None)
        t2 = time.perf_counter()
        env._observations()
        t3 = time.perf_counter()
        env.task.rewards(env.core.state(), np.zeros(1, dtype=bool))
        t4 = time.perf_counter()
        for key, dt in zip(timings, (t1 - t0, t2 - t1, t3 - t2, t4 - t3)):
            timings[key] += dt
    out = {k: 1e3 * v / steps for k, v in timings.items()}
    # whole env.step including action validation and infos
    actions = {a: act[env.agent_robots[i]].astype(np.float32) for i, a in enumerate(env.agents)}
    t0 = time.perf_counter()
    for _ in range(steps):
        env.step(actions)
    out["env.step"] = 1e3 * (time.perf_counter() - t0) / steps
    out["steps/s"] = 1e3 / out["env.step"]
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[100, 1000])
    parser.add_argument("--platform", default="epuck")
    parser.add_argument("--task", default="swarm_envs/Aggregation-v0")
    parser.add_argument("--sensing", nargs="+", default=["ideal", "full"])
    parser.add_argument("--steps", type=int, default=20)
    args = parser.parse_args(argv)
    cols = ["physics", "sensing", "observation", "reward", "env.step", "steps/s"]
    print(f"platform={args.platform} task={args.task} (ms per control step; steps/s = 1000 / env.step)")
    print(f"| {'n_robots':>8} | {'sensing':>7} | " + " | ".join(f"{c:>11}" for c in cols) + " |")
    print("|" + "---|" * (len(cols) + 2))
    for n in args.sizes:
        for sensing in args.sensing:
            row = measure(args.task, n, args.platform, sensing, args.steps)
            print(f"| {n:>8} | {sensing:>7} | " + " | ".join(f"{row[c]:>11.2f}" for c in cols) + " |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
