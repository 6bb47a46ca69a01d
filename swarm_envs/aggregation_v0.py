"""Aggregation: robots start spread out and should gather into one cluster (SPEC 6).

Reward (global, default) = decrease of the swarm's spread (mean distance to the centroid) this step,
normalised by the arena size; ``reward_mode="local"`` rewards each robot for the decrease of its own
distance to the centroid. Metrics in ``infos[agent]["metrics"]``: largest-cluster fraction (clusters =
robots whose centres are within 1.5 diameters, chained), number of clusters, mean distance to centroid (m).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from pettingzoo.utils.conversions import parallel_to_aec

from swarm_envs.env import SwarmEnv
from swarm_envs.metrics import largest_component_fraction
from swarm_envs.task import BatchState, Task

__all__ = ["AggregationTask", "AggregationEnv", "raw_env", "parallel_env", "env"]

CLUSTER_LINK_DIAMETERS = 1.5


class AggregationTask(Task):
    """Aggregation rewards and metrics over all env copies (module docstring)."""

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


class AggregationEnv(SwarmEnv):
    """Aggregation task; see the module docstring and :class:`swarm_envs.env.SwarmEnv` for kwargs."""

    metadata = {**SwarmEnv.metadata, "name": "aggregation_v0"}
    TASK = AggregationTask


raw_env = AggregationEnv


def parallel_env(**kwargs: Any) -> AggregationEnv:
    """The native parallel environment."""
    return AggregationEnv(**kwargs)


def env(**kwargs: Any):
    """The AEC (turn-based) view of the parallel environment (PettingZoo ``parallel_to_aec``)."""
    return parallel_to_aec(parallel_env(**kwargs))
