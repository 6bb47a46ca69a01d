"""Evaluate policies on the swarm tasks over many seeds, with 95 % confidence intervals.

An episode is run with :func:`run_episode`: the policy sees the named batched observations of the agents
(:meth:`swarm_envs.env.SwarmEnv.batched_observations`, rows = agents in ``possible_agents`` order); the task
metrics are read from ``infos[agent]["metrics", name]`` by the *evaluator* only. Each task metric is reduced
over the episode as listed in :data:`TASK_METRICS` ("final" = value after the last step, "mean" = mean
over all steps after reset). ``episode_return`` is the mean over robots of the summed per-robot reward.
Confidence intervals: Student-t 95 % interval of the mean over seeds (:func:`confidence_interval`).
"""

from __future__ import annotations

import csv
import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats

from swarm_envs.agents.base import Policy, RandomPolicy
from swarm_envs.env import info_group

__all__ = [
    "TASKS",
    "TASK_METRICS",
    "PRIMARY_METRIC",
    "make_env",
    "run_episode",
    "evaluate",
    "confidence_interval",
    "summarise",
    "write_csv",
    "markdown_table",
    "RESULT_COLUMNS",
    "random_factory",
]

#: task name -> module path of its parallel env
TASKS = {
    "aggregation": "swarm_envs.aggregation_v0",
    "flocking": "swarm_envs.flocking_v0",
    "centroid_seeking": "swarm_envs.centroid_seeking_v0",
}

#: task -> {metric: reduction over the episode}
TASK_METRICS: dict[str, dict[str, str]] = {
    "aggregation": {"largest_cluster_fraction": "final", "n_clusters": "final", "mean_distance_to_centroid": "final"},
    "flocking": {"polarisation": "mean", "cohesion": "mean", "collision_fraction": "mean"},
    "centroid_seeking": {"mean_distance_second_half": "final", "mean_distance_to_centroid": "final"},
}

#: task -> (headline metric, +1 if higher is better else -1)
PRIMARY_METRIC: dict[str, tuple[str, int]] = {
    "aggregation": ("largest_cluster_fraction", +1),
    "flocking": ("polarisation", +1),
    "centroid_seeking": ("mean_distance_second_half", -1),
}

RESULT_COLUMNS = ("policy", "metric", "mean", "ci_low", "ci_high")


def make_env(task: str, **env_kwargs: Any):
    """The native parallel env of ``task`` (``aggregation``, ``flocking``, ``centroid_seeking``)."""
    if task not in TASKS:
        raise ValueError(f"unknown task {task!r}; available: {sorted(TASKS)}")
    import importlib

    return importlib.import_module(TASKS[task]).parallel_env(**env_kwargs)


def run_episode(
    env,
    policy: Policy,
    seed: int,
    task: str,
    frames: list | None = None,
) -> dict[str, float]:
    """Run one episode of ``policy`` on ``env`` from ``reset(seed=seed)``; returns the reduced metrics.

    The policy is reset with its own generator derived from ``seed``. If ``frames`` is a list, rendered
    RGB frames are appended (the env needs ``render_mode="rgb_array"``).
    """
    reductions = TASK_METRICS[task]
    policy.reset(env.n_agents, rng=np.random.default_rng([seed, 7919]))
    _, infos = env.reset(seed=seed)
    if frames is not None:
        frames.append(env.render())
    sums = dict.fromkeys(reductions, 0.0)
    last: dict[str, float] = {}
    returns = np.zeros(env.n_agents)
    steps = 0
    while env.agents:
        parts = {k: v[env.agent_robots] for k, v in env.batched_observations().items()}
        actions = np.asarray(policy.act_batch(parts), dtype=np.float64)
        _, rewards, _, _, infos = env.step({a: actions[i] for i, a in enumerate(env.possible_agents)})
        returns += np.array([rewards[a] for a in env.possible_agents])
        metrics = info_group(infos[env.possible_agents[0]], "metrics")
        for name in reductions:
            sums[name] += metrics[name]
        last = metrics
        steps += 1
        if frames is not None:
            frames.append(env.render())
    out = {name: (last[name] if how == "final" else sums[name] / max(steps, 1)) for name, how in reductions.items()}
    out["episode_return"] = float(returns.mean())
    return {k: float(v) for k, v in out.items()}


