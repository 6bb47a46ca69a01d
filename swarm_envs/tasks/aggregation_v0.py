"""Aggregation: robots start spread out and should gather into one cluster (docs/design.md#tasks).

Reward (global, default) = decrease of the swarm's spread (mean distance to the centroid) this step,
normalised by the arena size; ``reward_mode="local"`` rewards each robot for the decrease of its own
distance to the centroid. Metrics in ``infos[agent]["metrics"][name]``: largest-cluster fraction (clusters =
robots whose centres are within 1.5 diameters, chained), number of clusters, mean distance to centroid (m).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from swarm_envs.tasks.factories import task_module
from swarm_envs.tasks.task import BatchState, Task, largest_component_fraction

__all__ = ["AggregationTask", "AggregationEnv", "raw_env", "parallel_env", "env"]

CLUSTER_LINK_DIAMETERS = 1.5


class AggregationTask(Task):
    """Aggregation rewards and metrics over all env copies (module docstring)."""

    METRICS = {"largest_cluster_fraction": "final", "n_clusters": "final", "mean_distance_to_centroid": "final"}
    HEADLINE = ("largest_cluster_fraction", +1)
    SCRIPTED_POLICY = "swarm_envs.agents.scripted:BearingAggregation"

    def __init__(self, config: dict[str, Any], platform, n_copies: int = 1) -> None:
        super().__init__(config, platform, n_copies)
        self._prev_own = np.zeros((self.n_copies, self.n_agents))

    def rewards(self, state: BatchState, first: np.ndarray):
        pos = self.agents_of(state.positions)  # (B, A, 2)
        own = np.linalg.norm(pos - pos.mean(axis=1, keepdims=True), axis=2)  # (B, A)
        spread = own.mean(axis=1)
        self._prev_own[first] = own[first]
        size = self.arena.size
        global_term = (self._prev_own.mean(axis=1) - spread) / size  # (B,)
        local_term = (self._prev_own - own) / size
        self._prev_own = own
        global_rows = np.repeat(global_term[:, None], self.n_agents, axis=1)
        rewards = global_rows if self.reward_mode == "global" else local_term
        link = CLUSTER_LINK_DIAMETERS * self.platform.diameter
        largest, n_clusters = largest_component_fraction(pos, link)
        metrics = {
            "largest_cluster_fraction": largest,
            "n_clusters": n_clusters.astype(float),
            "mean_distance_to_centroid": spread,
        }
        terms = {"spread_decrease": global_rows, "own_distance_decrease": local_term}
        return rewards, terms, metrics

    def markers(self, positions: np.ndarray) -> dict[str, np.ndarray]:
        return {"centroid": positions[self.n_static :].mean(axis=0)}


_DOC = """Create the aggregation environment (a native PettingZoo ``ParallelEnv``).

## Description

Aggregation (docs/design.md#tasks): ``n_robots`` robots start spread over the arena and should gather into one
cluster, sensing each other only through infrared. Two robots are in one cluster when their centres
are within 1.5 diameters (chained). Agents are named ``robot_0`` .. ``robot_{N-1}``.

## Rewards

With ``D_t`` the robots' mean distance (m) to their centroid and ``L`` the arena size (m):
``reward_mode="global"`` gives every agent ``(D_{t-1} - D_t) / L``, the decrease of the swarm's
spread this step; ``"local"`` gives each robot the decrease of its own distance to the centroid, / L.
Both terms are in ``infos[agent]["reward_terms"][name]`` (``spread_decrease``, ``own_distance_decrease``).
Metrics in ``infos[agent]["metrics"][name]``: ``largest_cluster_fraction``, ``n_clusters``,
``mean_distance_to_centroid`` (m).

## Version History

- v0: initial release (swarm_envs 0.1.0).
"""

raw_env, parallel_env, env = task_module(AggregationTask, _DOC)
AggregationEnv = raw_env
