"""A task of your own: dispersion -- spread out while staying connected. Importing this module registers
``swarm_examples/Dispersion-v0``; then every tool of the suite takes the id::

    import examples.custom_task, swarm_envs            # from the repository root
    env = swarm_envs.make("swarm_examples/Dispersion-v0", n_robots=10)      # PettingZoo ParallelEnv
    vec = swarm_envs.make_vec("swarm_examples/Dispersion-v0", 64)           # 64 copies, one batched core
    python train.py --config examples/custom_task.yaml                      # PPO vs random

Observations come from the sensing stack as for every task; the task only spawns (the default: uniform),
rewards and measures, from ground truth, over all env copies at once (``(B, N)`` arrays).
"""

import numpy as np

import swarm_envs
from swarm_envs.tasks.task import Real, Task, largest_component_fraction, nearest_distances


class Dispersion(Task):
    """Team reward: mean nearest-neighbour distance / link range (capped at 1) x connected fraction."""

    SETTINGS = {
        "arena_size": 1.5,  # another default for a common setting (m)
        "link_range": Real(0.4, "robots closer than this are connected", low=0.0, low_open=True, high=10.0, unit="m"),
    }
    METRICS = {"mean_spacing": "final", "connected_fraction": "final"}  # how evaluators reduce an episode
    HEADLINE = ("mean_spacing", +1)  # higher is better

    def rewards(self, state, first):
        positions = self.agents_of(state.positions)  # (B, N, 2) m of the B copies
        link = self.config["link_range"]
        spacing = np.minimum(nearest_distances(positions), link).mean(axis=1)  # (B,) m
        connected, _ = largest_component_fraction(positions, link)  # (B,) fraction in the largest group
        team = spacing / link * connected
        rewards = np.repeat(team[:, None], self.n_agents, axis=1)  # (B, N): every robot gets the team reward
        return rewards, {"dispersion": rewards}, {"mean_spacing": spacing, "connected_fraction": connected}


swarm_envs.register("swarm_examples/Dispersion-v0", Dispersion)
