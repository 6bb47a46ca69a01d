"""Centroid seeking: seekers move to the centroid of static anchor robots (SPEC 6, [L] Sec. 6.2).

``n_anchors`` static robots (default 4) stand at the corners of a random convex polygon; they are not
agents but still emit infrared and talk, so seekers can sense them. The agents are the ``n_robots``
seekers (default 1). Reward = -distance of the seeker to the anchors' centroid / arena size.
Metric ``mean_distance_second_half`` = mean seeker-centroid distance (m) over the second half of the
episode so far, i.e. over steps ceil(t/2) .. t at step t (just the current distance at reset; never NaN),
which at the last step is the mean over the episode's second half (compare [L] 14.03 cm with
d_step = 11 cm).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from pettingzoo.utils.conversions import parallel_to_aec
from scipy.spatial import cKDTree

from swarm_envs.env import SwarmEnv
from swarm_envs.settings import SettingsError
from swarm_envs.world import Arena, spawn_positions

__all__ = ["CentroidSeekingEnv", "raw_env", "parallel_env", "env"]


class CentroidSeekingEnv(SwarmEnv):
    """Centroid-seeking task; extra kwarg ``n_anchors`` (default 4, at least 3)."""

    metadata = {**SwarmEnv.metadata, "name": "centroid_seeking_v0"}
    TASK_DEFAULTS = {"n_anchors": 4, "n_robots": 1}

    def _n_static(self) -> int:
        n = self.config["n_anchors"]
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 3:
            raise ValueError(f"n_anchors must be an integer >= 3 (a polygon), got {n!r}")
        return int(n)

    def _default_arena_size(self) -> float:
        # room for an anchor polygon of radius ~0.3 IR ranges plus seekers around it
        return max(super()._default_arena_size(), 0.9 * self.platform.ir_range)

    def _anchor_min_angle(self) -> float:
        """Smallest angle (rad) between neighbouring anchors on their circle: a chord of 2.1 radii."""
        ratio = 1.05 * self.platform.radius / self.polygon_radius
        return 2 * float(np.arcsin(ratio)) if ratio < 1 else np.inf

    def _check_layout(self) -> None:
        n_a, angle = self.n_static, self._anchor_min_angle()
        if n_a * angle >= 2 * np.pi:
            fit = int(np.ceil(2 * np.pi / angle)) - 1 if np.isfinite(angle) else 0
            raise SettingsError(
                "n_anchors",
                f"n_anchors={n_a} anchors of diameter {2 * self.platform.radius:.3f} m do not fit on the anchor circle "
                f"of radius {self.polygon_radius:.3f} m (0.3 x min(IR range, arena size)): at most {fit} fit; "
                "use fewer anchors",
            )

    @property
    def polygon_radius(self) -> float:
        """Radius (m) of the circle the anchors stand on: within IR range of each other."""
        return min(0.3 * self.platform.ir_range, 0.3 * self.arena.size)

    def _spawn(self, rng: np.random.Generator):
        n_a, radius = self.n_static, self.platform.radius
        # points on a circle are in convex position; keep corners apart by at least a diameter + margin
        min_gap = max(2 * np.pi / n_a * 0.4, self._anchor_min_angle())
        for _ in range(1000):
            angles = np.sort(rng.uniform(-np.pi, np.pi, n_a))
            gaps = np.diff(np.concatenate([angles, angles[:1] + 2 * np.pi]))
            if gaps.min() > min_gap and gaps.max() < np.pi * 0.95:
                break
        else:  # many anchors: rejection rarely succeeds, so draw the gaps directly (min_gap + a random share)
            for _ in range(1000):
                gaps = min_gap + (2 * np.pi - n_a * min_gap) * rng.dirichlet(np.ones(n_a))
                if gaps.max() < np.pi * 0.95:
                    break
            else:
                raise ValueError(f"could not place {n_a} anchors in convex position; use fewer anchors")
            angles = np.sort((rng.uniform(-np.pi, np.pi) + np.cumsum(gaps) + np.pi) % (2 * np.pi) - np.pi)
        anchors = self.polygon_radius * np.stack([np.cos(angles), np.sin(angles)], -1)
        seekers = np.empty((0, 2))
        for _ in range(200):
            cand = spawn_positions(rng, self.n_agents, radius, self.arena, gap=0.2 * radius)
            d, _ = cKDTree(anchors).query(cand)
            if np.all(d > 2.2 * radius):
                seekers = cand
                break
        else:  # crowded: place the seekers around the anchors directly
            seekers = spawn_positions(
                rng, self.n_agents, radius, self.arena, gap=0.2 * radius, avoid=anchors, avoid_distance=2.2 * radius * (1 + 1e-9)
            )
        positions = np.concatenate([anchors, seekers])
        return positions, rng.uniform(-np.pi, np.pi, self.n_world)

    @property
    def centroid(self) -> np.ndarray:
        """The anchors' centroid (m), ground truth."""
        return self.world.positions[: self.n_static].mean(axis=0)

    def _rewards(self, first: bool):
        seekers = self.world.positions[self.agent_robots]
        dist = np.linalg.norm(seekers - self.centroid, axis=1)
        if first:
            self._distance_cumsum = [0.0]  # cumulative sum of the mean distance over steps 0 .. t
        self._distance_cumsum.append(self._distance_cumsum[-1] + float(dist.mean()))
        # steps t/2 .. t (num_cycles >= t/2): at the end of an episode, its second half
        start = -(-self.num_cycles // 2)
        second_half = (self._distance_cumsum[-1] - self._distance_cumsum[start]) / (self.num_cycles + 1 - start)
        rewards = -dist / self.arena.size
        if self.reward_mode == "global":
            rewards = np.full(self.n_agents, rewards.mean())
        metrics = {
            "mean_distance_to_centroid": float(dist.mean()),
            "mean_distance_second_half": second_half,
        }
        return rewards, {"distance_to_centroid": dist}, metrics

    def _markers(self) -> dict[str, np.ndarray]:
        return {"centroid": self.centroid}


raw_env = CentroidSeekingEnv


def parallel_env(**kwargs: Any) -> CentroidSeekingEnv:
    """The native parallel environment."""
    return CentroidSeekingEnv(**kwargs)


def env(**kwargs: Any):
    """The AEC (turn-based) view of the parallel environment (PettingZoo ``parallel_to_aec``)."""
    return parallel_to_aec(parallel_env(**kwargs))
