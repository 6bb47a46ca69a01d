"""Aggregation: robots start spread out and should gather into one cluster (SPEC 6).

Reward (global, default) = decrease of the swarm's spread (mean distance to the centroid) this step,
normalised by the arena size; ``reward_mode="local"`` rewards each robot for the decrease of its own
distance to the centroid. Metrics in ``infos[agent]["metrics", name]``: largest-cluster fraction (clusters =
robots whose centres are within 1.5 diameters, chained), number of clusters, mean distance to centroid (m).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from pettingzoo.utils.conversions import parallel_to_aec

from swarm_envs.env import SwarmEnv
from swarm_envs.metrics import cluster_stats, mean_distance_to_centroid

__all__ = ["AggregationEnv", "raw_env", "parallel_env", "env"]

CLUSTER_LINK_DIAMETERS = 1.5


class AggregationEnv(SwarmEnv):
    """Aggregation task; see the module docstring and :class:`swarm_envs.env.SwarmEnv` for kwargs."""

    metadata = {**SwarmEnv.metadata, "name": "aggregation_v0"}

    def _rewards(self, first: bool):
        pos = self.world.positions[self.agent_robots]
        own = np.linalg.norm(pos - pos.mean(axis=0), axis=1)
        spread = float(own.mean())
        if first:
            self._prev_own = own
        size = self.arena.size
        global_term = (self._prev_own.mean() - spread) / size
        local_term = (self._prev_own - own) / size
        self._prev_own = own
        rewards = np.full(self.n_agents, global_term) if self.reward_mode == "global" else local_term
        largest, n_clusters = cluster_stats(pos, CLUSTER_LINK_DIAMETERS * self.platform.diameter)
        metrics = {
            "largest_cluster_fraction": largest,
            "n_clusters": float(n_clusters),
            "mean_distance_to_centroid": mean_distance_to_centroid(pos),
        }
        terms = {"spread_decrease": np.full(self.n_agents, global_term), "own_distance_decrease": local_term}
        return rewards, terms, metrics

    def _markers(self) -> dict[str, np.ndarray]:
        return {"centroid": self.world.positions[self.agent_robots].mean(axis=0)}


raw_env = AggregationEnv


def parallel_env(**kwargs: Any) -> AggregationEnv:
    """The native parallel environment."""
    return AggregationEnv(**kwargs)


def env(**kwargs: Any):
    """The AEC (turn-based) view of the parallel environment (PettingZoo ``parallel_to_aec``)."""
    return parallel_to_aec(parallel_env(**kwargs))
