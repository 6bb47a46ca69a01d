"""Flocking: move together in one direction without collisions ([L] Sec. 6.4.1).

Reward (global, default) = polarisation x cohesion - collision_penalty x (fraction of robots bumping),
with polarisation = norm of the mean unit heading weighted by speed / max speed, cohesion = the mean over
robots of the share of the other robots within the platform's reliable message range
(:data:`swarm_envs.tasks.task.MESSAGE_RANGE`: e-puck 0.61 m, Droplet 0.43 m, r-one 1.0 m), the neighbourhood the
robots can keep in touch over: 1 only when every pair is that close, lower as the flock spreads or splits
(the largest chained component over that range would be 1 in the default arenas whatever the robots do). ``reward_mode="local"``: each robot's polarisation is computed over itself and those
neighbours and its own bump is penalised.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from swarm_envs.tasks.factories import task_module
from swarm_envs.tasks.task import BatchState, Task, bump_any, message_range, neighbourhood_sums, pairs_within, reward_weight

__all__ = ["FlockingTask", "FlockingEnv", "raw_env", "parallel_env", "env"]


class FlockingTask(Task):
    """Flocking rewards and metrics over all env copies; extra kwarg ``collision_penalty`` (default 0.1)."""

    SETTINGS = {
        "collision_penalty": reward_weight(0.1, "weight of the fraction of robots bumping", help="weight of the fraction of robots bumping, subtracted from the reward"),
    }
    METRICS = {"polarisation": "mean", "cohesion": "mean", "collision_fraction": "mean"}
    HEADLINE = ("polarisation", +1)
    SCRIPTED_POLICY = "swarm_envs.agents.scripted:OrientationFlocking"

    def __init__(self, config: dict[str, Any], platform, n_copies: int = 1) -> None:
        super().__init__(config, platform, n_copies)
        self.penalty = config["collision_penalty"]

    def rewards(self, state: BatchState, first: np.ndarray):
        B, A = self.n_copies, self.n_agents
        pos, head = self.agents_of(state.positions), self.agents_of(state.headings)
        speed = np.linalg.norm(self.agents_of(state.velocities), axis=2)  # (B, A)
        vmax = self.platform.max_speed
        link = message_range(self.platform)
        # message-range links of every copy, once, for cohesion and local polarisation (never across copies)
        pairs = pairs_within(pos, link)
        # cohesion: the mean share of the other robots within the message range (every pair counted twice)
        cohesion = 2.0 * np.bincount(pairs[:, 0] // A, minlength=B) / (A * (A - 1)) if A > 1 else np.ones(B)
        weight = np.clip(speed / vmax, 0.0, 1.0)
        vec = np.stack([np.cos(head), np.sin(head)], -1) * weight[..., None]  # (B, A, 2)
        pol = np.linalg.norm(vec.mean(axis=1), axis=1)  # (B,) [polarisation]
        bumped = bump_any(self.agents_of(state.bumps)).astype(float)  # (B, A)
        # local polarisation over each robot and its IR neighbours
        sums, counts = neighbourhood_sums(vec.reshape(B * A, 2), pairs)
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


_DOC = """Create the flocking environment (a native PettingZoo ``ParallelEnv``).

## Description

Flocking ([L] Sec. 6.4.1): ``n_robots`` robots should move together in one direction without collisions,
sensing each other only through infrared. Agents are named ``robot_0`` .. ``robot_{N-1}``.

## Rewards

``reward_mode="global"``: ``polarisation x cohesion - collision_penalty x (fraction of robots
bumping)``, with polarisation = norm of the mean unit heading weighted by speed / max speed (in
[0, 1]) and cohesion = the mean over robots of the share of the other robots whose centres are
within the platform's reliable message range (e-puck 0.61 m [T20 Sec. 7], Droplet 0.43 m, r-one
1.0 m). ``"local"``: each robot's polarisation is taken over itself and those neighbours and
only its own bump is penalised. Terms in ``infos[agent]["reward_terms"][name]``:
``polarisation``, ``local_polarisation``, ``cohesion``, ``collision``. Metrics in
``infos[agent]["metrics"][name]``: ``polarisation``, ``cohesion``, ``collision_fraction``.

## Version History

- v0: initial release (swarm_envs 0.1.0).
"""

raw_env, parallel_env, env = task_module(FlockingTask, _DOC)
FlockingEnv = raw_env
