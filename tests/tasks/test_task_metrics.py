"""Every task's metrics can fail: the headline metric separates the scripted baseline from random actions,
and no metric takes the same value under the scripted, the random and a still policy."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from swarm_envs.agents.base import Policy, RandomPolicy
from swarm_envs.agents.evaluation import evaluate
from swarm_envs.agents.scripted import make_scripted
from swarm_envs.agents.tasks import SHORT_NAMES, headline, scripted_policy

SEEDS = list(range(5))  # one-sided Mann-Whitney U with 5 + 5 seeds reaches p = 0.004 at best
#: episode length per task: long enough for the scripted behaviour to show (the mid-angle seeker needs ~50 s;
#: parity clustering runs its default 50 s: after 20 s its groups have not formed, segregation 0.18-0.27 over
#: seeds 0-4 against up to 0.36 for random actions on one seed)
STEPS = {"mid_angle_navigation": 600, "centroid_seeking": 300, "parity_clustering": 500}
#: more seeds where the headline is a success share (about half the scripted seekers arrive in 60 s)
TASK_SEEDS = {"mid_angle_navigation": list(range(12))}


#: the tasks whose evaluations take longest (600 and 500 steps, 12 and 5 seeds): their cases run with `-m slow`
LONG = {"mid_angle_navigation", "parity_clustering"}
TASKS = [pytest.param(t, marks=pytest.mark.slow) if t in LONG else t for t in SHORT_NAMES]


class Still(Policy):
    """Every robot stands still (its message bits silent)."""

    name = "still"

    def act_batch(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        n = len(obs["proprio"])
        return self.compose(np.zeros(n), np.zeros(n))


@pytest.fixture(scope="module")
def results():
    return {}


def _run(task: str, cache: dict) -> dict[str, dict[str, np.ndarray]]:
    if task not in cache:
        kwargs = {"max_cycles": STEPS.get(task, 200), "sensing": "full"}
        factories = {
            "scripted": lambda env: make_scripted(scripted_policy(task), env),
            "random": lambda env: RandomPolicy(env.platform, env.layout),
            "still": lambda env: Still(env.platform, env.layout),
        }
        seeds = TASK_SEEDS.get(task, SEEDS)
        cache[task] = {name: evaluate(task, kwargs, factory, seeds) for name, factory in factories.items()}
    return cache[task]


@pytest.mark.parametrize("task", TASKS)
def test_headline_separates_the_scripted_baseline_from_random(task, results):
    metric, sign = headline(task)
    runs = _run(task, results)
    scripted, random = runs["scripted"][metric], runs["random"][metric]
    scripted, random = np.nan_to_num(scripted, nan=-np.inf * sign), np.nan_to_num(random, nan=-np.inf * sign)
    p = stats.mannwhitneyu(scripted, random, alternative="greater" if sign > 0 else "less").pvalue
    assert p < 0.05, f"{task}: {metric} scripted {scripted} vs random {random} (p = {p:.3f})"


@pytest.mark.parametrize("task", TASKS)
def test_no_metric_is_the_same_under_every_policy(task, results):
    runs = _run(task, results)
    for metric in runs["scripted"]:
        means = [np.nanmean(runs[p][metric]) if np.isfinite(runs[p][metric]).any() else np.nan for p in runs]
        distinct = {round(float(m), 9) if np.isfinite(m) else "nan" for m in means}
        assert len(distinct) > 1, f"{task}: {metric} is {means[0]} under scripted, random and still policies alike"
