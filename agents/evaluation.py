"""Evaluate policies on the swarm tasks over many seeds, with bootstrap 95 % confidence intervals.

An episode is run with :func:`run_episode`: the policy sees the named batched observations of the agents
(:meth:`swarm_envs.adapters.env.SwarmEnv.batched_observations`, rows = agents in ``possible_agents`` order); the task
metrics are read from ``infos[agent]["metrics"][name]`` by the *evaluator* only. Each task metric is reduced
over the episode as the task declares in ``Task.METRICS`` ("final" = value after the last step, "mean" = mean
over all steps after reset). ``episode_return`` is the mean over robots of the summed per-robot reward.
Confidence intervals: bootstrap percentile 95 % interval of the mean over seeds (:func:`confidence_interval`),
which lies inside the range of the per-seed values and so inside the metric's range (a fraction stays in
[0, 1]); with one seed there is no interval (the table says ``n=1``).
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
from swarm_envs.agents.tasks import env_id, metric_reductions

__all__ = [
    "make_env",
    "run_episode",
    "evaluate",
    "run_batch",
    "confidence_interval",
    "t_interval",
    "summarise",
    "write_csv",
    "markdown_table",
    "RESULT_COLUMNS",
    "random_factory",
]

RESULT_COLUMNS = ("policy", "metric", "mean", "ci_low", "ci_high", "n")
#: below this many seeds the tables warn that bootstrap intervals under-cover (tests/agents/test_confidence_intervals.py)
FEW_SEEDS = 10


def make_env(task: str, **env_kwargs: Any):
    """The parallel env of ``task`` (an env id or a short name such as ``"aggregation"``)."""
    import swarm_envs

    return swarm_envs.make(env_id(task), **env_kwargs)


def _reductions(task: str, metric_names: Any) -> dict[str, str]:
    """The task's ``METRICS`` reductions, or every metric it reports as a mean when it declares none."""
    return metric_reductions(task) or dict.fromkeys(metric_names, "mean")


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
    policy.reset(env.n_agents, rng=np.random.default_rng([seed, 7919]))
    _, infos = env.reset(seed=seed)
    reductions = _reductions(task, infos[env.possible_agents[0]]["metrics"])
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
        metrics = infos[env.possible_agents[0]]["metrics"]
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
    max_copies: int = 32,
) -> dict[str, np.ndarray]:
    """Metrics per seed ``{metric: (n_seeds,)}`` for the policy built by ``policy_factory(env)``.

    The seeds run side by side as copies of one batched core (:func:`swarm_envs.make_vec`), at most
    ``max_copies`` at a time, each copy with its own policy instance; copy b seeded with ``s`` equals a single
    env reset with ``s`` bit for bit, so the numbers are exactly those of :func:`run_episode` per seed
    (``tests/agents/test_scripted.py::test_batched_evaluation_equals_sequential``). ``max_copies=1`` runs one
    seed at a time.
    """
    if max_copies < 1:
        raise ValueError(f"max_copies must be >= 1, got {max_copies}")
    seeds = [int(s) for s in seeds]
    if not seeds:
        raise ValueError("evaluate() needs at least one seed")
    rows: list[dict[str, float]] = []
    chunks = [seeds[i : i + max_copies] for i in range(0, len(seeds), max_copies)]
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=len(seeds), desc=desc or "eval", leave=False)
    for chunk in chunks:
        rows.extend(run_batch(task, env_kwargs, policy_factory, chunk))
        if bar is not None:
            bar.update(len(chunk))
    if bar is not None:
        bar.close()
    return {name: np.array([r[name] for r in rows]) for name in rows[0]}


def run_batch(task: str, env_kwargs: dict[str, Any], policy_factory: Callable[[Any], Policy], seeds: Sequence[int]) -> list[dict[str, float]]:
    """One episode per seed, all seeds as copies of one vector env; returns reduced metrics per seed
    (as :func:`run_episode`). Episodes end at ``max_cycles`` (the tasks never terminate early)."""
    import swarm_envs

    vec = swarm_envs.make_vec(env_id(task), len(seeds), **env_kwargs)
    policies = [policy_factory(vec) for _ in seeds]
    for policy, seed in zip(policies, seeds):
        policy.reset(vec.n_agents, rng=np.random.default_rng([seed, 7919]))
    obs, infos = vec.reset(seed=list(seeds))
    reductions = _reductions(task, infos["metrics"])
    B = len(seeds)
    sums = {name: np.zeros(B) for name in reductions}
    returns = np.zeros((B, vec.n_agents))
    steps = 0
    metrics: dict[str, np.ndarray] = {}
    for _ in range(vec.max_cycles):
        actions = np.stack([np.asarray(p.act_batch({k: v[b] for k, v in obs.items()}), dtype=np.float64) for b, p in enumerate(policies)])
        obs, _, _, truncations, infos = vec.step(actions)
        returns += vec.core.rewards  # float64, as the single env reports them
        metrics = infos["metrics"]
        for name in reductions:
            sums[name] += metrics[name]
        steps += 1
        if truncations.all():
            break
    vec.close()
    out = []
    for b in range(B):
        row = {name: (metrics[name][b] if how == "final" else sums[name][b] / max(steps, 1)) for name, how in reductions.items()}
        row["episode_return"] = returns[b].mean()
        out.append({k: float(v) for k, v in row.items()})
    return out


def random_factory(env) -> Policy:
    """Factory of the uniform random baseline."""
    return RandomPolicy(env.platform, env.layout)


