"""The PettingZoo view's cost: the ``ParallelEnv`` (dicts of actions, observations, rewards and infos per agent)
against ``make_vec(..., 1)`` (arrays) over the same batched core, in the same run.

    python benchmarks/bench_views.py                         # N = 1000, full sensing, 5 alternated rounds
    python benchmarks/bench_views.py --n 100 --rounds 3 --env swarm_envs/Flocking-v0
    python benchmarks/bench_views.py --import examples/custom_task.py --env swarm_examples/Dispersion-v0

Each round times ``--steps`` env steps of each view (random actions; the ParallelEnv's actions are made as
a dict of arrays before the timer starts), one after the other, so both sides of a round's ratio see the
same machine load. Prints env steps/s per round, the ratio ParallelEnv / make_vec per round and the median
ratio, and the load average before and after. The same ratio of process CPU time per step (all threads of
this process; it depends less on other processes' load than wall-clock time) is printed beside, and the
median time of the ParallelEnv's infos alone (``SwarmEnv._infos``, per-agent nested dicts).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

os.environ.setdefault("OMP_NUM_THREADS", "1")

import swarm_envs  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from swarm_envs.agents.tasks import import_modules  # noqa: E402


def time_steps(step: Callable[[Any], Any], actions: Sequence[Any], steps: int) -> tuple[float, float]:
    """(env steps per second, process CPU seconds per step) of ``step`` over ``steps`` actions, after 2 warm-up steps."""
    for a in actions[:2]:
        step(a)
    t0, c0 = time.perf_counter(), time.process_time()
    for a in actions[2 : 2 + steps]:
        step(a)
    return steps / (time.perf_counter() - t0), (time.process_time() - c0) / steps


def time_infos(env, repeats: int = 50) -> float:
    """Median seconds of the ParallelEnv's infos alone (``SwarmEnv._infos``) at its current step."""
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        env._infos()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--env", default="swarm_envs/Aggregation-v0", help="registered env id")
    parser.add_argument("--import", dest="imports", action="append", default=[], metavar="MODULE",
                        help="module or .py file that registers the env (repeatable)")
    parser.add_argument("--n", type=int, default=1000, help="robots")
    parser.add_argument("--sensing", choices=("full", "ideal"), default="full")
    parser.add_argument("--steps", type=int, default=20, help="timed steps per view and round")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--json", action="store_true", help="also print the medians as one JSON line (for run_all.py)")
    args = parser.parse_args(argv)
    if args.n < 1 or args.steps < 1 or args.rounds < 1:
        parser.error("--n, --steps and --rounds must be >= 1")
    try:
        import_modules(args.imports)
    except ImportError as err:
        parser.error(str(err))

    kwargs = dict(n_robots=args.n, sensing=args.sensing, max_cycles=10**6)
    env = swarm_envs.make(args.env, **kwargs)
    vec = swarm_envs.make_vec(args.env, 1, **kwargs)
    env.reset(seed=0)
    vec.reset(seed=0)
    rng = np.random.default_rng(0)
    size = vec.layout.action_size
    load0 = os.getloadavg()
    print(f"{args.env}, N = {args.n}, {args.sensing} sensing, {args.steps} steps per view and round; swarm_envs "
          f"{swarm_envs.__version__} from {Path(swarm_envs.__file__).parent}; load {load0[0]:.2f} on {os.cpu_count()} cores")
    print("| round | ParallelEnv (env steps/s) | make_vec(1) (env steps/s) | ratio | CPU ms/step ParallelEnv | make_vec(1) | CPU ratio | infos ms |")
    print("|---|---|---|---|---|---|---|---|")
    ratios, cpu_ratios, par_rates, arr_rates, info_times = [], [], [], [], []
    for r in range(args.rounds):
        arrays = rng.uniform(-1, 1, (args.steps + 2, 1, vec.n_agents, size))
        dicts = [{a: arrays[t, 0, i] for i, a in enumerate(env.possible_agents)} for t in range(args.steps + 2)]
        par, par_cpu = time_steps(env.step, dicts, args.steps)
        arr, arr_cpu = time_steps(vec.step, arrays, args.steps)
        info_times.append(time_infos(env))
        ratios.append(par / arr)
        cpu_ratios.append(arr_cpu / par_cpu)  # a speed ratio, as the wall-clock one
        par_rates.append(par)
        arr_rates.append(arr)
        print(f"| {r + 1} | {par:.2f} | {arr:.2f} | {par / arr:.3f} | {par_cpu * 1e3:.1f} | {arr_cpu * 1e3:.1f} | {cpu_ratios[-1]:.3f} "
              f"| {info_times[-1] * 1e3:.2f} |", flush=True)
    load1 = os.getloadavg()
    print(f"\nmedian ratio ParallelEnv / make_vec(1): {statistics.median(ratios):.3f} (wall clock), {statistics.median(cpu_ratios):.3f} "
          f"(process CPU time); infos {statistics.median(info_times) * 1e3:.2f} ms; load {load0[0]:.2f} -> {load1[0]:.2f}")
    if args.json:
        print(json.dumps({"env": args.env, "n": args.n, "sensing": args.sensing, "rounds": args.rounds,
                          "parallel_env_steps_per_s": statistics.median(par_rates),
                          "make_vec_steps_per_s": statistics.median(arr_rates), "ratio": statistics.median(ratios),
                          "cpu_ratio": statistics.median(cpu_ratios), "infos_s": statistics.median(info_times)}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
