"""Cost of the checks of a task's rewards() return (``swarm_envs.tasks._task_checks.RewardsCheck``) per vector step.

Two measures, in the same run: (1) the median wall-clock time of a ``make_vec`` step with the checks and
with them replaced by a pass-through, alternated in rounds so both see the same load on a shared machine;
(2) the median time of the check itself on the task's real return, many calls, against the median step.

    python benchmarks/bench_task_checks.py                                  # Aggregation-v0, N = 10, B = 256, full sensing
    python benchmarks/bench_task_checks.py --env swarm_envs/Flocking-v0 --rounds 7 --steps 15
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np

os.environ.setdefault("OMP_NUM_THREADS", "1")

import swarm_envs  # noqa: E402


def step_times(vec, rng: np.random.Generator, steps: int) -> list[float]:
    """Wall-clock seconds of ``steps`` vector steps with random actions."""
    out = []
    for _ in range(steps):
        action = rng.uniform(-1, 1, vec.action_space.shape)
        t0 = time.perf_counter()
        vec.step(action)
        out.append(time.perf_counter() - t0)
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", default="swarm_envs/Aggregation-v0")
    parser.add_argument("--n", type=int, default=10, help="robots per copy")
    parser.add_argument("--copies", type=int, default=256)
    parser.add_argument("--sensing", default="full")
    parser.add_argument("--rounds", type=int, default=5, help="alternations of checked and unchecked steps")
    parser.add_argument("--steps", type=int, default=20, help="timed steps per round and variant")
    args = parser.parse_args(argv)

    steps = 3 + 2 * args.rounds * args.steps  # every step this run takes: no copy resets while timed
    vec = swarm_envs.make_vec(args.env, args.copies, n_robots=args.n, sensing=args.sensing, max_cycles=steps + 1)
    vec.reset(seed=0)
    rng = np.random.default_rng(0)
    step_times(vec, rng, 3)  # warm-up
    core = vec.core
    check = core._check_rewards
    checked: list[float] = []
    unchecked: list[float] = []
    for _ in range(args.rounds):
        core._check_rewards = check
        checked += step_times(vec, rng, args.steps)
        core._check_rewards = lambda result: result  # the task's return as it is
        unchecked += step_times(vec, rng, args.steps)
    core._check_rewards = check

    result = vec.task.rewards(core.state(), np.zeros(args.copies, dtype=bool))
    calls = []
    for _ in range(2000):
        t0 = time.perf_counter()
        check(result)
        calls.append(time.perf_counter() - t0)

    with_checks, without = statistics.median(checked), statistics.median(unchecked)
    per_call = statistics.median(calls)
    arrays = 1 + len(result[1]) + len(result[2])
    print(f"{args.env}, N = {args.n} x B = {args.copies}, sensing {args.sensing}; {args.rounds} rounds x {args.steps} steps per variant")
    print(f"step, checks on : median {with_checks * 1e3:8.2f} ms")
    print(f"step, checks off: median {without * 1e3:8.2f} ms   (difference {100 * (with_checks - without) / without:+.2f} % of the unchecked step)")
    print(f"check alone     : median {per_call * 1e6:8.1f} us per step ({arrays} arrays) = {100 * per_call / with_checks:.3f} % of the median step")


if __name__ == "__main__":
    main()
