"""Soak test: many agent-steps of random actions with resets, watching memory and every observation.

Runs the three tasks in turn (one reused env each, ``sensing="full"`` by default), an episode at a time,
with uniformly random actions in [-1, 1] and a new seed per episode. At every step every agent's
observation must be finite and inside its observation space (the script stops at the first violation and
exits with status 1). The resident set size (RSS, psutil or ``/proc/self/status`` VmRSS) is sampled and
printed as a table; after a warm-up (default: the first 20 % of the run) it should stay flat: the slope
of a straight-line fit is reported in MB per 100k agent-steps.

    python benchmarks/soak.py                        # 10^6 agent-steps, e-puck, 20 robots (long)
    python benchmarks/soak.py --agent-steps 100000   # shortened
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

import swarm_envs  # noqa: E402


def rss_mb() -> float:
    """Resident set size of this process (MB)."""
    try:
        import psutil

        return psutil.Process().memory_info().rss / 2**20
    except ImportError:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024
    return float("nan")


def leaves(obs) -> list[np.ndarray]:
    if isinstance(obs, dict):
        return [x for v in obs.values() for x in leaves(v)]
    return [np.asarray(obs)]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--agent-steps", type=int, default=1_000_000, help="total robot-steps (env steps x robots)")
    parser.add_argument("--n-robots", type=int, default=20)
    parser.add_argument("--platform", default="epuck")
    parser.add_argument("--sensing", default="full", choices=["full", "ideal"])
    parser.add_argument("--episode-steps", type=int, default=250, help="max_cycles of each episode")
    parser.add_argument("--samples", type=int, default=20, help="RSS samples (table rows)")
    parser.add_argument("--warmup", type=float, default=0.2, help="fraction of the run before RSS should be flat")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)

    envs = [
        swarm_envs.make(env_id, n_robots=args.n_robots, platform=args.platform, sensing=args.sensing, max_cycles=args.episode_steps)
        for env_id in swarm_envs.list_envs()
    ]
    rng = np.random.default_rng(args.seed)
    every = max(1, args.agent_steps // args.samples)
    rows: list[tuple[int, int, float, float]] = []  # agent-steps, episodes, RSS MB, elapsed s
    agent_steps = episodes = 0
    next_sample = 0
    start = time.perf_counter()
    print(f"soak: {args.agent_steps} agent-steps, {args.n_robots} robots, {args.platform}, sensing={args.sensing}, "
          f"episodes of {args.episode_steps} steps over {[type(e).__name__ for e in envs]}", flush=True)
    print(f"{'agent-steps':>12} {'episodes':>9} {'RSS MB':>9} {'agent-steps/s':>14}", flush=True)
    while agent_steps < args.agent_steps:
        env = envs[episodes % len(envs)]
        obs, _ = env.reset(seed=int(rng.integers(2**31)))
        episodes += 1
        while env.agents and agent_steps < args.agent_steps:
            for agent, o in obs.items():
                bad = [x for x in leaves(o) if not np.all(np.isfinite(x))]
                if bad or not env.observation_space(agent).contains(o):
                    what = "non-finite" if bad else "outside its space"
                    print(f"FAIL: {type(env).__name__} {agent} observation {what} at agent-step {agent_steps}", flush=True)
                    return 1
            if agent_steps >= next_sample:
                rows.append((agent_steps, episodes, rss_mb(), time.perf_counter() - start))
                print(f"{rows[-1][0]:>12} {rows[-1][1]:>9} {rows[-1][2]:>9.1f} {rows[-1][0] / max(rows[-1][3], 1e-9):>14.0f}", flush=True)
                next_sample += every
            actions = {a: rng.uniform(-1, 1, env.action_space(a).shape).astype(np.float32) for a in env.agents}
            obs, _, _, _, _ = env.step(actions)
            agent_steps += len(actions)
    rows.append((agent_steps, episodes, rss_mb(), time.perf_counter() - start))
    print(f"{rows[-1][0]:>12} {rows[-1][1]:>9} {rows[-1][2]:>9.1f} {rows[-1][0] / max(rows[-1][3], 1e-9):>14.0f}", flush=True)

    steps = np.array([r[0] for r in rows], float)
    rss = np.array([r[2] for r in rows])
    after = steps >= args.warmup * args.agent_steps
    slope = np.polyfit(steps[after], rss[after], 1)[0] * 1e5 if after.sum() >= 2 else float("nan")
    print(f"\nall observations finite and inside their spaces over {agent_steps} agent-steps, {episodes} episodes")
    print(f"RSS: start {rss[0]:.1f} MB, after warm-up {rss[after][0]:.1f} MB, end {rss[-1]:.1f} MB, max {rss.max():.1f} MB; "
          f"slope after warm-up {slope:+.2f} MB per 100k agent-steps")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
