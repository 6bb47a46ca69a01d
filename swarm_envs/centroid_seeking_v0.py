"""Centroid seeking: seekers move to the centroid of static anchor robots (SPEC 6, [L] Sec. 6.2).

``n_anchors`` static robots (default 4) stand at the corners of a random convex polygon; they are not
agents but still emit infrared and talk, so seekers can sense them. The agents are the ``n_robots``
seekers (default 1). Reward = -distance of the seeker to the anchors' centroid / arena size.
Metric ``mean_distance_second_half`` = mean seeker-centroid distance (m) over the second half of the
episode so far (compare [L] 14.03 cm with d_step = 11 cm).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from pettingzoo.utils.conversions import parallel_to_aec
from scipy.spatial import cKDTree

from swarm_envs.env import SwarmEnv
from swarm_envs.task import BatchState, Task
from swarm_envs.world import spawn_positions

__all__ = ["CentroidSeekingTask", "CentroidSeekingEnv", "raw_env", "parallel_env", "env"]


class CentroidSeekingTask(Task):
    """Centroid-seeking rewards and metrics over all env copies; extra kwarg ``n_anchors`` (default 4, >= 3)."""

    TASK_DEFAULTS = {"n_anchors": 4, "n_robots": 1}

    def __init__(self, config: dict[str, Any], platform, n_copies: int = 1) -> None:
        super().__init__(config, platform, n_copies)
        self._second_half_sum = np.zeros(self.n_copies)
        self._second_half_steps = np.zeros(self.n_copies, dtype=np.int64)

    def _n_static(self) -> int:
        n = self.config["n_anchors"]
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 3:
            raise ValueError(f"n_anchors must be an integer >= 3 (a polygon), got {n!r}")
        return int(n)

    def default_arena_size(self) -> float:
        # room for an anchor polygon of radius ~0.3 IR ranges plus seekers around it
        return max(super().default_arena_size(), 0.9 * self.platform.ir_range)

    @property
    def polygon_radius(self) -> float:
        """Radius (m) of the circle the anchors stand on: within IR range of each other."""
        return min(0.3 * self.platform.ir_range, 0.3 * self.arena.size)

    def spawn(self, rng: np.random.Generator):
        n_a, radius = self.n_static, self.platform.radius
        # points on a circle are in convex position; keep corners apart by at least a diameter + margin
        for _ in range(1000):
            angles = np.sort(rng.uniform(-np.pi, np.pi, n_a))
            gaps = np.diff(np.concatenate([angles, angles[:1] + 2 * np.pi]))
            if gaps.min() > 2 * np.pi / n_a * 0.4 and gaps.max() < np.pi * 0.95:
                break
        anchors = self.polygon_radius * np.stack([np.cos(angles), np.sin(angles)], -1)
        seekers = np.empty((0, 2))
        for _ in range(200):
            cand = spawn_positions(rng, self.n_agents, radius, self.arena, gap=0.2 * radius)
            d, _ = cKDTree(anchors).query(cand)
            if np.all(d > 2.2 * radius):
                seekers = cand
                break
        else:
            raise ValueError("could not place the seekers away from the anchors; use a larger arena_size")
        positions = np.concatenate([anchors, seekers])
        return positions, rng.uniform(-np.pi, np.pi, self.n_world)

    def centroids(self, positions: np.ndarray) -> np.ndarray:
        """The anchors' centroid (..., 2) m of positions (..., n_world, 2), ground truth."""
        return positions[..., : self.n_static, :].mean(axis=-2)

    def rewards(self, state: BatchState, first: np.ndarray):
        seekers = self.agents_of(state.positions)  # (B, A, 2)
        dist = np.linalg.norm(seekers - self.centroids(state.positions)[:, None, :], axis=2)  # (B, A)
        mean_dist = dist.mean(axis=1)
        self._second_half_sum[first] = 0.0
        self._second_half_steps[first] = 0
        late = state.num_cycles >= self.max_cycles / 2
        self._second_half_sum[late] += mean_dist[late]
        self._second_half_steps[late] += 1
        rewards = -dist / self.arena.size
        if self.reward_mode == "global":
            rewards = np.repeat(rewards.mean(axis=1)[:, None], self.n_agents, axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            second = np.where(self._second_half_steps > 0, self._second_half_sum / np.maximum(self._second_half_steps, 1), np.nan)
        metrics = {"mean_distance_to_centroid": mean_dist, "mean_distance_second_half": second}
        return rewards, {"distance_to_centroid": dist}, metrics

    def markers(self, positions: np.ndarray) -> dict[str, np.ndarray]:
        return {"centroid": self.centroids(positions)}


class CentroidSeekingEnv(SwarmEnv):
    """Centroid-seeking task; extra kwarg ``n_anchors`` (default 4, at least 3)."""

    metadata = {**SwarmEnv.metadata, "name": "centroid_seeking_v0"}
    TASK = CentroidSeekingTask

    @property
    def centroid(self) -> np.ndarray:
        """The anchors' centroid (m), ground truth."""
        return self.task.centroids(self.world.positions)


raw_env = CentroidSeekingEnv


def parallel_env(**kwargs: Any) -> CentroidSeekingEnv:
    """The native parallel environment."""
    return CentroidSeekingEnv(**kwargs)


def env(**kwargs: Any):
    """The AEC (turn-based) view of the parallel environment (PettingZoo ``parallel_to_aec``)."""
    return parallel_to_aec(parallel_env(**kwargs))
