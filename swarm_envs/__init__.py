"""swarm_envs: PettingZoo swarm-robotics environments with a physically modelled infrared sensing stack.

Importing the package registers the suite's tasks (in its registry and in PettingZoo's)::

    import pettingzoo, swarm_envs
    env = pettingzoo.make("parallel", "swarm_envs/Aggregation-v0", n_robots=10)
    env = swarm_envs.make("swarm_envs/Flocking-v0", platform="rone")        # same, parallel API
    vec = swarm_envs.make_vec("swarm_envs/Flocking-v0", 64)                 # 64 copies, one batched core

Your own task: subclass :class:`swarm_envs.Task` (``swarm_envs.tasks.task`` has its helpers) and ``swarm_envs.register("my_lab/MyTask-v0",
MyTask)`` (or ``"my_module:MyTask"``, imported when first made); every function here then accepts the id.

``swarm_envs.make`` passes every keyword to the env unchanged (``max_cycles=-1`` raises), whereas
``pettingzoo.make`` drops ``max_cycles=-1`` and uses the env's default.
"""

from __future__ import annotations

from typing import Any

import swarm_envs._moved  # noqa: F401  (old module paths: the task aliases, deprecated paths)
from swarm_envs.ir import models as _ir_models  # noqa: F401  (registers the IR models with swarm_envs.sim.platforms)
from swarm_envs.adapters.env import SwarmEnv
from swarm_envs.sim.platforms import PLATFORMS, Platform, get_platform
from swarm_envs.registry import ENV_IDS, EnvSpec, list_envs, make, make_vec, register, spec
from swarm_envs.tasks.task import BatchState, Task


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
    "make",
    "make_vec",
    "make_torchrl",
    "register",
    "spec",
    "list_envs",
    "EnvSpec",
    "ENV_IDS",
    "PLATFORMS",
    "Platform",
    "get_platform",
    "Task",
    "BatchState",
    "SwarmEnv",
]

register("swarm_envs/Aggregation-v0", "swarm_envs.tasks.aggregation_v0:AggregationEnv")
register("swarm_envs/Flocking-v0", "swarm_envs.tasks.flocking_v0:FlockingEnv")
register("swarm_envs/CentroidSeeking-v0", "swarm_envs.tasks.centroid_seeking_v0:CentroidSeekingEnv")
register("swarm_envs/SortedFollowing-v0", "swarm_envs.tasks.sorted_following_v0:SortedFollowingEnv")
register("swarm_envs/ParityClustering-v0", "swarm_envs.tasks.parity_clustering_v0:ParityClusteringEnv")
register("swarm_envs/MidAngleNavigation-v0", "swarm_envs.tasks.mid_angle_navigation_v0:MidAngleNavigationEnv")


def make_torchrl(env: str | type, num_envs: int, **kwargs: Any):
    """``num_envs`` copies of a registered id (or a ``Task`` class) as one batched TorchRL ``EnvBase``
    (:mod:`swarm_envs.adapters.torchrl_env`; needs the ``torchrl`` extra)."""
    from swarm_envs.adapters.torchrl_env import make_torchrl as _make_torchrl

    return _make_torchrl(env, num_envs, **kwargs)


def __getattr__(name: str) -> Any:
    # submodules on first use (``swarm_envs.tasks.flocking_v0``, ``swarm_envs.adapters.vector``)
    import importlib
    import importlib.util

    if not name.startswith("__") and importlib.util.find_spec(f"swarm_envs.{name}") is not None:
        return importlib.import_module(f"swarm_envs.{name}")
    raise AttributeError(f"module 'swarm_envs' has no attribute {name!r}")
