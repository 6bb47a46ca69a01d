"""The r-one's bearing-only behaviours [L Sec. 6.4, Figs. 6.7-6.10] run by the scripted agents in the envs.

``python -m swarm_envs.validate behaviours [--out DIR] [--seed S] [--seeds N] [--json] [--message-range]``

For each behaviour the scripted agent (the thesis's algorithm on the sensed observation) runs one
episode of its env on the r-one with ``sensing="full"`` and the trajectories are drawn as in the thesis's
figures, each robot's path in its own colour (Fig. 6.7 flocking [Alg. 5], Fig. 6.8 sorted following
[Alg. 6] with and without the leader switched off half way, Fig. 6.9 clustering by id parity [Alg. 7],
Fig. 6.10 mid-angle navigation through a corridor [Alg. 8], the goal in green). The drawn episode is a
typical one: of the ``--seeds`` evaluated episodes, the one whose headline metric is nearest their median
(``--seed`` draws another). The metrics of the drawn episode and their means over the ``--seeds``
episodes (bootstrap 95 % intervals) are printed.

The thesis's figures are illustrations ("an approximation of the algorithms performance not a
ground-truth measurement", Fig. 6.10) and its text gives no number for any of these behaviours, so there is
nothing to compare our metrics with: the figures show that the behaviours look like the thesis's, the
metrics are ours.

``--message-range`` also measures each platform's reliable message range on our channel model (the
distance up to which a facing pair exchanges frames with bit error probability below 0.01 at 310 bps, the
measure of [T20 Sec. 7]; the values :data:`swarm_envs.tasks.task.MESSAGE_RANGE` records).
"""

from __future__ import annotations

import json
import os
import sys
import time
from typing import Any

import numpy as np

import swarm_envs
from swarm_envs.agents.evaluation import confidence_interval, evaluate
from swarm_envs.agents.scripted import make_scripted
from swarm_envs.agents.tasks import headline, metric_reductions, scripted_policy
from swarm_envs.tasks.settings import COMMON_SETTINGS, Int
from swarm_envs.tasks.settings_cli import OneLineArgumentParser, cli_type

__all__ = ["BEHAVIOURS", "run_episode_trajectory", "message_ranges", "main"]

#: name -> (env id, env settings, figure of the thesis, what it shows)
BEHAVIOURS: dict[str, tuple[str, dict[str, Any], str, str]] = {
    "flocking": ("swarm_envs/Flocking-v0", {"platform": "rone", "n_robots": 4}, "Fig. 6.7", "Alg. 5: copy the neighbours' orientations"),
    "sorted_following": ("swarm_envs/SortedFollowing-v0", {"n_robots": 4}, "Fig. 6.8", "Alg. 6: follow a lower id; the lowest leads"),
    "sorted_following_leader_removed": (
        "swarm_envs/SortedFollowing-v0", {"n_robots": 4, "remove_leader_at": 250}, "Fig. 6.8", "Alg. 6, the leader switched off at 25 s"
    ),
    "parity_clustering": ("swarm_envs/ParityClustering-v0", {}, "Fig. 6.9", "Alg. 7: even ids gather with even, odd with odd"),
    "mid_angle_navigation": ("swarm_envs/MidAngleNavigation-v0", {}, "Fig. 6.10", "Alg. 8: through the mid-angles to the goal"),
}


def run_episode_trajectory(env_id: str, settings: dict[str, Any], seed: int) -> tuple[Any, np.ndarray, dict[str, float]]:
    """One episode of the env's scripted agent (``sensing="full"``, the seeds and policy generator of
    :func:`swarm_envs.agents.evaluation.evaluate`): (the env, positions (T + 1, n_world, 2) m of every
    step, the metrics reduced over the episode as the task declares)."""
    env = swarm_envs.make(env_id, sensing="full", **settings)
    policy = make_scripted(scripted_policy(env_id), env)
    policy.reset(env.n_agents, rng=np.random.default_rng([seed, 7919]))
    env.reset(seed=seed)
    path = [env.world.positions.copy()]
    reductions = metric_reductions(env_id)
    sums = dict.fromkeys(reductions, 0.0)
    last: dict[str, float] = {}
    steps = 0
    while env.agents:
        parts = {k: v[env.agent_robots] for k, v in env.batched_observations().items()}
        actions = policy.act_batch(parts)
        _, _, _, _, infos = env.step({a: actions[i] for i, a in enumerate(env.possible_agents)})
        path.append(env.world.positions.copy())
        last = infos[env.possible_agents[0]]["metrics"]
        for name in reductions:
            sums[name] += last[name]
        steps += 1
    metrics = {name: last[name] if how == "final" else sums[name] / max(steps, 1) for name, how in reductions.items()}
    return env, np.array(path), metrics


