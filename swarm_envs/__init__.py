"""swarm_envs: PettingZoo swarm-robotics environments with a physically modelled infrared sensing stack.

Importing the package registers the tasks in PettingZoo's registry::

    import pettingzoo, swarm_envs
    env = pettingzoo.make("parallel", "swarm_envs/Aggregation-v0", n_robots=10)
    env = swarm_envs.make("swarm_envs/Flocking-v0", platform="rone")   # same, parallel API
"""

from __future__ import annotations

from typing import Any

from pettingzoo import ParallelEnv, register

from swarm_envs import aggregation_v0, centroid_seeking_v0, flocking_v0
from swarm_envs.platforms import PLATFORMS, Platform, get_platform

__version__ = "0.1.0"
__all__ = [
    "aggregation_v0",
    "flocking_v0",
    "centroid_seeking_v0",
    "make",
    "make_vec",
    "list_envs",
    "ENV_IDS",
    "PLATFORMS",
    "Platform",
    "get_platform",
]

#: Registered id -> task module.
ENV_IDS = {
    "swarm_envs/Aggregation-v0": "swarm_envs.aggregation_v0",
    "swarm_envs/Flocking-v0": "swarm_envs.flocking_v0",
    "swarm_envs/CentroidSeeking-v0": "swarm_envs.centroid_seeking_v0",
}

for _id, _module in ENV_IDS.items():
    register("parallel", _id, entry_point=f"{_module}:parallel_env")
    register("aec", _id, entry_point=f"{_module}:env")


def list_envs() -> list[str]:
    """The registered environment ids."""
    return list(ENV_IDS)


def make(env_id: str, **kwargs: Any) -> ParallelEnv:
    """Create a parallel environment by registered id, e.g. ``make("swarm_envs/Aggregation-v0", n_robots=20)``."""
    if env_id not in ENV_IDS:
        raise ValueError(f"unknown environment id {env_id!r}; registered: {list_envs()}")
    import pettingzoo

    return pettingzoo.make("parallel", env_id, **kwargs)


def make_vec(env_id: str, num_envs: int, **kwargs: Any):
    """``num_envs`` copies of a registered task stepped by one batched core (:mod:`swarm_envs.vector`)."""
    from swarm_envs.vector import make_vec as _make_vec

    return _make_vec(env_id, num_envs, **kwargs)