def evaluate(
    task: str,
    env_kwargs: dict[str, Any],
    policy_factory: Callable[[Any], Policy],
    seeds: Sequence[int],
    progress: bool = False,
    desc: str = "",
) -> dict[str, np.ndarray]:
    """Metrics per seed ``{metric: (n_seeds,)}`` for the policy built by ``policy_factory(env)``."""
    env = make_env(task, **env_kwargs)
    policy = policy_factory(env)
    rows: list[dict[str, float]] = []
    iterator = seeds
    if progress:
        from tqdm import tqdm

        iterator = tqdm(seeds, desc=desc or f"eval {policy.name}", leave=False)
    for seed in iterator:
        rows.append(run_episode(env, policy, int(seed), task))
    env.close()
    return {name: np.array([r[name] for r in rows]) for name in rows[0]}


def random_factory(env) -> Policy:
    """Factory of the uniform random baseline."""
    return RandomPolicy(env.platform, env.layout)


def confidence_interval(values: Sequence[float], level: float = 0.95) -> tuple[float, float, float]:
    """(mean, low, high): Student-t interval of the mean. One value or zero spread -> a point interval."""
    x = np.asarray(values, dtype=float)
    x = x[np.isfinite(x)]
    if len(x) == 0:
        return math.nan, math.nan, math.nan
    mean = float(x.mean())
    if len(x) < 2 or float(x.std(ddof=1)) == 0.0:
        return mean, mean, mean
    half = float(stats.t.ppf(0.5 + level / 2, len(x) - 1) * x.std(ddof=1) / np.sqrt(len(x)))
    return mean, mean - half, mean + half


def summarise(results: dict[str, dict[str, np.ndarray]]) -> list[dict[str, Any]]:
    """Rows ``{policy, metric, mean, ci_low, ci_high}`` for ``{policy: {metric: per-seed values}}``."""
    rows = []
    for policy, metrics in results.items():
        for metric, values in metrics.items():
            mean, lo, hi = confidence_interval(values)
            rows.append({"policy": policy, "metric": metric, "mean": mean, "ci_low": lo, "ci_high": hi})
    return rows


def write_csv(rows: list[dict[str, Any]], path: str | Path) -> None:
    """Write summary rows with exactly the columns ``policy,metric,mean,ci_low,ci_high``."""
    with open(path, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(RESULT_COLUMNS))
        writer.writeheader()
        for row in rows:
            writer.writerow({k: row[k] for k in RESULT_COLUMNS})


def markdown_table(rows: list[dict[str, Any]], n_seeds: int | None = None) -> str:
    """A Markdown table, one row per metric, one column per policy: ``mean [ci_low, ci_high]``."""
    policies = list(dict.fromkeys(r["policy"] for r in rows))
    metrics = list(dict.fromkeys(r["metric"] for r in rows))
    cell = {(r["policy"], r["metric"]): r for r in rows}
    lines = ["| metric | " + " | ".join(policies) + " |", "|---|" + "---|" * len(policies)]
    for m in metrics:
        vals = []
        for p in policies:
            r = cell.get((p, m))
            vals.append("" if r is None else f"{r['mean']:.4g} [{r['ci_low']:.4g}, {r['ci_high']:.4g}]")
        lines.append(f"| {m} | " + " | ".join(vals) + " |")
    note = f"\n\nmean [95 % t-interval] over {n_seeds} seeds" if n_seeds else "\n\nmean [95 % t-interval] over seeds"
    return "\n".join(lines) + note + "\n"