def typical_seed(values: np.ndarray) -> int:
    """The seed (index) whose value is nearest the median of ``values`` (the lowest such seed): a typical
    episode to draw, neither the best nor the worst."""
    values = np.asarray(values, dtype=float)
    return int(np.argmin(np.abs(values - np.median(values))))


def _draw(name: str, env: Any, path: np.ndarray, metrics: dict[str, float], out_dir: str, seed: int) -> str:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle

    env_id, settings, figure, what = BEHAVIOURS[name]
    fig, ax = plt.subplots(figsize=(5.2, 5.2))
    h = env.arena.half
    ax.plot([-h, h, h, -h, -h], [-h, -h, h, h, -h], color="0.2", lw=1.5)
    for a, b in env.task.obstacle_segments:
        ax.plot([a[0], b[0]], [a[1], b[1]], color="0.2", lw=2.5)
    r, n_static = env.platform.radius, env.n_static
    parity = name.startswith("parity")
    colours = plt.get_cmap("tab10")
    for i in range(env.n_world):
        if i < n_static:  # static robots: the goal green (Fig. 6.10), relays grey
            ax.add_patch(Circle(path[0, i], r, color="tab:green" if i == 0 else "0.6", zorder=3))
            continue
        agent = i - n_static
        if parity:
            colour = plt.get_cmap("Blues" if agent % 2 == 0 else "Oranges")(0.45 + 0.5 * (agent // 2) / max(env.n_agents // 2, 1))
        else:
            colour = colours(agent % 10)
        ax.plot(path[:, i, 0], path[:, i, 1], color=colour, lw=1.1, label=f"id {agent}" if env.n_agents <= 6 else None)
        ax.plot(*path[0, i], "o", color=colour, ms=3)
        ax.add_patch(Circle(path[-1, i], r, fill=False, color=colour, lw=1.2, zorder=3))
    ax.set_aspect("equal")
    ax.set_xlim(-h - 0.02, h + 0.02)
    ax.set_ylim(-h - 0.02, h + 0.02)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    best = headline(env_id)[0]
    ax.set_title(f"{name.replace('_', ' ')} ({figure}): {what}\nseed {seed}: {best} = {metrics[best]:.3g}", fontsize=8)
    if env.n_agents <= 6 and not parity:
        ax.legend(fontsize=7, loc="upper right")
    if parity:
        ax.plot([], [], color="tab:blue", label="even ids")
        ax.plot([], [], color="tab:orange", label="odd ids")
        ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    os.makedirs(out_dir, exist_ok=True)
    out = os.path.join(out_dir, f"behaviour_{name}.png")
    fig.savefig(out, dpi=90)
    plt.close(fig)
    return out


def message_ranges(steps: int = 300, seed: int = 0) -> dict[str, float]:
    """Reliable message range (m) per platform on our channel model: static facing pairs, one every 1 cm
    from a diameter apart to the IR range (each 3 m from the others), 310 bps, the platform's detector
    threshold; the largest distance up to which every pair's bit error probability stays below 0.01 and
    every pair delivered a frame [T20 Sec. 7]."""
    from swarm_envs.comm.channel import recommended_relative_threshold
    from swarm_envs.comm.network import Network
    from swarm_envs.ir.layer import compute_links
    from swarm_envs.sim.platforms import PLATFORMS

    out = {}
    rng = np.random.default_rng(seed)
    for name, platform in PLATFORMS.items():
        distances = np.arange(platform.diameter + 0.01, platform.ir_range + 1e-9, 0.01)
        k = len(distances)
        positions = np.zeros((2 * k, 2))
        positions[0::2, 0] = 3.0 * np.arange(k) + distances  # transmitters, facing their receivers
        positions[1::2, 0] = 3.0 * np.arange(k)
        headings = np.zeros(2 * k)
        headings[0::2] = np.pi
        links = compute_links(positions, headings, platform)
        net = Network(platform, 2 * k, rng, bitrate=310, relative_threshold=recommended_relative_threshold(platform))
        senders = np.arange(0, 2 * k, 2)
        for _ in range(steps):
            idle = senders[(net.q_count[senders] == 0) & ~net.sending[senders]]
            if idle.size:
                net.send_many(idle, rng.integers(0, 2, size=(idle.size, 16)).astype(bool), lengths=np.full(idle.size, 16))
            net.step(links)
        s = net.stats
        checked = s["bits_checked_per_robot"][senders + 1].astype(float)
        errors = s["bit_errors_per_robot"][senders + 1].astype(float)
        delivered = s["rx_delivered_per_robot"][senders + 1]
        good = (delivered > 0) & (checked > 0) & (errors <= 0.01 * checked)
        bad = np.flatnonzero(~good)
        # beyond the first bad distance nothing counts (the r-one's receivers miss a pair closer than ~0.2 m
        # only when its arcs do not overlap: the range is its farthest good distance)
        good_run = np.flatnonzero(good)
        if good_run.size == 0:
            out[name] = float("nan")
            continue
        start = good_run[0]
        end = bad[bad > start][0] - 1 if np.any(bad > start) else k - 1
        out[name] = float(distances[end])
    return out


def main(argv: list[str] | None = None) -> int:
    """Command line of ``python -m swarm_envs.validate behaviours``; returns the exit code."""
    ap = OneLineArgumentParser(prog="python -m swarm_envs.validate behaviours", description=__doc__.split("\n")[0])
    ap.add_argument("--out", default="validation_output", help="folder for the PNG figures")
    ap.add_argument("--seed", type=cli_type(Int(None, low=0, high=2**63 - 1), "--seed"), default=None,
                    help="draw this seed (default: the evaluated seed whose headline is nearest the median)")
    ap.add_argument("--seeds", type=cli_type(Int(10, low=1, high=100_000), "--seeds"), default=10,
                    help="episodes per behaviour for the mean metrics (default 10)")
    ap.add_argument("--only", action="append", default=[], choices=list(BEHAVIOURS), help="run only these behaviours (repeatable)")
    ap.add_argument("--max-cycles", type=cli_type(COMMON_SETTINGS["max_cycles"], "--max-cycles"), default=None,
                    help="episode length (default: each env's)")
    ap.add_argument("--message-range", action="store_true", help="also measure each platform's reliable message range")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)  # every number checked by its rule: a bad one is one usage line, exit code 2
    summary: dict[str, Any] = {"behaviours": {}}
    for name in args.only or list(BEHAVIOURS):
        env_id, settings, figure, what = BEHAVIOURS[name]
        if args.max_cycles is not None:
            settings = {**settings, "max_cycles": args.max_cycles}
        t0 = time.perf_counter()
        per_seed = evaluate(env_id, {"sensing": "full", **settings}, lambda e: make_scripted(scripted_policy(env_id), e), list(range(args.seeds)))
        seed = typical_seed(per_seed[headline(env_id)[0]]) if args.seed is None else args.seed
        env, path, metrics = run_episode_trajectory(env_id, settings, seed)
        figure_path = _draw(name, env, path, metrics, args.out, seed)
        means = {k: confidence_interval(v) for k, v in per_seed.items() if k != "episode_return"}
        summary["behaviours"][name] = {
            "env": env_id, "settings": settings, "thesis_figure": figure, "figure": figure_path, "seed": seed, "episode": metrics,
            "mean": {k: list(v) for k, v in means.items()}, "seconds": time.perf_counter() - t0,
        }
    if args.message_range:
        summary["message_range_m"] = message_ranges()
    if args.json:
        print(json.dumps(summary, indent=2, default=float))
        return 0
    print("r-one bearing-only behaviours [L Sec. 6.4], scripted agents, sensing='full'. The thesis gives no number for")
    print(f"any of them (its figures are illustrations): nothing to compare with. Means over {args.seeds} seeds [95 % bootstrap interval].")
    for name, res in summary["behaviours"].items():
        best = headline(res["env"])[0]
        print(f"\n{name} ({res['thesis_figure']}; {res['env']} {res['settings']}): figure {res['figure']} (seed {res['seed']}; {res['seconds']:.0f} s)")
        for metric, (mean, lo, hi) in res["mean"].items():
            mark = " (headline)" if metric == best else ""
            print(f"  {metric:24s} drawn episode {res['episode'][metric]:8.3g}   mean {mean:8.3g} [{lo:.3g}, {hi:.3g}]{mark}")
    if "message_range_m" in summary:
        print("\nreliable message range (P_e < 0.01, facing pair, 310 bps) on our channel model:")
        for name, value in summary["message_range_m"].items():
            print(f"  {name:8s} {value:.2f} m")
    return 0


if __name__ == "__main__":
    sys.exit(main())
