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

from swarm_envs.env import SwarmEnv
from swarm_envs.metrics import largest_component_fraction
from swarm_envs.task import BatchState, Task, bump_any
from swarm_envs.sensing.ideal import neighbour_pairs

__all__ = ["FlockingTask", "FlockingEnv", "raw_env", "parallel_env", "env"]


class FlockingTask(Task):
    """Flocking rewards and metrics over all env copies; extra kwarg ``collision_penalty`` (default 0.1)."""

    TASK_DEFAULTS = {"collision_penalty": 0.1}

    def __init__(self, config: dict[str, Any], platform, n_copies: int = 1) -> None:
        super().__init__(config, platform, n_copies)
        penalty = config["collision_penalty"]
        if isinstance(penalty, bool) or not isinstance(penalty, (int, float)) or not np.isfinite(penalty) or penalty < 0:
            raise ValueError(f"collision_penalty must be a non-negative number, got {penalty!r}")
        self.penalty = float(penalty)

    def rewards(self, state: BatchState, first: np.ndarray):
        B, A = self.n_copies, self.n_agents
        pos, head = self.agents_of(state.positions), self.agents_of(state.headings)
        speed = np.linalg.norm(self.agents_of(state.velocities), axis=2)  # (B, A)
        vmax = self.platform.max_speed
        ir_range = self.platform.ir_range
        cohesion, _ = largest_component_fraction(pos, ir_range)
        weight = np.clip(speed / vmax, 0.0, 1.0)
        vec = np.stack([np.cos(head), np.sin(head)], -1) * weight[..., None]  # (B, A, 2)
        pol = np.linalg.norm(vec.mean(axis=1), axis=1)  # (B,) [polarisation]
        bumped = bump_any(self.agents_of(state.bumps)).astype(float)  # (B, A)
        # local polarisation over each robot and its IR neighbours (pairs never cross copies)
        copy = np.repeat(np.arange(B), A)
        rx, tx = neighbour_pairs(pos.reshape(B * A, 2), ir_range, copy)
        flat = vec.reshape(B * A, 2)
        sums = flat.copy()
        np.add.at(sums, rx, flat[tx])
        counts = 1 + np.bincount(rx, minlength=B * A)
        local_pol = np.linalg.norm(sums / counts[:, None], axis=1).reshape(B, A)
        global_reward = pol * cohesion - self.penalty * bumped.mean(axis=1)
        local_reward = local_pol * cohesion[:, None] - self.penalty * bumped
        rewards = np.repeat(global_reward[:, None], A, axis=1) if self.reward_mode == "global" else local_reward
        terms = {
            "polarisation": np.repeat(pol[:, None], A, axis=1),
            "local_polarisation": local_pol,
            "cohesion": np.repeat(cohesion[:, None], A, axis=1),
            "collision": bumped,
        }
        metrics = {"polarisation": pol, "cohesion": cohesion, "collision_fraction": bumped.mean(axis=1)}
        return rewards, terms, metrics

    def markers(self, positions: np.ndarray) -> dict[str, np.ndarray]:
        return {"centroid": positions[self.n_static :].mean(axis=0)}


class FlockingEnv(SwarmEnv):
    """Flocking task; extra kwarg ``collision_penalty`` (default 0.1)."""

    metadata = {**SwarmEnv.metadata, "name": "flocking_v0"}
    TASK = FlockingTask


raw_env = FlockingEnv


def parallel_env(**kwargs: Any) -> FlockingEnv:
    """The native parallel environment."""
    return FlockingEnv(**kwargs)


def env(**kwargs: Any):
    """The AEC (turn-based) view of the parallel environment (PettingZoo ``parallel_to_aec``)."""
    return parallel_to_aec(parallel_env(**kwargs))
