"""swarm_envs: PettingZoo swarm-robotics environments with a physically modelled infrared sensing stack.

Importing the package registers the tasks in PettingZoo's registry::

    import pettingzoo, swarm_envs
    env = pettingzoo.make("parallel", "swarm_envs/Aggregation-v0", n_robots=10)
    env = swarm_envs.make("swarm_envs/Flocking-v0", platform="rone")   # same, parallel API

``swarm_envs.make`` passes every keyword to the env unchanged (``max_cycles=-1`` raises), whereas
``pettingzoo.make`` drops ``max_cycles=-1`` and uses the env's default.
"""

from __future__ import annotations

from typing import Any

from pettingzoo import ParallelEnv, register

from swarm_envs import aggregation_v0, centroid_seeking_v0, flocking_v0
from swarm_envs.platforms import PLATFORMS, Platform, get_platform
from swarm_envs.registry import ENV_IDS, list_envs


def _read_version() -> str:
    """The version in pyproject.toml: from the installed package's metadata, else (a source tree on the
    path without an install) from the pyproject.toml beside the package, else ``"0+unknown"``."""
    import re
    from importlib import metadata

    try:
        return metadata.version("swarm_envs")
    except metadata.PackageNotFoundError:
        from pathlib import Path

        pyproject = Path(__file__).resolve().parent.parent / "pyproject.toml"
        text = pyproject.read_text(encoding="utf-8") if pyproject.is_file() else ""
        found = re.search(r'^version\s*=\s*"([^"]+)"', text, re.M)
        return found.group(1) if found else "0+unknown"


__version__ = _read_version()
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

for _id, _module in ENV_IDS.items():
    register("parallel", _id, entry_point=f"{_module}:parallel_env")
    register("aec", _id, entry_point=f"{_module}:env")


def make(env_id: str, **kwargs: Any) -> ParallelEnv:
    """Create a parallel environment by registered id, e.g. ``make("swarm_envs/Aggregation-v0", n_robots=20)``."""
    if env_id not in ENV_IDS:
        raise ValueError(f"unknown environment id {env_id!r}; registered: {list_envs()}")
    import importlib

    # the registry's own entry point, called directly: pettingzoo.make treats max_cycles=-1 as "not
    # given" (its spec default), which would silently turn an invalid -1 into 500-step episodes
    return importlib.import_module(ENV_IDS[env_id]).parallel_env(**kwargs)


def make_vec(env_id: str, num_envs: int, **kwargs: Any):
    """``num_envs`` copies of a registered task stepped by one batched core (:mod:`swarm_envs.vector`)."""
    from swarm_envs.vector import make_vec as _make_vec

    return _make_vec(env_id, num_envs, **kwargs)
