"""Where the time of one ``make_vec`` step goes: physics, sensing, observations, rewards, infos, the rest.

Each stage is wrapped with a timer (wall clock and process CPU time; the machine is shared, and CPU time
depends less on other load); the table gives the mean per vector step over the timed steps.

    python benchmarks/bench_stages.py                          # flocking, ideal sensing, B = 256 x N = 10
    python benchmarks/bench_stages.py --task Aggregation --copies 32
    python benchmarks/bench_stages.py --copies 1 --n 1000 --sensing full --steps 10
"""

from __future__ import annotations

import argparse
import collections
import os
import time

import numpy as np

os.environ.setdefault("OMP_NUM_THREADS", "1")

import swarm_envs  # noqa: E402
import swarm_envs.core as core_mod  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default="Flocking", choices=["Flocking", "Aggregation", "CentroidSeeking"])
    parser.add_argument("--copies", type=int, default=256)
    parser.add_argument("--n", type=int, default=10)
    parser.add_argument("--sensing", default="ideal", choices=["ideal", "full"])
    parser.add_argument("--steps", type=int, default=30)
    args = parser.parse_args()

    wall: dict[str, float] = collections.defaultdict(float)
    cpu: dict[str, float] = collections.defaultdict(float)

    def timed(obj, name: str, label: str) -> None:
        inner = getattr(obj, name)

        def call(*a, **k):
            w, c = time.perf_counter(), time.process_time()
            out = inner(*a, **k)
            wall[label] += time.perf_counter() - w
            cpu[label] += time.process_time() - c
            return out

        setattr(obj, name, call)

    timed(core_mod, "step_worlds", "physics")
    vec = swarm_envs.make_vec(f"swarm_envs/{args.task}-v0", args.copies, n_robots=args.n, sensing=args.sensing, max_cycles=args.steps + 4)  # every step run here
    timed(vec.core.sensing, "step", "sensing")
    timed(vec.core, "observations", "observations")
    timed(vec.core.task, "rewards", "rewards")
    timed(vec.batch, "infos", "infos")
    vec.reset(seed=0)
    rng = np.random.default_rng(0)
    shape = (args.copies, vec.n_agents, vec.layout.action_size)
    for _ in range(3):  # warm-up (numba kernels load)
        vec.step(rng.uniform(-1, 1, shape))
    wall.clear()
    cpu.clear()
    links = 0
    w, c = time.perf_counter(), time.process_time()
    for _ in range(args.steps):
        vec.step(rng.uniform(-1, 1, shape))
        links += int(vec.core.frame.stats["ir_links"].sum()) if "ir_links" in vec.core.frame.stats else 0
    total_wall, total_cpu = (time.perf_counter() - w) / args.steps, (time.process_time() - c) / args.steps
    per = {k: (wall[k] / args.steps, cpu[k] / args.steps) for k in wall}
    per["rest (actions, gather, outputs)"] = (total_wall - sum(x for x, _ in per.values()), total_cpu - sum(y for _, y in per.values()))
    agents = args.copies * vec.n_agents
    print(f"{args.task} B={args.copies} N={args.n} sensing={args.sensing}: {total_wall * 1e3:.1f} ms/step wall "
          f"({agents / total_wall:,.0f} agent-steps/s), {total_cpu * 1e3:.1f} ms CPU")
    print(f"  {'stage':34s} {'wall ms':>8s} {'CPU ms':>8s}")
    for name, (x, y) in sorted(per.items(), key=lambda kv: -kv[1][0]):
        print(f"  {name:34s} {x * 1e3:8.2f} {y * 1e3:8.2f}")
    print(f"  {'non-physics':34s} {(total_wall - per['physics'][0]) * 1e3:8.2f} {(total_cpu - per['physics'][1]) * 1e3:8.2f}")
    if links:  # the sensing's work grows with the IR links (pairs in range with light), not with the robots
        per_step = links / args.steps
        print(f"  IR links: {per_step / agents:.1f} per robot; sensing {per['sensing'][1] / per_step * 1e6:.2f} CPU us per link")


if __name__ == "__main__":
    main()
