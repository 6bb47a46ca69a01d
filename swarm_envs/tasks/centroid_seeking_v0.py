"""Centroid seeking: seekers move to the centroid of static anchor robots ([L] Sec. 6.2).

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

from swarm_envs.tasks.factories import task_module
from swarm_envs.tasks.task import BatchState, Default, Int, SettingsError, Task, lattice_positions, spawn_positions

__all__ = ["CentroidSeekingTask", "CentroidSeekingEnv", "raw_env", "parallel_env", "env"]

#: gap (fraction of the radius) random placement keeps between seekers and from the anchors
SEEKER_GAP = 0.2
#: random anchor polygons a reset tries before it takes the fallback layout (crowded arenas only)
ANCHOR_DRAWS = 10


class CentroidSeekingTask(Task):
    """Centroid-seeking rewards and metrics over all env copies; extra kwarg ``n_anchors`` (default 4, >= 3)."""

    SETTINGS = {
        "n_robots": Default(1, help="number of agents (seekers)"),
        "n_anchors": Int(
            4, "static robots on a convex polygon", low=3, high=1000,
            why="at least 3 corners for a polygon around the centroid; at most 1,000 static robots (they must also fit on "
            "their circle, checked when the env is built)",
            help="static anchor robots (at least 3): they emit infrared and talk but are not agents",
        ),
    }
    METRICS = {"mean_distance_second_half": "final", "mean_distance_to_centroid": "final"}
    HEADLINE = ("mean_distance_second_half", -1)
    SCRIPTED_POLICY = "swarm_envs.agents.scripted:CentroidSeeker"

    def __init__(self, config: dict[str, Any], platform, n_copies: int = 1) -> None:
        super().__init__(config, platform, n_copies)
        # per copy, the cumulative sum of the mean seeker distance over steps 0 .. t (index t + 1); grown
        # as episodes run (memory follows the steps taken, not max_cycles)
        self._distance_cumsum = np.zeros((self.n_copies, 64))

    def n_static_robots(self) -> int:
        return self.config["n_anchors"]

    def default_arena_size(self) -> float:
        # room for an anchor polygon of radius ~0.3 IR ranges plus seekers around it
        return max(super().default_arena_size(), 0.9 * self.platform.ir_range)

    def _anchor_min_angle(self) -> float:
        """Smallest angle (rad) between neighbouring anchors on their circle: a chord of 2.1 radii."""
        ratio = 1.05 * self.platform.radius / self.polygon_radius
        return 2 * float(np.arcsin(ratio)) if ratio < 1 else np.inf

    def check_layout(self) -> None:
        """The anchors fit on their circle and inside the arena, and the seekers beside them for every
        seed: the spawner's last resort (:meth:`fallback_layout`) holds them."""
        n_a, angle = self.n_static, self._anchor_min_angle()
        if n_a * angle >= 2 * np.pi:
            fit = int(np.ceil(2 * np.pi / angle)) - 1 if np.isfinite(angle) else 0
            raise SettingsError(
                "n_anchors",
                f"n_anchors={n_a} anchors of diameter {2 * self.platform.radius:.3f} m do not fit on the anchor circle "
                f"of radius {self.polygon_radius:.3f} m (0.3 x min(IR range, arena size)): at most {fit} fit; "
                "use fewer anchors",
            )
        if self.polygon_radius + self.platform.radius > self.arena.half:
            raise SettingsError(
                self.size_key,
                f"the anchors (diameter {self.platform.diameter:.3f} m) on their circle of radius {self.polygon_radius:.3f} m "
                f"(0.3 x arena size) reach past the walls of the {self.arena.size:.4g} m arena: use arena_size >= "
                f"{5 * self.platform.radius:.4g} m",
            )
        fit = len(self.fallback_layout()[1])
        if fit < self.n_agents:
            raise SettingsError(
                self.size_key,
                f"n_robots={self.n_agents} seekers of diameter {self.platform.diameter:.3f} m do not fit beside "
                f"{n_a} anchors in a {self.arena.shape} arena of size {self.arena.size:.4g} m: at most {fit} fit for sure "
                "(a lattice around evenly spaced anchors); use fewer robots or a larger arena_size",
            )

    @property
    def polygon_radius(self) -> float:
        """Radius (m) of the circle the anchors stand on: within IR range of each other."""
        return min(0.3 * self.platform.ir_range, 0.3 * self.arena.size)

    def fallback_layout(self) -> tuple[np.ndarray, np.ndarray]:
        """The spawner's last resort, fixed when the env is built: (anchors (n_anchors, 2) m evenly spaced
        on their circle, seeker spots (k, 2) m on a lattice, touching neighbours and at least a diameter from
        every anchor). A reset that cannot draw a random layout takes these anchors and a random choice of
        ``n_robots`` of the spots."""
        if getattr(self, "_fallback", None) is None:
            n_a, radius = self.n_static, self.platform.radius
            best = None
            for offset in (0.0, np.pi / n_a):  # two rotations of the regular polygon
                angles = offset + 2 * np.pi * np.arange(n_a) / n_a
                anchors = self.polygon_radius * np.stack([np.cos(angles), np.sin(angles)], -1)
                spots = lattice_positions(self.arena, radius, n=self.n_agents, avoid=anchors, avoid_distance=2 * radius)
                if best is None or len(spots) > len(best[1]):
                    best = (anchors, spots)
            self._fallback = best
        return self._fallback

    def _draw_anchors(self, rng: np.random.Generator) -> np.ndarray | None:
        """Anchors (n_anchors, 2) m at random angles on their circle, corners apart by at least a diameter
        and a margin and no gap wider than 0.95 pi (a convex polygon around the centre); None if the draws fail."""
        n_a = self.n_static
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
                return None
            angles = np.sort((rng.uniform(-np.pi, np.pi) + np.cumsum(gaps) + np.pi) % (2 * np.pi) - np.pi)
        return self.polygon_radius * np.stack([np.cos(angles), np.sin(angles)], -1)

    def spawn(self, rng: np.random.Generator):
        radius = self.platform.radius
        for _ in range(ANCHOR_DRAWS):
            anchors = self._draw_anchors(rng)
            if anchors is None:
                break
            try:  # seekers uniformly at random, SEEKER_GAP apart and from the anchors
                seekers = spawn_positions(
                    rng, self.n_agents, radius, self.arena, gap=SEEKER_GAP * radius, max_tries=50,
                    avoid=anchors, avoid_distance=(2 + SEEKER_GAP) * radius,
                )
            except ValueError:  # crowded: draw another polygon
                continue
            return np.concatenate([anchors, seekers]), rng.uniform(-np.pi, np.pi, self.n_world)
        anchors, spots = self.fallback_layout()  # holds the seekers (checked when the env was built)
        seekers = spots[np.sort(rng.choice(len(spots), self.n_agents, replace=False))]
        return np.concatenate([anchors, seekers]), rng.uniform(-np.pi, np.pi, self.n_world)

    def centroids(self, positions: np.ndarray) -> np.ndarray:
        """The anchors' centroid (..., 2) m of positions (..., n_world, 2), ground truth."""
        return positions[..., : self.n_static, :].mean(axis=-2)

    def rewards(self, state: BatchState, first: np.ndarray):
        seekers = self.agents_of(state.positions)  # (B, A, 2)
        dist = np.linalg.norm(seekers - self.centroids(state.positions)[:, None, :], axis=2)  # (B, A)
        mean_dist = dist.mean(axis=1)
        copies = np.arange(self.n_copies)
        t = np.minimum(state.num_cycles, self.max_cycles)
        if t.max() + 2 > self._distance_cumsum.shape[1]:
            grown = np.zeros((self.n_copies, max(2 * self._distance_cumsum.shape[1], int(t.max()) + 2)))
            grown[:, : self._distance_cumsum.shape[1]] = self._distance_cumsum
            self._distance_cumsum = grown
        self._distance_cumsum[first, 0] = 0.0
        self._distance_cumsum[copies, t + 1] = self._distance_cumsum[copies, t] + mean_dist
        # steps ceil(t/2) .. t: at the end of an episode, its second half (never NaN)
        start = -(-t // 2)
        second = (self._distance_cumsum[copies, t + 1] - self._distance_cumsum[copies, start]) / (t + 1 - start)
        rewards = -dist / self.arena.size
        if self.reward_mode == "global":
            rewards = np.repeat(rewards.mean(axis=1)[:, None], self.n_agents, axis=1)
        metrics = {"mean_distance_to_centroid": mean_dist, "mean_distance_second_half": second}
        return rewards, {"distance_to_centroid": dist}, metrics

    def markers(self, positions: np.ndarray) -> dict[str, np.ndarray]:
        return {"centroid": self.centroids(positions)}


def _centroid(env: Any) -> np.ndarray:
    """The anchors' centroid (m), ground truth."""
    return env.task.centroids(env.world.positions)


_DOC = """Create the centroid-seeking environment (a native PettingZoo ``ParallelEnv``).

## Description

Centroid seeking ([L] Sec. 6.2): ``n_anchors`` static robots stand at the corners of a
random convex polygon; the ``n_robots`` seekers (the agents, ``robot_0`` ..) should reach the
anchors' centroid. Anchors are not agents, but they emit infrared and talk, so seekers sense them
like any robot (for example through scale-free coordinates).

## Rewards

Each seeker gets ``-d / L``, its distance d (m) to the anchors' centroid over the arena size L (m);
``reward_mode="global"`` gives every seeker the mean over seekers. Term in
``infos[agent]["reward_terms"][name]``: ``distance_to_centroid`` (m). Metrics in
``infos[agent]["metrics"][name]``: ``mean_distance_to_centroid`` and ``mean_distance_second_half`` (m, the
mean over the second half of the episode so far; compare [L]'s 14.03 cm).

## Starting State

Anchors stand at random angles on a circle around the arena centre of radius
``min(0.3 ir_range, 0.3 arena_size)`` (corners kept apart, so the polygon is convex); seekers are
placed uniformly at random at least 2.2 robot radii from every anchor. In an arena too crowded for
random draws, a reset takes evenly spaced anchors and seekers on lattice spots instead; the env is only
built if those hold the seekers, so every seed resets. The default ``arena_size`` is at least 0.9 ``ir_range``. In ``options["positions"]`` the anchors come first. Headings are uniform in [-pi, pi). ``reset(seed=..., options={"positions": (N, 2) m, "headings": (N,)
rad})`` places the robots exactly instead; overlapping or out-of-arena placements raise. All
randomness flows from the seed through independent child streams.

## Version History

- v0: initial release (swarm_envs 0.1.0).
"""

raw_env, parallel_env, env = task_module(CentroidSeekingTask, _DOC, members={"centroid": property(_centroid)})
CentroidSeekingEnv = raw_env
