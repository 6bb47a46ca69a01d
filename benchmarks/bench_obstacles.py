"""What static obstacles cost: the IR layer's links with and without walls, and env steps of a task without
obstacles (the path every existing task takes) next to the same task with walls.

Prints median milliseconds over timed repetitions (the machine is shared: medians, same-run ratios):

    python benchmarks/bench_obstacles.py [--n 10 100] [--reps 200]

Rows: ``compute_links`` of N e-pucks at the flocking density without obstacles, with ``obstacles=None``
vs an empty (0, 2, 2) array (both skip the pass), and with four walls crossing the scene (the pass runs);
then one env step (``sensing="full"``, random actions) of flocking with no walls and with the same four
walls (a ``Task`` subclass whose ``obstacles()`` returns them).
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np

os.environ.setdefault("OMP_NUM_THREADS", "1")

import swarm_envs  # noqa: E402
from swarm_envs.tasks.flocking_v0 import FlockingTask  # noqa: E402
from swarm_envs.ir.layer import compute_links  # noqa: E402
from swarm_envs.tasks.task import SPACING  # noqa: E402


def walls(size: float) -> np.ndarray:
    """Four walls across a square arena of side ``size`` (m): two horizontal, two vertical, each half long."""
    q = size / 4
    return np.array([[[-q, -q], [q, -q]], [[-q, q], [q, q]], [[-q, -q], [-q, q]], [[q, -q], [q, q]]])


def median_ms(fn, reps: int) -> float:
    fn()  # warm-up
    times = []
    for _ in range(reps):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1e3 * statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, nargs="+", default=[10, 100])
    ap.add_argument("--reps", type=int, default=200)
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    print(f"load average {os.getloadavg()[0]:.2f}; medians over {args.reps} repetitions (ms)")
    print("| N | links, obstacles=None | links, empty array | links, 4 walls | env step, no walls | env step, 4 walls |")
    print("|---|---|---|---|---|---|")
    for n in args.n:
        size = SPACING["epuck"] * np.sqrt(n)
        pos = rng.uniform(-size / 2 + 0.05, size / 2 - 0.05, (n, 2))
        head = rng.uniform(-np.pi, np.pi, n)
        w = walls(size)
        none = median_ms(lambda: compute_links(pos, head, "epuck"), args.reps)
        empty = median_ms(lambda: compute_links(pos, head, "epuck", obstacles=np.zeros((0, 2, 2))), args.reps)
        walled = median_ms(lambda: compute_links(pos, head, "epuck", obstacles=w), args.reps)
        steps = []
        for task in (FlockingTask, type("WalledFlocking", (FlockingTask,), {"obstacles": lambda self: walls(self.arena.size)})):
            env = swarm_envs.make(task, n_robots=n, sensing="full", max_cycles=10**6)
            env.reset(seed=0)
            actions = {a: np.zeros(2) for a in env.possible_agents}
            steps.append(median_ms(lambda: env.step(actions), max(20, args.reps // 10)))
        print(f"| {n} | {none:.3f} | {empty:.3f} | {walled:.3f} | {steps[0]:.2f} | {steps[1]:.2f} |")


if __name__ == "__main__":
    main()
