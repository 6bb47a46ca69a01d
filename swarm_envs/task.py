"""What a task adds to the simulation core: its robots, spawn, rewards and metrics, over all env copies.

A :class:`Task` sees the ground-truth state of ``B`` env copies as ``(B, n_world, ...)`` arrays
(:class:`BatchState`) and returns rewards and reward terms per agent ``(B, n_agents)`` and metrics per
copy ``(B,)``. Rewards and metrics are computed from ground truth; they reach the agents only as
rewards and ``infos``, never as observations.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from swarm_envs.platforms import Platform
from swarm_envs.world import N_BUMP_SECTORS, Arena, check_capacity, spawn_positions

__all__ = ["BatchState", "Task", "SPACING"]

#: default centre spacing (m) used to size the arena when ``arena_size`` is None
SPACING = {"droplet": 0.15, "epuck": 0.25, "rone": 0.45}


@dataclass
class BatchState:
    """Ground truth of ``B`` copies after a control step (world frame, SI).

    Attributes:
        positions: (B, n_world, 2) m.
        headings: (B, n_world) rad.
        velocities: (B, n_world, 2) m/s achieved over the last step.
        bumps: (B, n_world, N_BUMP_SECTORS) bool contact flags of the last step.
        num_cycles: (B,) control steps since each copy's reset.
    """

    positions: np.ndarray
    headings: np.ndarray
    velocities: np.ndarray
    bumps: np.ndarray
    num_cycles: np.ndarray


class Task:
    """Base class of the swarm tasks (subclasses: aggregation, flocking, centroid seeking).

    Args:
        config: resolved env settings (``swarm_envs.env.COMMON_DEFAULTS`` plus ``TASK_DEFAULTS``).
        platform: the robots' platform.
        n_copies: number of env copies stepped together.
    """

    #: extra keyword arguments of the task, with defaults
    TASK_DEFAULTS: dict[str, Any] = {}

    def __init__(self, config: dict[str, Any], platform: Platform, n_copies: int = 1) -> None:
        self.config = config
        self.platform = platform
        self.n_copies = int(n_copies)
        self.n_static = self._n_static()
        self.n_agents = int(config["n_robots"])
        self.n_world = self.n_static + self.n_agents
        self.max_cycles = int(config["max_cycles"])
        self.reward_mode = config["reward_mode"]
        size = config["arena_size"] if config["arena_size"] is not None else self.default_arena_size()
        self.arena = Arena(config["arena"], float(size))
        self.agent_robots = np.arange(self.n_static, self.n_world)
        # robots that cannot fit even touching fail here; the random spawner also keeps a gap of 0.1
        # radius, so an arena within ~10 % of a full packing can still fail at reset (without positions)
        check_capacity(self.n_world, platform.radius, self.arena, gap=0.0)
        self._check_layout()

    # -- hooks -----------------------------------------------------------------------------------
    def _n_static(self) -> int:
        """Number of non-agent (static) robots; they sense and emit but are never commanded."""
        return 0

    def _check_layout(self) -> None:
        """Raise ``ValueError`` when the task's initial layout cannot fit (e.g. too many anchors)."""

    def default_arena_size(self) -> float:
        """Arena size (m) when ``arena_size=None``: the platform's spacing times sqrt(robots)."""
        n_world = self.n_static + int(self.config["n_robots"])
        return SPACING.get(self.platform.name, 4 * self.platform.diameter) * float(np.sqrt(n_world))

    def spawn(self, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """One copy's initial (positions (n_world, 2) m, headings (n_world,) rad)."""
        positions = spawn_positions(rng, self.n_world, self.platform.radius, self.arena)
        return positions, rng.uniform(-np.pi, np.pi, self.n_world)

    def rewards(self, state: BatchState, first: np.ndarray) -> tuple[np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]:
        """(rewards (B, n_agents), reward terms {name: (B, n_agents)}, metrics {name: (B,)}).

        ``first`` (B,) marks copies whose episode starts with this state (their reset).
        """
        raise NotImplementedError

    def markers(self, positions: np.ndarray) -> dict[str, np.ndarray]:
        """Task markers of one copy (name -> world point (2,) m) from its positions (n_world, 2)."""
        return {}

    # -- helpers ---------------------------------------------------------------------------------
    def agents_of(self, array: np.ndarray) -> np.ndarray:
        """The agent rows of a (B, n_world, ...) array."""
        return array[:, self.n_static :]


def bump_any(bumps: np.ndarray) -> np.ndarray:
    """True per robot in contact with anything this step; ``bumps`` (..., N_BUMP_SECTORS)."""
    return bumps.reshape(*bumps.shape[:-1], N_BUMP_SECTORS).any(axis=-1)
