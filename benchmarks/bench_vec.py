"""Rollout throughput of the batched core (``swarm_envs.make_vec``), and VMAS in the same run.

Prints agent-steps/s (robots x env copies x steps per second) with random actions, flocking, e-puck at the
default density, for N in {10, 100} x B in {1, 16, 64, 256} and N = 1000 x B = 1, sensing full and ideal;
each figure is the median over timed steps after warm-up (the machine is shared: medians, and same-run
ratios; the process CPU time per step is printed too, as it depends less on other load), with the mean
number of neighbours in IR range per robot and the time per robot-step and per neighbour, which compares
swarm sizes at equal work (a larger swarm has more neighbours in range per robot). When ``vmas`` is importable, VMAS's flocking scenario with N = 10 and 1024 envs on the CPU
(torch with 1 thread, or ``--threads``) is timed in the same run and printed beside, as a ratio.

    python benchmarks/bench_vec.py                     # the full table (several minutes)
    python benchmarks/bench_vec.py --quick             # N = 10 only
    python benchmarks/bench_vec.py --n 10 --copies 64 --sensing full
    python benchmarks/bench_vec.py --interleave 5        # VMAS vs N = 10 ideal, alternated, 5 rounds
    python benchmarks/bench_vec.py --interleave 5 --sensing full
    python benchmarks/bench_vec.py --n 1000 --json     # one JSON object instead of the table (run_all.py --markdown)
    python benchmarks/bench_vec.py --threads 2         # swarm_envs on 2 numba threads, VMAS on 2 torch threads

On a shared machine the load drifts between the VMAS row and ours; ``--interleave R`` alternates the two
measurements (VMAS, then N = 10 flocking at B = 64 and 256, ideal sensing or --sensing) R times and prints each round's ratio
and the median ratio, so both sides of every ratio see the same load.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time

import numpy as np
from scipy.spatial import cKDTree

os.environ.setdefault("OMP_NUM_THREADS", "1")


def _threads_argument(argv: list[str]) -> int | None:
    """The value of ``--threads`` in ``argv`` (None when absent or not an integer; argparse reports it)."""
    for i, arg in enumerate(argv):
        value = arg.split("=", 1)[1] if arg.startswith("--threads=") else (argv[i + 1] if arg == "--threads" and i + 1 < len(argv) else None)
        if value is not None:
            try:
                return int(value)
            except ValueError:
                return None
    return None


# numba's thread pool is sized when numba starts: --threads T asks for T whatever NUMBA_NUM_THREADS says
if (_T := _threads_argument(sys.argv[1:])) is not None and _T >= 1:
    os.environ["NUMBA_NUM_THREADS"] = str(_T)

import swarm_envs  # noqa: E402

GRID = [(10, 1), (10, 16), (10, 64), (10, 256), (100, 1), (100, 16), (100, 64), (100, 256), (1000, 1)]


def neighbours_in_range(vec: object) -> float:
    """Mean number of robots of the same copy within the platform's IR range of a robot (directed pairs in
    range / robots): the pairs the IR layer and every sensing stage after it work on."""
    core = vec.core
    positions = np.asarray(core.positions, dtype=float).reshape(-1, 2)
    reach = float(core.platform.ir_range)
    extent = float(np.ptp(positions, axis=0).max()) + 2.0 * reach  # copies stacked this far apart never meet
    lifted = np.column_stack([positions, np.asarray(core.copy_of_robot, dtype=float) * extent])
    return 2.0 * len(cKDTree(lifted).query_pairs(reach)) / positions.shape[0]


def time_swarm(n: int, copies: int, sensing: str, min_steps: int, min_seconds: float,
               env_id: str = "swarm_envs/Flocking-v0") -> tuple[float, float, float]:
    """Median (wall-clock, process CPU) seconds per vector step (B copies of N robots of ``env_id``), and the
    mean number of neighbours in IR range per robot over the timed steps (:func:`neighbours_in_range`)."""
    # episodes longer than the at most 203 steps run here (no copy resets while timed), short enough for
    # make_vec's memory check (a copy's command log grows with max_cycles)
    vec = swarm_envs.make_vec(env_id, copies, n_robots=n, sensing=sensing, max_cycles=1_000)
    vec.reset(seed=0)
    rng = np.random.default_rng(0)
    shape = (copies, n, vec.layout.action_size)
    for _ in range(3):  # warm-up (numba kernels load, caches fill)
        vec.step(rng.uniform(-1, 1, shape))
    times: list[float] = []
    cpu: list[float] = []
    neighbours: list[float] = []
    start = time.perf_counter()
    while len(times) < min_steps or time.perf_counter() - start < min_seconds:
        action = rng.uniform(-1, 1, shape)
        t0, c0 = time.perf_counter(), time.process_time()
        vec.step(action)
        times.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
        neighbours.append(neighbours_in_range(vec))  # outside the timed interval
        if len(times) >= 200:
            break
    return statistics.median(times), statistics.median(cpu), statistics.fmean(neighbours)


def make_vmas(n: int, num_envs: int, threads: int = 1):
    """VMAS flocking (num_envs envs of n agents, CPU, ``threads`` torch threads), reset and warmed up, or None."""
    try:
        import torch
        import vmas
    except ImportError:
        return None
    torch.set_num_threads(threads)
    env = vmas.make_env(scenario="flocking", num_envs=num_envs, device="cpu", continuous_actions=True, n_agents=n, seed=0)
    env.reset()
    for _ in range(3):
        env.step([env.get_random_action(agent) for agent in env.agents])
    return env


def time_vmas(n: int, num_envs: int, steps: int, env=None, threads: int = 1) -> float | None:
    """Median seconds per VMAS flocking step (num_envs envs of n agents, CPU, ``threads`` torch threads), or None."""
    env = env if env is not None else make_vmas(n, num_envs, threads)
    if env is None:
        return None
    times = []
    for _ in range(steps):
        actions = [env.get_random_action(agent) for agent in env.agents]
        t0 = time.perf_counter()
        env.step(actions)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def interleaved(rounds: int, copies: tuple[int, ...] = (64, 256), vmas_steps: int = 15, sensing: str = "ideal",
                env_id: str = "swarm_envs/Flocking-v0", threads: int = 1, quiet: bool = False) -> dict | None:
    """VMAS (N = 10, 1024 envs, ``threads`` torch threads) and N = 10 of ``env_id`` with ``sensing`` at each of
    ``copies`` (numba's thread count), alternated ``rounds`` times; prints each round (unless ``quiet``) and
    returns the ratios (median, min, max per copy count), or None without VMAS."""
    env = make_vmas(10, 1024, threads)
    if env is None:
        print("VMAS: not installed (pip install vmas) - nothing to interleave")
        return None
    load_start = os.getloadavg()[0]
    say = (lambda *a, **k: None) if quiet else print
    say(f"{env_id}, {sensing} sensing, {_numba_threads()} numba / {threads} torch threads; load average at start: {load_start:.2f} on {os.cpu_count()} cores")
    say("| round | VMAS agent-steps/s | " + " | ".join(f"B={b} agent-steps/s | ratio" for b in copies) + " |")
    say("|---|---|" + "---|---|" * len(copies))
    ratios: dict[int, list[float]] = {b: [] for b in copies}
    vmas_rates = []
    for r in range(rounds):
        vmas_rate = 10 * 1024 / time_vmas(10, 1024, vmas_steps, env, threads)
        vmas_rates.append(vmas_rate)
        cells = []
        for b in copies:
            rate = 10 * b / time_swarm(10, b, sensing, 5, 2.0, env_id)[0]
            ratios[b].append(rate / vmas_rate)
            cells.append(f"{rate:,.0f} | {rate / vmas_rate:.2f}x")
        say(f"| {r + 1} | {vmas_rate:,.0f} | " + " | ".join(cells) + " |", flush=True)
    say("\nmedian ratio: " + ", ".join(f"B={b} {statistics.median(v):.2f}x (min {min(v):.2f}, max {max(v):.2f})" for b, v in ratios.items()))
    say(f"load average at end: {os.getloadavg()[0]:.2f}")
    return {"env": env_id, "sensing": sensing, "numba_threads": _numba_threads(), "torch_threads": threads, "rounds": rounds,
            "vmas_median_agent_steps_per_s": statistics.median(vmas_rates), "load_start": load_start, "load_end": os.getloadavg()[0],
            "ratios": {str(b): {"median": statistics.median(v), "min": min(v), "max": max(v)} for b, v in ratios.items()}}


def _numba_threads() -> int:
    import numba

    return numba.get_num_threads()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="N = 10 rows only")
    parser.add_argument("--n", type=int, help="one swarm size")
    parser.add_argument("--copies", type=int, help="one copy count")
    parser.add_argument("--sensing", choices=["full", "ideal"], help="one sensing mode")
    parser.add_argument("--min-steps", type=int, default=5)
    parser.add_argument("--min-seconds", type=float, default=3.0)
    parser.add_argument("--no-vmas", action="store_true")
    parser.add_argument("--vmas-steps", type=int, default=20, help="timed VMAS steps (median)")
    parser.add_argument("--interleave", type=int, metavar="R", help="alternate VMAS and N = 10 R times (ratios only; ideal sensing unless --sensing)")
    parser.add_argument("--env", default="swarm_envs/Flocking-v0", help="registered env id (default: flocking, as VMAS's scenario)")
    parser.add_argument("--import", dest="imports", action="append", default=[], metavar="MODULE",
                        help="module or .py file that registers --env (repeatable), e.g. examples/custom_task.py")
    parser.add_argument("--json", action="store_true", help="print one JSON object (rows, VMAS, load, threads) instead of the table")
    parser.add_argument("--threads", type=int, help="numba threads for swarm_envs (overrides NUMBA_NUM_THREADS) and torch threads "
                        "for VMAS (default: numba's count, NUMBA_NUM_THREADS, all cores unless set; VMAS 1)")
    args = parser.parse_args()
    if args.threads is not None:
        import numba

        if args.threads < 1:
            parser.error(f"--threads must be at least 1, got {args.threads}")
        numba.set_num_threads(args.threads)
    from swarm_envs.agents.tasks import import_modules

    try:
        import_modules(args.imports)
        swarm_envs.spec(args.env)
    except (ImportError, ValueError) as err:
        parser.error(str(err))
    if args.interleave:
        result = interleaved(args.interleave, sensing=args.sensing or "ideal", env_id=args.env, threads=args.threads or 1, quiet=args.json)
        if args.json:
            print(json.dumps(result))
        return
    grid = [(n, b) for n, b in GRID if not args.quick or n == 10]
    if args.n:
        grid = [(n, b) for n, b in grid if n == args.n] or [(args.n, args.copies or 1)]
    if args.copies:
        grid = [(n, b) for n, b in grid if b == args.copies] or [(args.n or 10, args.copies)]
    modes = [args.sensing] if args.sensing else ["full", "ideal"]
    if args.json:
        print(json.dumps(_measure_json(grid, modes, args)))
        return
    print(f"{args.env}; load average at start: {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    print(f"threads: {_numba_threads()} (numba's thread count: batches of >= 16 copies step their physics on that many threads, and a "
          "scene with >= 16384 candidate IR pairs runs its occluder search and gain kernel in that many chunks, and SwarmCom's draws, "
          "the rewards and range & bearing on a worker thread; NUMBA_NUM_THREADS=1 or --threads 1 for one core)")
    vmas_rate = None
    vmas_threads = args.threads or 1
    if not args.no_vmas:
        t = time_vmas(10, 1024, args.vmas_steps, threads=vmas_threads)
        if t is None:
            print("VMAS: not installed (pip install vmas) - no VMAS column")
        else:
            vmas_rate = 10 * 1024 / t
            print(f"VMAS 1024 envs x 10 agents flocking (cpu, {vmas_threads} torch threads): {t * 1e3:.1f} ms/step, {vmas_rate:,.0f} agent-steps/s")
    print()
    print("| N | B | sensing | ms / vector step | CPU ms / step | agent-steps/s | env steps/s (per copy) | vs VMAS N=10 x 1024 "
          "| neighbours in IR range | us per robot-step per neighbour |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for sensing in modes:
        for n, b in grid:
            t, cpu, near = time_swarm(n, b, sensing, args.min_steps, args.min_seconds, args.env)
            rate = n * b / t
            ratio = f"{rate / vmas_rate:.2f}x" if vmas_rate else "-"
            per_pair = f"{1e6 / (rate * near):.2f}" if near > 0 else "-"
            print(f"| {n} | {b} | {sensing} | {t * 1e3:.1f} | {cpu * 1e3:.1f} | {rate:,.0f} | {1 / t:,.1f} | {ratio} | {near:.1f} | {per_pair} |",
                  flush=True)
    print(f"\nload average at end: {os.getloadavg()[0]:.2f}")


def _measure_json(grid: list[tuple[int, int]], modes: list[str], args: argparse.Namespace) -> dict:
    """The table's measurements as one JSON-serialisable dict (times in seconds per vector step)."""
    result: dict = {"load_start": os.getloadavg()[0], "numba_threads": _numba_threads(), "vmas": None, "rows": []}
    if not args.no_vmas:
        threads = args.threads or 1
        t = time_vmas(10, 1024, args.vmas_steps, threads=threads)
        if t is not None:
            import vmas

            result["vmas"] = {"version": vmas.__version__, "n_agents": 10, "num_envs": 1024, "s_per_step": t,
                              "agent_steps_per_s": 10 * 1024 / t, "torch_threads": threads}
    for sensing in modes:
        for n, b in grid:
            t, cpu, near = time_swarm(n, b, sensing, args.min_steps, args.min_seconds, args.env)
            result["rows"].append({"n": n, "copies": b, "sensing": sensing, "s_per_step": t, "cpu_s_per_step": cpu,
                                   "agent_steps_per_s": n * b / t, "env_steps_per_s": 1 / t, "neighbours_in_range": near})
    result["load_end"] = os.getloadavg()[0]
    return result


if __name__ == "__main__":
    main()
