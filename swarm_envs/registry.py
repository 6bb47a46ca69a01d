"""The registered environment ids and their task modules (a leaf module: it imports no task at import time)."""

from __future__ import annotations

import importlib

__all__ = ["ENV_IDS", "list_envs", "env_class"]

#: Registered id -> task module.
ENV_IDS = {
    "swarm_envs/Aggregation-v0": "swarm_envs.aggregation_v0",
    "swarm_envs/Flocking-v0": "swarm_envs.flocking_v0",
    "swarm_envs/CentroidSeeking-v0": "swarm_envs.centroid_seeking_v0",
}


def list_envs() -> list[str]:
    """The registered environment ids."""
    return list(ENV_IDS)


def env_class(env_id: str) -> type:
    """The env class (``raw_env``) of a registered id; ``ValueError`` for an unknown id."""
    if env_id not in ENV_IDS:
        raise ValueError(f"unknown environment id {env_id!r}; registered: {list_envs()}")
    return importlib.import_module(ENV_IDS[env_id]).raw_env
