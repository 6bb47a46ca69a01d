"""Flocking: move together in one direction without collisions (SPEC 6).

Reward (global, default) = polarisation x cohesion - collision_penalty x (fraction of robots bumping),
with polarisation = norm of the mean unit heading weighted by speed / max speed, cohesion = size of the
largest connected component of the IR graph (centres within the platform's IR range) / N.
``reward_mode="local"``: each robot's polarisation is computed over itself and its IR neighbours and
its own bump is penalised.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from pettingzoo.utils.conversions import parallel_to_aec

from swarm_envs.env import SwarmEnv, bump_any
from swarm_envs.metrics import components, polarisation
from swarm_envs.sensing.ideal import neighbour_pairs

__all__ = ["FlockingEnv", "raw_env", "parallel_env", "env"]


class FlockingEnv(SwarmEnv):
    """Flocking task; extra kwarg ``collision_penalty`` (default 0.1)."""

    metadata = {**SwarmEnv.metadata, "name": "flocking_v0"}
    TASK_DEFAULTS = {"collision_penalty": 0.1}

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        penalty = self.config["collision_penalty"]
        if isinstance(penalty, bool) or not isinstance(penalty, (int, float)) or penalty < 0:
            raise ValueError(f"collision_penalty must be a non-negative number, got {penalty!r}")

    def _rewards(self, first: bool):
        idx = self.agent_robots
        pos, head = self.world.positions[idx], self.world.headings[idx]
        speed = np.linalg.norm(self.world.velocities[idx], axis=1)
        vmax = self.platform.max_speed
        labels = components(pos, self.platform.ir_range)
        cohesion = float(np.bincount(labels).max() / self.n_agents)
        pol = polarisation(head, speed, vmax)
        bumped = bump_any(self.world.bumps[idx]).astype(float)
        penalty = self.config["collision_penalty"]
        # local polarisation over each robot and its IR neighbours (vectorised with bincount)
        weight = np.clip(speed / vmax, 0, 1)
        vec = np.stack([np.cos(head), np.sin(head)], -1) * weight[:, None]
        rx, tx = neighbour_pairs(pos, self.platform.ir_range)
        sums = vec.copy()
        np.add.at(sums, rx, vec[tx])
        counts = 1 + np.bincount(rx, minlength=self.n_agents)
        local_pol = np.linalg.norm(sums / counts[:, None], axis=1)
        global_reward = pol * cohesion - penalty * bumped.mean()
        local_reward = local_pol * cohesion - penalty * bumped
        rewards = np.full(self.n_agents, global_reward) if self.reward_mode == "global" else local_reward
        terms = {
            "polarisation": np.full(self.n_agents, pol),
            "local_polarisation": local_pol,
            "cohesion": np.full(self.n_agents, cohesion),
            "collision": bumped,
        }
        metrics = {"polarisation": pol, "cohesion": cohesion, "collision_fraction": float(bumped.mean())}
        return rewards, terms, metrics

    def _markers(self) -> dict[str, np.ndarray]:
        return {"centroid": self.world.positions[self.agent_robots].mean(axis=0)}


raw_env = FlockingEnv


def parallel_env(**kwargs: Any) -> FlockingEnv:
    """The native parallel environment."""
    return FlockingEnv(**kwargs)


def env(**kwargs: Any):
    """The AEC (turn-based) view of the parallel environment (PettingZoo ``parallel_to_aec``)."""
    return parallel_to_aec(parallel_env(**kwargs))
