"""The ``sensing="ideal"`` stack: exact, noiseless, lossless values in the same layout as the full stack.

An ablation (what would a policy do with perfect sensing?) and a check that the observation layout is
right. Neighbours are all robots within the platform's IR range (no occlusion); messages reach every
robot in range instantly; scale-free coordinates are the true relative positions divided by the mean
neighbour distance.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from swarm_envs.observation import pack_nearest, relative_pose
from swarm_envs.platforms import Platform
from swarm_envs.sensing.base import MessageReadings, NeighbourReadings, ScaleFreeReadings, SensorFrame

__all__ = ["IdealSensing", "neighbour_pairs"]


def neighbour_pairs(positions: np.ndarray, max_range: float) -> tuple[np.ndarray, np.ndarray]:
    """Both directions (rx, tx) of every pair of centres closer than ``max_range`` (m); KD-tree, not N^2."""
    pairs = cKDTree(positions).query_pairs(max_range, output_type="ndarray")
    if len(pairs) == 0:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty
    return np.concatenate([pairs[:, 0], pairs[:, 1]]), np.concatenate([pairs[:, 1], pairs[:, 0]])


class IdealSensing:
    """Ground-truth sensing within IR range (see module docstring)."""

    def __init__(self, platform: Platform, n_robots: int, n_neighbours: int, message_bits: int) -> None:
        self.platform = platform
        self.n = n_robots
        self.k = n_neighbours
        self.message_bits = message_bits

    def reset(self, rng: np.random.Generator | None = None) -> None:
        """Nothing to reset: the ideal stack is stateless and noiseless."""

    def step(self, positions: np.ndarray, headings: np.ndarray, payloads: np.ndarray | None) -> SensorFrame:
        rx, tx = neighbour_pairs(positions, self.platform.ir_range)
        distance, bearing, heading = relative_pose(positions, headings, rx, tx)
        neighbours = NeighbourReadings(rx, tx, distance, bearing, heading, np.zeros(len(rx)))

        if self.message_bits > 0 and payloads is not None:
            messages = MessageReadings(rx, tx, bearing, payloads[tx].astype(float), distance)
        else:
            messages = MessageReadings(payload=np.zeros((0, self.message_bits)))

        mean_distance = np.bincount(rx, distance, self.n) / np.maximum(np.bincount(rx, minlength=self.n), 1)
        scale = np.where(mean_distance > 0, mean_distance, 1.0)[rx]
        local = np.stack([distance * np.cos(bearing), distance * np.sin(bearing)], -1) / scale[:, None]
        packed, order = pack_nearest(self.n, rx, distance, local, self.k)
        valid = order >= 0
        scale_free = ScaleFreeReadings(packed, valid, valid.any(axis=1))
        return SensorFrame(neighbours, messages, scale_free)