def confidence_interval(
    values: Sequence[float], level: float = 0.95, seed: int | Sequence[int] = 0, n_resamples: int = 9999
) -> tuple[float, float, float]:
    """(mean, low, high): bootstrap percentile interval of the mean over the finite ``values``.

    Resamples come from ``numpy.random.default_rng(seed)`` (:func:`scipy.stats.bootstrap`, ``method="percentile"``),
    so the interval lies within [min, max] of the values, hence within the metric's range. One value: no interval,
    ``(mean, nan, nan)``; no finite value: all NaN; all values equal: the point ``(mean, mean, mean)``.
    """
    x, mean = _finite(values)
    if len(x) < 2:
        return mean, math.nan, math.nan
    if float(np.ptp(x)) == 0.0:
        return mean, mean, mean
    res = stats.bootstrap((x,), np.mean, n_resamples=n_resamples, confidence_level=level, method="percentile",
                          random_state=np.random.default_rng(seed))
    lo, hi = float(res.confidence_interval.low), float(res.confidence_interval.high)
    # percentile bounds lie in [min, max] and bracket the mean up to floating-point ties: clamp those ulps
    return mean, max(min(lo, mean), float(x.min())), min(max(hi, mean), float(x.max()))


def _finite(values: Sequence[float]) -> tuple[np.ndarray, float]:
    """The finite ``values`` and their mean (NaN if none)."""
    x = np.asarray(values, dtype=float)
    x = x[np.isfinite(x)]
    return x, float(x.mean()) if len(x) else math.nan


def t_interval(values: Sequence[float], level: float = 0.95) -> tuple[float, float, float]:
    """(mean, low, high): Student-t interval of the mean of the finite ``values`` (for a few training seeds,
    each already a mean over evaluation seeds); one value: no interval ``(mean, nan, nan)``."""
    x, mean = _finite(values)
    if len(x) < 2:
        return mean, math.nan, math.nan
    half = float(stats.t.ppf(0.5 + level / 2, len(x) - 1) * x.std(ddof=1) / math.sqrt(len(x)))
    return mean, mean - half, mean + half


def summarise(results: dict[str, dict[str, np.ndarray]], seed: int = 0) -> list[dict[str, Any]]:
    """Rows ``{policy, metric, mean, ci_low, ci_high, n}`` for ``{policy: {metric: per-seed values}}``.

    ``n`` counts the finite values; the bootstrap of row ``i`` uses the generator ``default_rng([seed, i])``.
    """
    rows = []
    for policy, metrics in results.items():
        for metric, values in metrics.items():
            mean, lo, hi = confidence_interval(values, seed=[seed, len(rows)])
            n = int(np.isfinite(np.asarray(values, dtype=float)).sum())
            rows.append({"policy": policy, "metric": metric, "mean": mean, "ci_low": lo, "ci_high": hi, "n": n})
    return rows


def write_csv(rows: list[dict[str, Any]], path: str | Path) -> None:
    """Write summary rows with exactly the columns ``policy,metric,mean,ci_low,ci_high,n`` (NaN bounds: no interval)."""
    with open(path, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(RESULT_COLUMNS))
        writer.writeheader()
        for row in rows:
            writer.writerow({k: row.get(k, "") for k in RESULT_COLUMNS})


def _cell(row: dict[str, Any] | None, n_seeds: int | None) -> str:
    if row is None:
        return ""
    n = row.get("n", n_seeds)
    if not np.isfinite(row["mean"]):
        return "n/a (no finite value)"
    text = f"{row['mean']:.4g}"
    if np.isfinite(row["ci_low"]) and np.isfinite(row["ci_high"]):
        text += " (all equal)" if row["ci_low"] == row["ci_high"] else f" [{row['ci_low']:.4g}, {row['ci_high']:.4g}]"
    if n is not None and (n != n_seeds or n < 2):
        text += f" (n={n})"
    return text


def markdown_table(rows: list[dict[str, Any]], n_seeds: int | None = None) -> str:
    """A Markdown table, one row per metric, one column per policy: ``mean [ci_low, ci_high]``.

    A cell whose metric has fewer finite values than ``n_seeds``, or fewer than 2, says ``(n=k)``; with one
    value there is no interval.
    """
    policies = list(dict.fromkeys(r["policy"] for r in rows))
    metrics = list(dict.fromkeys(r["metric"] for r in rows))
    cell = {(r["policy"], r["metric"]): r for r in rows}
    lines = ["| metric | " + " | ".join(policies) + " |", "|---|" + "---|" * len(policies)]
    for m in metrics:
        lines.append(f"| {m} | " + " | ".join(_cell(cell.get((p, m)), n_seeds) for p in policies) + " |")
    ns = sorted({r.get("n") for r in rows if r.get("n") is not None})
    n_text = f"n={n_seeds} seeds" if n_seeds else ("n=" + "/".join(map(str, ns)) + " seeds" if ns else "seeds")
    if n_seeds == 1 or (not n_seeds and ns == [1]):
        note = f"\n\nmean over {n_text} (one seed: no confidence interval)"
    else:
        note = f"\n\nmean [95 % bootstrap percentile interval of the mean] over {n_text}"
        if min(ns or [n_seeds or 0]) < FEW_SEEDS:
            note += (f"; with fewer than {FEW_SEEDS} seeds these intervals are too narrow (real coverage of a nominal "
                     "95 % bootstrap interval, normal data: ~52 % at n=2, ~71 % at n=3, ~85 % at n=5)")
    return "\n".join(lines) + note + "\n"
